"""The ``nilpotent`` command line: a thin typed shell over the library.

:func:`main` takes an argument list and returns the exit status, so tests and
notebooks can call it without a subprocess; :func:`run` is the console script.

Every way a run can end is decided here, so that each gives a clear answer:

- 0: done; 2: a user mistake (:class:`~nilpotent.errors.NilpotentError`) or a
  malformed command line (a missing/unknown option, a value of the wrong type);
  under ``--json`` either prints one ``{"error": {"kind", "message"}}`` object on
  stdout, nothing else;
- 130 / 143: interrupted by Ctrl-C / SIGTERM (``timeout``, ``kill``, CI), handled
  alike: partial outputs are removed on the way out;
- 70: an internal error (a bug): one line asking to report it, kind
  ``"internal"`` under ``--json``; the traceback only with ``--debug``.

``--debug`` and ``--quiet`` (no progress on stderr) are accepted anywhere on the
command line.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import traceback
from collections.abc import Sequence

import typer

from nilpotent.cli import (  # noqa: F401  (each module registers its command)
    cmd_analyze,
    cmd_approximate,
    cmd_execute,
    cmd_models,
    cmd_plan,
    cmd_reproduce,
    cmd_scaling,
    cmd_simulate,
    cmd_sweep,
)
from nilpotent.cli.app import app, bounded_message, literal, report_error
from nilpotent.errors import NilpotentError

EXIT_USAGE = 2
EXIT_INTERNAL = 70
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143

GLOBAL_FLAGS = ("--debug", "--quiet")
"""Flags read by :func:`main` wherever they stand (before a ``--``)."""

REPORT_URL = "https://github.com/nilpotent-robotics/nilpotent/issues"


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that every ``finally`` cleans up."""


def _split_flags(args: list[str]) -> tuple[list[str], set[str]]:
    flags: set[str] = set()
    rest: list[str] = []
    for k, arg in enumerate(args):
        if arg == "--":
            rest.extend(args[k:])
            break
        if arg in GLOBAL_FLAGS:
            flags.add(arg)
        else:
            rest.append(arg)
    return rest, flags


def _wants_json(args: list[str]) -> bool:
    for arg in args:
        if arg == "--":
            return False
        if arg == "--json":
            return True
    return False


_received: dict[str, bool] = {"term": False}


def _on_sigterm(signum, frame):  # pragma: no cover - exercised in a subprocess test
    _received["term"] = True
    raise Terminated()


@contextlib.contextmanager
def _sigterm_as_interrupt():
    """Handle SIGTERM like Ctrl-C while the command runs (main thread only)."""
    try:
        previous = signal.signal(signal.SIGTERM, _on_sigterm)
    except (ValueError, OSError):  # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _interrupted(as_json: bool) -> int:
    term = _received["term"]
    why = "terminated (SIGTERM)" if term else "interrupted"
    report_error("interrupted", f"{why}; partial outputs were removed", as_json)
    return EXIT_TERMINATED if term else EXIT_INTERRUPTED


def _internal_error(exc: BaseException, as_json: bool, debug: bool) -> int:
    what = f"{type(exc).__name__}: {literal(exc, 300)}"
    message = (
        f"internal error ({what}). This is a bug in nilpotent, not in your input: please "
        f"report it with the command line at {REPORT_URL}"
        + ("" if debug else " (add --debug for the traceback)")
    )
    if debug:
        with contextlib.suppress(OSError, ValueError, AttributeError):
            traceback.print_exception(exc, file=sys.stderr)
    report_error("internal", message, as_json)
    return EXIT_INTERNAL


def _usage_error(exc: typer.TyperException, as_json: bool) -> int:
    if as_json:
        report_error("usage", bounded_message(exc.format_message()), True)
    else:
        with contextlib.suppress(OSError, ValueError, AttributeError):
            show = getattr(exc, "show", None)
            if show is not None:
                show()
            else:
                sys.stderr.write(f"nilpotent: error: {literal(exc.format_message(), 2000)}\n")
    return EXIT_USAGE if exc.exit_code in (0, 1, 2) else int(exc.exit_code)


def _silence_stdout() -> None:
    """After stdout failed (closed pipe, full disk), keep the interpreter's final flush
    from failing again."""
    with contextlib.suppress(OSError, ValueError, AttributeError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI on ``argv`` (default: ``sys.argv[1:]``) and return the exit status."""
    from nilpotent import progress

    command = typer.main.get_command(app)
    args, flags = _split_flags(list(sys.argv[1:] if argv is None else argv))
    as_json = _wants_json(args)
    debug = "--debug" in flags
    was_enabled = progress.enabled()
    progress.configure(enabled="--quiet" not in flags)
    _received["term"] = False
    if sys.stdout is None:  # started with stdout closed (>&-): no result could be shown
        report_error("output", "stdout is closed: nothing could be printed (run without "
                     "closing stdout, or redirect it to a file)", False)
        progress.configure(enabled=was_enabled)
        return EXIT_USAGE
    try:
        with _sigterm_as_interrupt():
            result = command.main(args=args, prog_name="nilpotent", standalone_mode=False)
        code = int(result) if isinstance(result, int) else 0
        if code == EXIT_INTERRUPTED:  # typer turns Ctrl-C (and our SIGTERM) into Exit(130)
            return _interrupted(as_json)
        if code == 0 and sys.stdout is not None:
            sys.stdout.flush()
        return code
    except typer.Exit as exc:
        if exc.exit_code == EXIT_INTERRUPTED:
            return _interrupted(as_json)
        return int(exc.exit_code)
    except (typer.Abort, KeyboardInterrupt):
        return _interrupted(as_json)
    except typer.TyperException as exc:  # usage errors of the option parser
        return _usage_error(exc, as_json)
    except NilpotentError as exc:  # raised while parsing options (bounded integers, ...)
        report_error(exc.kind, str(exc), as_json)
        return EXIT_USAGE
    except BrokenPipeError:
        _silence_stdout()  # the reader of stdout went away (| head): not an error to report
        return 1
    except RecursionError:
        report_error("option", "input too deeply nested", as_json)
        return EXIT_USAGE
    except Exception as exc:
        return _internal_error(exc, as_json, debug)
    finally:
        progress.configure(enabled=was_enabled)


def run() -> None:
    """Console-script entry point."""
    code = main()
    if sys.stdout is not None:
        try:
            sys.stdout.flush()
        except OSError:
            _silence_stdout()
            report_error("output", "cannot print the result on stdout", False)
            code = code or EXIT_USAGE
    sys.exit(code)
