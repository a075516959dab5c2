"""The ``nilpotent`` console script and ``python -m nilpotent``.

The first thing it does is :func:`nilpotent.interrupts.install`: this module and
the package's ``__init__`` import only the standard library, so Ctrl-C and
SIGTERM are handled (recorded, raised at a safe point, exit 130 / 143) from the
first moment the program runs, through the imports of typer, sympy, flint,
heyoka and the rest, to the last flush; then :func:`nilpotent.cli.main` runs
the command (it reports every way a run can end).
"""

from __future__ import annotations

import sys

from nilpotent import interrupts


def run() -> None:
    """Console-script entry point: install the signal handlers, then run the CLI.

    Exits with the command's status (see :func:`nilpotent.cli.main`).
    """
    argv = sys.argv[1:]
    try:
        interrupts.install()
        from nilpotent.cli import finish, main  # typer, sympy, ...: after the handlers

        code = finish(main(argv))
    except KeyboardInterrupt:  # before the command line could report it (its import)
        code = interrupts.early_exit(argv)
    interrupts.exiting()  # a signal from here on is ignored: the status is decided
    sys.exit(code)
