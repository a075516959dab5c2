"""Progress of long work, reported on stderr.

One mechanism for every long computation of the library (exact rank decisions,
approximations, simulations, sweeps, the paper reproduction):

- on a terminal, a rich progress bar on stderr;
- on a pipe or a file (CI, ``2> log``), plain lines ``nilpotent: <what>: <done>/<total>``,
  at most one per :data:`PLAIN_INTERVAL` seconds, the first after :data:`PLAIN_INTERVAL`
  seconds (a quick task prints nothing), a line every :data:`HEARTBEAT` seconds of
  silence (``... (still running, 12 s)``) and a last one when a reported task ends;
- nothing at all until :func:`configure` enables it (the CLI does; a notebook or a
  script may), so that library calls stay silent by default.

Usage::

    from nilpotent.progress import progress

    with progress("brackets of length 4", total=len(words)) as bar:
        for word in words:
            ...
            bar.advance()

stdout is never written: ``--json`` output stays clean.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TextIO

from nilpotent import interrupts

PLAIN_INTERVAL = 1.0
"""Seconds between two plain progress lines of one task (rate limit off a terminal)."""

HEARTBEAT = 5.0
"""Seconds of silence after which a plain progress line says the task is still running
(so that a long step that reports nothing, an exact rank decision, still shows life)."""

_state = {"enabled": False}
_lock = threading.Lock()


def configure(*, enabled: bool) -> None:
    """Turn progress reports on or off for this process (the CLI turns them on)."""
    _state["enabled"] = bool(enabled)


def enabled() -> bool:
    """Whether progress reports are currently shown."""
    return _state["enabled"]


def _plain_text(text: str, limit: int = 200) -> str:
    """``text`` with control characters removed and its length bounded (user text is printed)."""
    clean = "".join(ch if ch.isprintable() else ascii(ch)[1:-1] for ch in text)
    if len(clean) > limit:
        clean = clean[:limit] + f"... ({len(clean) - limit} more characters)"
    return clean


@dataclass
class Progress:
    """A running task: call :meth:`advance` or :meth:`update` as work is done."""

    description: str
    total: int | None = None
    completed: int = 0
    detail: str = ""
    _stream: TextIO | None = None
    _last: float = field(default=0.0)
    _bar: object | None = None
    _task: object | None = None
    _start: float = field(default=0.0)
    _emitted: bool = False

    def advance(self, n: int = 1, detail: str | None = None) -> None:
        """Count ``n`` more units of work done (optionally with a short detail text)."""
        self.update(self.completed + n, detail)

    def update(self, completed: int | None = None, detail: str | None = None) -> None:
        """Set the number of units done and/or the detail text.

        Also a safe point for a recorded Ctrl-C / SIGTERM
        (:func:`nilpotent.interrupts.checkpoint`).

        Raises
        ------
        nilpotent.interrupts.Interrupted
            A signal was received and not yet raised (or its exception was swallowed).
        """
        interrupts.checkpoint()
        if completed is not None:
            self.completed = int(completed)
        if detail is not None:
            self.detail = _plain_text(detail, 80)
        if self._bar is not None:
            self._bar.update(  # type: ignore[attr-defined]
                self._task, completed=self.completed, description=self._label()
            )
        elif self._stream is not None:
            now = time.monotonic()
            if now - self._last >= PLAIN_INTERVAL:
                self._emit()
                self._last = now

    def _label(self) -> str:
        text = self.description + (f" ({self.detail})" if self.detail else "")
        return text

    def _emit(self, suffix: str = "") -> None:
        count = f"{self.completed}/{self.total}" if self.total else (
            f"{self.completed}" if self.completed else "")
        line = f"nilpotent: {self._label()}{': ' if count else ''}{count}{suffix}\n"
        with _lock:
            self._emitted = True
            try:
                if self._stream is None:
                    return
                self._stream.write(line)
                self._stream.flush()
            except (OSError, ValueError):
                self._stream = None  # stderr closed: stop reporting, never fail the work


@contextmanager
def progress(
    description: str, total: int | None = None, *, stream: TextIO | None = None
) -> Iterator[Progress]:
    """Report the progress of one task on stderr while the ``with`` block runs.

    Parameters
    ----------
    description : str
        What is being done, in a few words (printed literally: no markup is read).
    total : int or None
        Number of units of work, if known.
    stream : text stream or None
        Where to write (default ``sys.stderr``); for tests.

    Yields
    ------
    Progress
        Call ``advance()``/``update()`` on it. When reports are disabled
        (see :func:`configure`) the object is inert and costs nothing.
    """
    description = _plain_text(description)
    task = Progress(description, total)
    if not _state["enabled"]:
        yield task
        return
    out = stream if stream is not None else sys.stderr
    is_tty = False
    try:
        is_tty = out.isatty()
    except (AttributeError, ValueError, OSError):
        is_tty = False
    if is_tty:
        from rich.console import Console
        from rich.markup import escape
        from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn
        from rich.progress import Progress as RichProgress

        columns = [TextColumn("{task.description}"), BarColumn()]
        if total:
            columns.append(MofNCompleteColumn())
        columns.append(TimeElapsedColumn())
        with RichProgress(*columns, console=Console(file=out), transient=True) as bar:
            task._bar = bar
            task._task = bar.add_task(escape(description), total=total)
            task._label = lambda: escape(Progress._label(task))  # type: ignore[method-assign]
            yield task
        return
    task._stream = out
    task._last = time.monotonic()  # the first line comes after PLAIN_INTERVAL: a quick
    start = task._start = task._last  # task prints nothing at all
    stop = threading.Event()
    beat = threading.Thread(target=_heartbeat, args=(task, stop), daemon=True)
    beat.start()
    try:
        yield task
    finally:
        stop.set()
        beat.join()
        if task._emitted:
            task._emit(f" (done in {time.monotonic() - start:.1f} s)")


def _heartbeat(task: Progress, stop: threading.Event) -> None:
    """Say that ``task`` is still running after :data:`HEARTBEAT` seconds of silence."""
    while not stop.wait(min(HEARTBEAT, PLAIN_INTERVAL) / 2):
        now = time.monotonic()
        quiet_for = now - task._last
        if task._stream is None:
            return
        if task._emitted and quiet_for < HEARTBEAT:
            continue
        if not task._emitted and quiet_for < PLAIN_INTERVAL:
            continue
        task._emit(f" (still running, {now - task._start:.0f} s)")
        task._last = now
