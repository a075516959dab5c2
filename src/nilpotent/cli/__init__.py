"""The ``nilpotent`` command line: a thin typed shell over the library.

:func:`main` takes an argument list and returns the exit status, so tests and
notebooks can call it without a subprocess; :func:`run` is the console script.

Every way a run can end is decided here, so that each gives a clear answer:

- 0: done; 2: a user mistake (:class:`~nilpotent.errors.NilpotentError`) or a
  malformed command line (a missing/unknown option, a value of the wrong type);
  under ``--json`` either prints one ``{"error": {"kind", "message"}}`` object on
  stdout, nothing else;
- 130 / 143: interrupted by Ctrl-C / SIGTERM (``timeout``, ``kill``, CI), handled
  alike at any moment (:mod:`nilpotent.interrupts`: the signal is recorded, raised
  only at a safe point, never inside an import): partial outputs are removed on
  the way out, and the record decides even when a library swallowed or converted
  the exception;
- 70: an internal error (a bug): one line asking to report it, kind
  ``"internal"`` under ``--json``; the traceback only with ``--debug``.

``--debug`` and ``--quiet`` (no progress on stderr) are accepted anywhere on the
command line.
"""

from __future__ import annotations

import contextlib
import os
import sys
import traceback
from collections.abc import Sequence

import typer

from nilpotent import interrupts
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
from nilpotent.cli.app import (
    app,
    bounded_message,
    literal,
    report_error,
    reset_stdout,
    stdout_written,
)
from nilpotent.errors import NilpotentError
from nilpotent.interrupts import EXIT_INTERRUPTED, EXIT_TERMINATED

EXIT_USAGE = 2
EXIT_INTERNAL = 70

GLOBAL_FLAGS = ("--debug", "--quiet")
"""Flags read by :func:`main` wherever they stand (before a ``--``)."""

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


def _interrupted(as_json: bool) -> int:
    interrupts.close()  # reported from here on: a second signal is recorded, not raised
    code = interrupts.exit_code() or EXIT_INTERRUPTED
    why = "terminated (SIGTERM)" if code == EXIT_TERMINATED else "interrupted"
    # under --json stdout holds one object: the result, if it was printed before the signal
    report_error("interrupted", f"{why}; partial outputs were removed",
                 as_json and not stdout_written())
    return code


def _internal_error(exc: BaseException, as_json: bool, debug: bool) -> int:
    # no report address: the project publishes none (pyproject.toml has no [project.urls])
    from nilpotent.version import __version__

    what = f"{type(exc).__name__}: {literal(exc, 300)}"
    message = (
        f"internal error ({what}). This is a bug in nilpotent, not in your input: please "
        "report it to the project's maintainers with the command line, this message and "
        f"the versions (nilpotent {__version__}, Python {sys.version.split()[0]})"
        + ("" if debug else "; add --debug for the traceback")
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
    """Run the CLI on ``argv`` (default: ``sys.argv[1:]``) and return the exit status.

    SIGINT and SIGTERM are handled while it runs (:mod:`nilpotent.interrupts`; the
    handlers are put back afterwards when this call installed them, in the main
    thread only): an interrupt at any moment returns 130 / 143.
    """
    from nilpotent import progress

    owned = interrupts.install()
    args, flags = _split_flags(list(sys.argv[1:] if argv is None else argv))
    as_json = _wants_json(args)
    was_enabled = progress.enabled()
    try:
        return _run_command(args, flags, as_json)
    except KeyboardInterrupt:  # raised before (or after) the command's own handling
        return _interrupted(as_json)
    finally:
        interrupts.close()  # the command is over: a later signal is recorded, not raised
        progress.configure(enabled=was_enabled)
        if owned:
            interrupts.uninstall()


def _repeated_option(command: object, args: list[str]) -> str | None:
    """The first single-valued option of the subcommand ``args[0]`` that ``args`` gives
    more than once (``--to x=1 --to x=2``: click would keep the last silently), else None."""
    commands = getattr(command, "commands", {})
    sub = commands.get(args[0]) if args else None
    if sub is None:
        return None
    rest = args[1 : args.index("--")] if "--" in args else args[1:]
    for param in sub.params:
        # duck-typed: typer may carry its own copy of click's classes
        if getattr(param, "param_type_name", "") != "option" or param.multiple or getattr(
                param, "is_flag", False):
            continue
        names = param.opts + param.secondary_opts
        seen = sum(1 for a in rest for n in names if a == n or a.startswith(n + "="))
        if seen > 1:
            return names[0]
    return None


def _run_command(args: list[str], flags: set[str], as_json: bool) -> int:
    from nilpotent import progress

    debug = "--debug" in flags
    progress.configure(enabled="--quiet" not in flags)
    reset_stdout()
    if sys.stdout is None:  # started with stdout closed (>&-): no result could be shown
        report_error("output", "stdout is closed: nothing could be printed (run without "
                     "closing stdout, or redirect it to a file)", False)
        return EXIT_USAGE
    try:
        command = typer.main.get_command(app)
        twice = _repeated_option(command, args)
        if twice is not None:
            report_error("usage", f"option {twice} given twice: give it once (a second "
                         "value would silently replace the first)", as_json)
            return EXIT_USAGE
        result = command.main(args=args, prog_name="nilpotent", standalone_mode=False)
        code = int(result) if isinstance(result, int) else 0
        if interrupts.pending() is not None or code == EXIT_INTERRUPTED:
            # typer turns Ctrl-C into Exit(130); a signal whose exception a library
            # swallowed still ends the run here (the record is the source of truth)
            return _interrupted(as_json)
        if code == 0 and sys.stdout is not None:
            sys.stdout.flush()
        return code
    except BaseException as exc:
        if interrupts.pending() is not None:  # whatever the exception became on the way
            return _interrupted(as_json)  # (an ImportError of a C extension, an Abort)
        return _classify(exc, as_json, debug)


def _classify(exc: BaseException, as_json: bool, debug: bool) -> int:
    """The exit status (and report) of a command that ended with ``exc``."""
    if isinstance(exc, typer.Exit):
        if exc.exit_code == EXIT_INTERRUPTED:
            return _interrupted(as_json)
        return int(exc.exit_code)
    if isinstance(exc, typer.Abort | KeyboardInterrupt):
        return _interrupted(as_json)
    if isinstance(exc, typer.TyperException):  # usage errors of the option parser
        return _usage_error(exc, as_json)
    if isinstance(exc, NilpotentError):  # raised while parsing options (bounded integers)
        report_error(exc.kind, str(exc), as_json)
        return EXIT_USAGE
    if isinstance(exc, BrokenPipeError):
        _silence_stdout()  # the reader of stdout went away (| head): not an error to report
        return 1
    if isinstance(exc, RecursionError):
        report_error("option", "input too deeply nested", as_json)
        return EXIT_USAGE
    if isinstance(exc, Exception):
        return _internal_error(exc, as_json, debug)
    raise exc  # SystemExit, GeneratorExit: not a command's outcome


def finish(code: int) -> int:
    """Flush stdout after :func:`main` and return the final exit status (a result that
    cannot be printed is an error, not a success)."""
    if sys.stdout is not None:
        try:
            sys.stdout.flush()
        except OSError:
            _silence_stdout()
            report_error("output", "cannot print the result on stdout", False)
            code = code or EXIT_USAGE
    return code


def run() -> None:
    """Console-script entry point of a process (in-process callers use :func:`main`).

    :func:`nilpotent.entry.run`, the one ``pyproject.toml`` names, installs the
    signal handlers before importing this module; here they come after its imports.
    The handlers stay in place (recording only) until the process has exited.
    """
    try:
        interrupts.install()
        code = finish(main())
    except KeyboardInterrupt:
        code = interrupts.early_exit(sys.argv[1:])
    interrupts.exiting()  # a signal from here on is ignored: the status is decided
    sys.exit(code)
