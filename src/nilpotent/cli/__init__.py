"""The ``nilpotent`` command line: a thin typed shell over the library.

:func:`main` takes an argument list and returns the exit status, so tests and
notebooks can call it without a subprocess; :func:`run` is the console script.
"""

from __future__ import annotations

import sys
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
from nilpotent.cli.app import app


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI on ``argv`` (default: ``sys.argv[1:]``) and return the exit status."""
    command = typer.main.get_command(app)
    args = list(sys.argv[1:] if argv is None else argv)
    try:
        result = command.main(args=args, prog_name="nilpotent", standalone_mode=False)
    except typer.Exit as exc:
        return int(exc.exit_code)
    except typer.Abort:
        sys.stderr.write("nilpotent: aborted\n")
        return 1
    except Exception as exc:  # usage errors of the vendored click: show them, exit 2
        show = getattr(exc, "show", None)
        code = getattr(exc, "exit_code", None)
        if show is None or code is None:
            raise
        show()
        return int(code)
    return int(result) if isinstance(result, int) else 0


def run() -> None:
    """Console-script entry point."""
    sys.exit(main())
