"""Progress of long work, reported on stderr.

One protocol for every long computation of the library (exact rank decisions,
approximations, simulations, sweeps, plans, the paper audit and reproduction): a
computation that reports how far it is sends :class:`ProgressEvent` values
``(stage, done, total, detail)`` to a :class:`ProgressCallback` (any callable taking
one event).  A library function that takes ``progress=`` calls it with events; the
bar on stderr, :class:`Progress`, is one such callback (``progress=bar``), and
:func:`report` sends an event to the innermost bar now shown (for code deep in a
long step that does not own it).

The bar:

- on a terminal, a rich progress bar on stderr;
- on a pipe or a file (CI, ``2> log``), plain lines ``nilpotent: <what>: <done>/<total>``,
  at most one per :data:`PLAIN_INTERVAL` seconds, the first after :data:`PLAIN_INTERVAL`
  seconds (a quick task prints nothing), a line every :data:`HEARTBEAT` seconds of
  silence (``... (still running, 12 s)``) and a last one when a reported task ends;
- where the total is known, the rate (units per second) and the estimated time left
  (on a terminal rich's :class:`~rich.progress.TimeRemainingColumn`; off a terminal
  ``(12.3/s, about 40 s left)`` on each line), the rate counted from the report that
  gave the total (a plan's pieces steered after a long search: not the search's
  seconds), and no estimate past the task's :attr:`Progress.deadline` (a time limit: then
  ``time limit in 25 s``);
- a task started while another runs (compiling the integrator during a sweep) is a
  second line of the same bar;
- nothing at all until :func:`configure` enables it (the CLI does; a notebook or a
  script may), so that library calls stay silent by default.

Usage::

    from nilpotent.progress import ProgressEvent, progress

    with progress("brackets of length 4", total=len(words)) as bar:
        for word in words:
            ...
            bar.advance()

    with progress("bracket motions") as bar:      # the bar as a callback
        result = sweep(system, (1, 2), progress=bar)

    def log(event: ProgressEvent) -> None:        # or any callable of one event
        print(event.stage, event.done, event.total, event.detail)

stdout is never written: ``--json`` output stays clean.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Protocol, TextIO

from nilpotent import interrupts

PLAIN_INTERVAL = 1.0
"""Seconds between two plain progress lines of one task (rate limit off a terminal)."""

HEARTBEAT = 5.0
"""Seconds of silence after which a plain progress line says the task is still running
(so that a long step that reports nothing, an exact rank decision, still shows life)."""

_state = {"enabled": False}
_lock = threading.Lock()
_live: list[object] = []
"""The rich progress display now shown (at most one; nested tasks join it)."""
_tasks: list[Progress] = []  # the tasks now reported, innermost last (see current())
"""The rich progress display now shown (at most one; nested tasks join it)."""

COMPILING = "compiling the integrator (first run of this model)"
"""The stage shown while an integrator is compiled (heyoka's LLVM, numba's kernels)."""


def configure(*, enabled: bool) -> None:
    """Turn progress reports on or off for this process (the CLI turns them on)."""
    _state["enabled"] = bool(enabled)


def enabled() -> bool:
    """Whether progress reports are currently shown."""
    return _state["enabled"]


@dataclass(frozen=True)
class ProgressEvent:
    """How far a long computation is: the one value every progress report carries.

    Parameters
    ----------
    stage : str
        The named stage now running, in a few words (``"bracket motions"``, a step of
        the reproduction such as ``"audit of the paper"``, ``"pieces steered"``).
    done : int
        Units of work done so far (``>= 0``).
    total : int or None
        Units of work in all, where known (it may become known later, or grow).
    detail : str
        A short extra text (empty: none).
    """

    stage: str
    done: int
    total: int | None = None
    detail: str = ""


class ProgressCallback(Protocol):
    """What ``progress=`` takes: called with one :class:`ProgressEvent` per report.

    :class:`Progress` (the bar on stderr) is one; so is any function of one event.
    """

    def __call__(self, event: ProgressEvent, /) -> None:
        """Take one report."""


def _plain_text(text: str, limit: int = 200) -> str:
    """``text`` with control characters removed and its length bounded (user text is printed)."""
    clean = "".join(ch if ch.isprintable() else ascii(ch)[1:-1] for ch in text)
    if len(clean) > limit:
        clean = clean[:limit] + f"... ({len(clean) - limit} more characters)"
    return clean


@dataclass
class Progress:
    """A running task shown on stderr: call :meth:`advance` or :meth:`update` as work is
    done, or pass it where a :class:`ProgressCallback` is taken (it is one)."""

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
    #: When the work stops at the latest (``time.monotonic()`` seconds: a time limit), or
    #: ``None``; no estimate of the time left goes past it.
    deadline: float | None = None
    _base_time: float = 0.0
    _base_done: int = 0
    _rebase: bool = False  # the rich bar's own rate to restart (the count begins)

    def __call__(self, event: ProgressEvent, /) -> None:
        """Show ``event``: its counts, and its detail, or its stage when that is not the
        task's own description (the steps of a reproduction)."""
        if event.total is not None:
            if self.total is None:
                # the count begins (pieces steered after a search): its own rate
                self._base_time, self._base_done = time.monotonic(), int(event.done)
                self._rebase = True
            self.total = int(event.total)
        detail = event.detail or (event.stage if event.stage != self.description else "")
        self.update(event.done, detail or None)

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
        if self._bar is not None and self._rebase:
            self._rebase = False
            self._bar.reset(  # type: ignore[attr-defined]
                self._task, completed=self.completed, description=self._label(),
                total=self.total, deadline=self.deadline,
            )
        elif self._bar is not None:
            self._bar.update(  # type: ignore[attr-defined]
                self._task, completed=self.completed, description=self._label(),
                total=self.total, deadline=self.deadline,
            )
        elif self._stream is not None:
            now = time.monotonic()
            if now - self._last >= PLAIN_INTERVAL:
                self._emit()
                self._last = now

    def _label(self) -> str:
        text = self.description + (f" ({self.detail})" if self.detail else "")
        return text

    def rate(self) -> float | None:
        """Units done per second since the count began (the task's start, or the first
        report of the stage now counted; ``None`` before a unit is done in it)."""
        begun = self._base_time or self._start
        elapsed = time.monotonic() - begun
        done = self.completed - self._base_done
        if done <= 0 or elapsed <= 0 or not begun:
            return None
        return done / elapsed

    def remaining(self) -> float | None:
        """Estimated seconds left, from the rate so far (``None`` without a total), at most
        the seconds to the :attr:`deadline`."""
        speed = self.rate()
        if not self.total or speed is None:
            return None
        return _capped(max(self.total - self.completed, 0) / speed, self.deadline)

    def _emit(self, suffix: str = "") -> None:
        count = f"{self.completed}/{self.total}" if self.total else (
            f"{self.completed}" if self.completed else "")
        if count and not suffix:
            speed, left = self.rate(), self.remaining()
            if speed is not None:
                count += f" ({_format_rate(speed)}"
                if left is not None and self.deadline is not None and \
                        left >= self.deadline - time.monotonic():
                    count += f", time limit in {_format_seconds(left)})"
                else:
                    count += f", about {_format_seconds(left)} left)" if left is not None \
                        else ")"
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


def _capped(seconds: float, deadline: float | None) -> float:
    """``seconds`` left, at most those to ``deadline`` (``time.monotonic()``; at least 0)."""
    if deadline is None:
        return seconds
    return max(0.0, min(seconds, deadline - time.monotonic()))


def _format_rate(speed: float) -> str:
    return f"{speed:,.0f}/s" if speed >= 10 else f"{speed:.2g}/s"


def _format_seconds(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def rich_columns(total: int | None) -> list[object]:
    """The columns of the terminal bar: what, bar, the count, the rate and the estimated
    time left (rich's :class:`~rich.progress.TimeRemainingColumn`), then the time elapsed.

    The count, rate and time left show only while the task's total is known (it may
    become known later: :func:`report`); ``total`` is the total at the start.
    """
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        ProgressColumn,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )
    from rich.text import Text

    class RateColumn(ProgressColumn):
        """Units per second (rich's TransferSpeedColumn counts bytes)."""

        def render(self, task):  # type: ignore[override]
            speed = task.finished_speed or task.speed
            return Text("" if speed is None or task.total is None else _format_rate(speed))

    class CountColumn(MofNCompleteColumn):
        def render(self, task):  # type: ignore[override]
            return Text("") if task.total is None else super().render(task)

    class RemainingColumn(TimeRemainingColumn):
        def render(self, task):  # type: ignore[override]
            if task.total is None:
                return Text("")
            deadline = task.fields.get("deadline")
            left = task.time_remaining
            if deadline is not None and left is not None and \
                    left >= deadline - time.monotonic():
                return Text(f"time limit in {_format_seconds(_capped(left, deadline))}")
            return super().render(task)

    del total  # every task gets the same columns (a nested task may know its total)
    return [TextColumn("{task.description}"), BarColumn(), CountColumn(), RateColumn(),
            RemainingColumn(), TimeElapsedColumn()]


def current() -> Progress | None:
    """The innermost task now reported (``None`` when none is, or reports are off)."""
    return _tasks[-1] if _tasks else None


def report(event: ProgressEvent) -> None:
    """Send ``event`` to the innermost running task (:meth:`Progress.__call__`): for code
    deep in a long step (pieces of a plan steered) that does not own the task; nothing
    when no task is reported."""
    task = current()
    if task is not None:
        task(event)


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
    _tasks.append(task)
    try:
        with _shown(task, out) as shown:
            yield shown
    finally:
        _tasks.remove(task)


@contextmanager
def _shown(task: Progress, out: TextIO) -> Iterator[Progress]:
    """Show ``task`` on ``out``: a rich bar on a terminal, plain lines otherwise."""
    description, total = task.description, task.total
    is_tty = False
    try:
        is_tty = out.isatty()
    except (AttributeError, ValueError, OSError):
        is_tty = False
    task._start = time.monotonic()
    if is_tty:
        from rich.console import Console
        from rich.markup import escape
        from rich.progress import Progress as RichProgress

        task._label = lambda: escape(Progress._label(task))  # type: ignore[method-assign]
        if _live:  # a task within a task: one more line of the bar shown
            bar = _live[-1]
            task._bar = bar
            task._task = bar.add_task(escape(description), total=total)  # type: ignore
            try:
                yield task
            finally:
                bar.remove_task(task._task)  # type: ignore[attr-defined]
            return
        with RichProgress(*rich_columns(total), console=Console(file=out),  # type: ignore
                          transient=True) as bar:
            task._bar = bar
            task._task = bar.add_task(escape(description), total=total)
            _live.append(bar)
            try:
                yield task
            finally:
                _live.remove(bar)
        return
    task._stream = out
    task._last = time.monotonic()  # the first line comes after PLAIN_INTERVAL: a quick
    start = task._start = task._last  # task prints nothing at all
    stop = threading.Event()
    beat = threading.Thread(target=_heartbeat, args=(task, stop), daemon=True)
    beat.start()
    finished = False
    try:
        yield task
        finished = True
    finally:
        stop.set()
        beat.join()
        if task._emitted:  # an exception (an error, an interrupt) is not "done"
            word = "done in" if finished else "stopped after"
            task._emit(f" ({word} {time.monotonic() - start:.1f} s)")


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
