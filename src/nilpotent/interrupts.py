"""Ctrl-C and SIGTERM at any moment: recorded at once, raised only where it is safe.

The command line (:mod:`nilpotent.entry`, then :func:`nilpotent.cli.main`) installs
:func:`install`'s handlers before anything heavy is imported.  A signal then

- is *recorded* first (the first one decides the exit status: 130 for SIGINT, 143
  for SIGTERM); the record, not the exception, is the source of truth;
- is raised as :class:`Interrupted` (a :class:`KeyboardInterrupt`, so every
  ``finally`` cleans up: partial outputs are removed by
  :func:`nilpotent.outputs.write_atomically`) only at a safe point: never while a
  module is being imported (a C extension's initialiser, heyoka's, scipy's,
  OMPL's, turns an exception into ``ImportError: initialization failed``, or
  aborts), never inside a :func:`deferred` block (two renames that must both
  happen), never while an earlier interrupt is being handled (a second SIGTERM
  during the clean-up is recorded, not raised);
- when it could not be raised at once, is raised again shortly after (every
  :data:`RETRY` seconds, from a helper thread, through
  :func:`_thread.interrupt_main`) until the program reaches a safe point, and at
  every :func:`checkpoint` (each progress update, before an output is moved
  into place).  A library that swallows the exception (a bare ``except:`` in
  compiled code) therefore only delays the stop.

Once the command line has reported the interruption, or finished, :func:`close`
turns the handlers into records only, and :func:`exiting` ignores the signals while
the interpreter shuts down (which would otherwise put back their default action:
a late SIGTERM would kill the process after its status was decided).  This module
imports only the standard library, so that it can be the first thing the entry point
loads.
"""

from __future__ import annotations

import _thread
import contextlib
import signal
import sys
import threading
import time
from collections.abc import Iterator
from types import FrameType

__all__ = [
    "EXIT_INTERRUPTED",
    "EXIT_TERMINATED",
    "RETRY",
    "Interrupted",
    "Terminated",
    "checkpoint",
    "close",
    "deferred",
    "exit_code",
    "exiting",
    "install",
    "installed",
    "pending",
    "uninstall",
]

EXIT_INTERRUPTED = 130
"""Exit status after Ctrl-C (SIGINT): 128 + 2."""

EXIT_TERMINATED = 143
"""Exit status after SIGTERM: 128 + 15."""

RETRY = 0.02
"""Seconds between two attempts to raise an interrupt that arrived at an unsafe moment."""

SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Interrupted(KeyboardInterrupt):
    """An interrupt (Ctrl-C), raised at a safe point; ``signum`` says which signal."""

    signum: int = signal.SIGINT


class Terminated(Interrupted):
    """SIGTERM, raised like Ctrl-C so that every ``finally`` cleans up."""

    signum: int = signal.SIGTERM


_state: dict[str, object] = {
    "pending": None,  # the first signal received (int) or None
    "closed": False,  # after the interruption was reported / the command ended: record only
    "critical": 0,  # depth of deferred() blocks
    "retrying": False,  # a retry thread is running
}
_previous: dict[int, object] = {}
_main_thread = threading.main_thread()


def pending() -> int | None:
    """The signal received since :func:`install` (the first one), or ``None``."""
    value = _state["pending"]
    return value if isinstance(value, int) else None


def exit_code() -> int | None:
    """The exit status the received signal calls for (130 or 143), or ``None``."""
    signum = pending()
    if signum is None:
        return None
    return EXIT_TERMINATED if signum == signal.SIGTERM else EXIT_INTERRUPTED


def installed() -> bool:
    """Whether :func:`install`'s handlers are in place."""
    return bool(_previous)


def install() -> bool:
    """Install the handlers of SIGINT and SIGTERM (main thread only).

    A signal ignored when the process started (``nohup``, a background job) stays
    ignored.  Signals blocked by the launcher are unblocked once the handlers are
    in place, so that a launcher may start ``nilpotent`` with them blocked to leave
    no moment at all to the default action (the interpreter's own start-up).

    Returns
    -------
    bool
        True if this call installed them (the caller then calls :func:`uninstall`);
        False if they already were, or this is not the main thread.
    """
    if _previous or threading.current_thread() is not _main_thread:
        return False
    _state.update(pending=None, closed=False, critical=0)
    for signum in SIGNALS:
        try:
            current = signal.getsignal(signum)
            if current == signal.SIG_IGN:
                continue
            _previous[signum] = signal.signal(signum, _handler)
        except (ValueError, OSError):  # pragma: no cover - not the main interpreter
            continue
    if sys.unraisablehook is not _quiet_unraisable:
        _state["unraisablehook"] = sys.unraisablehook
        sys.unraisablehook = _quiet_unraisable
    with contextlib.suppress(AttributeError, ValueError, OSError):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, SIGNALS)
    return bool(_previous)


def _quiet_unraisable(unraisable: object) -> None:
    """``sys.unraisablehook`` while the handlers are installed: an :class:`Interrupted`
    raised where Python cannot propagate it (a weakref callback, ``__del__``, run by the
    garbage collector at any moment) is dropped without a traceback on stderr: the
    record stays and the retry thread delivers it again at the next safe point.  Every
    other unraisable exception goes to the hook that was there before."""
    if isinstance(getattr(unraisable, "exc_value", None), Interrupted):
        return
    previous = _state.get("unraisablehook") or sys.__unraisablehook__
    previous(unraisable)  # type: ignore[operator]  # pyright: ignore[reportCallIssue]


def uninstall() -> None:
    """Put back the handlers found by :func:`install` and forget any record."""
    for signum, previous in list(_previous.items()):
        with contextlib.suppress(ValueError, OSError, TypeError):
            signal.signal(signum, previous)  # type: ignore[arg-type]
        del _previous[signum]
    if sys.unraisablehook is _quiet_unraisable:
        hook = _state.get("unraisablehook") or sys.__unraisablehook__
        sys.unraisablehook = hook  # type: ignore[assignment]  # pyright: ignore
    _state.update(pending=None, closed=True, critical=0)


def close() -> None:
    """From now on only record signals (the interruption was reported, or the work is
    over): nothing is raised while the program reports, flushes and exits."""
    _state["closed"] = True


def exiting() -> None:
    """Ignore SIGINT and SIGTERM from here to the end of the process (call it right
    before ``sys.exit``).

    While the interpreter shuts down it puts back the default action of every
    signal that has a Python handler, so a late SIGTERM would kill the process
    (status -15) after its status was decided; an ignored signal stays ignored.
    """
    _state["closed"] = True
    for signum in list(_previous):
        with contextlib.suppress(ValueError, OSError):
            signal.signal(signum, signal.SIG_IGN)


def _handling_interrupt() -> bool:
    """Whether the code that was running is handling an interrupt (an ``except`` or a
    ``finally`` with a :class:`KeyboardInterrupt` in its exception's chain)."""
    exc: BaseException | None = sys.exc_info()[1]
    seen = 0
    while exc is not None and seen < 50:
        if isinstance(exc, KeyboardInterrupt):
            return True
        exc = exc.__cause__ or exc.__context__
        seen += 1
    return False


def _in_import(frame: FrameType | None) -> bool:
    """Whether ``frame`` runs inside an import (a module's body or a C extension's
    initialiser): some frame of its chain is importlib's bootstrap."""
    depth = 0
    while frame is not None and depth < 100_000:
        name = frame.f_code.co_filename
        if name.startswith("<frozen importlib") or (
                "importlib" in name and "_bootstrap" in name):
            return True
        frame = frame.f_back
        depth += 1
    return False


def _safe(frame: FrameType | None) -> bool:
    return not _state["closed"] and not _state["critical"] and not _in_import(frame) and (
        not _handling_interrupt())


def _raise(signum: int) -> None:
    raise Terminated() if signum == signal.SIGTERM else Interrupted()


def _handler(signum: int, frame: FrameType | None) -> None:
    if _state["pending"] is None:
        _state["pending"] = int(signum)
    if _state["closed"]:
        return
    first = pending()
    assert first is not None
    _retry_later()  # also after raising: a library may swallow the exception
    if _safe(frame):
        _raise(first)


def _retry_later() -> None:
    """Deliver the recorded interrupt again every :data:`RETRY` seconds until the
    command line has handled it (:func:`close`): raised once the import or the
    :func:`deferred` block is over, or again if it was swallowed."""
    if _state["retrying"]:
        return
    _state["retrying"] = True
    ident = _main_thread.ident

    def retry() -> None:
        try:
            while True:
                time.sleep(RETRY)
                signum = pending()
                if signum is None or _state["closed"] or not _previous or ident is None:
                    return
                frame = sys._current_frames().get(ident)
                if frame is None:
                    return
                if _state["critical"] or _in_import(frame):
                    continue  # wait for the import (or block) to end: no handler call
                # a simulated signal (no real one: no EINTR in a library's system calls)
                _thread.interrupt_main(signal.Signals(signum))
        finally:
            _state["retrying"] = False

    try:
        threading.Thread(target=retry, name="nilpotent-interrupt", daemon=True).start()
    except RuntimeError:  # pragma: no cover - interpreter shutting down
        _state["retrying"] = False


def checkpoint() -> None:
    """Raise the recorded interrupt here if there is one and this is a safe point.

    Called at every progress update and before an output is moved into place; a
    no-op (one look-up) when no signal came, in another thread than the main one,
    and when the handlers are not installed (library use).

    Raises
    ------
    Interrupted
        A signal was received (:class:`Terminated` for SIGTERM).
    """
    signum = _state["pending"]
    if signum is None or not _previous or threading.current_thread() is not _main_thread:
        return
    if _safe(sys._getframe(1)):
        assert isinstance(signum, int)
        _raise(signum)


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """A block that an interrupt never cuts in two (it is raised at the block's end).

    For a few steps that must all happen or none (replacing a folder by two renames).
    """
    _state["critical"] = int(_state["critical"]) + 1  # type: ignore[call-overload]
    try:
        yield
    finally:
        _state["critical"] = int(_state["critical"]) - 1  # type: ignore[call-overload]
    checkpoint()


def early_exit(argv: list[str]) -> int:
    """Report an interrupt that came before the command line could (its import) and
    return the exit status: one JSON object on stdout under ``--json``, else a line on
    stderr; never raises."""
    close()
    code = exit_code() or EXIT_INTERRUPTED
    why = "terminated (SIGTERM)" if code == EXIT_TERMINATED else "interrupted"
    message = f"{why}; partial outputs were removed"
    as_json = False
    app = sys.modules.get("nilpotent.cli.app")
    if app is not None and getattr(app, "stdout_written", lambda: False)():
        argv = ["--"]  # the result is on stdout already: say it on stderr only
    for arg in argv:
        if arg == "--":
            break
        if arg == "--json":
            as_json = True
            break
    try:
        if as_json:
            import json

            sys.stdout.write(json.dumps({"error": {"kind": "interrupted", "message": message}},
                                        indent=2) + "\n")
            sys.stdout.flush()
        else:
            sys.stderr.write(f"nilpotent: error: {message}\n")
            sys.stderr.flush()
    except (OSError, ValueError, AttributeError):
        pass
    return code

