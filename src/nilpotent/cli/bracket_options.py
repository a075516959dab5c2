"""Options shared by the bracket-motion commands (``simulate``, ``scaling``, ``sweep``).

Only the option declarations live here (whole numbers are read by
:func:`~nilpotent.cli.app.bounded_int`, within the CLI's limits); the library
validates the values
(:func:`nilpotent.numeric.signals.bracket_inputs`,
:func:`nilpotent.simulation.compare_bracket_motion`, ...), so that the
commands parse, call and print and never import one another.
"""

from __future__ import annotations

from typing import Annotated

import typer

from nilpotent.cli.app import MAX_PERIODS, bounded_float, bounded_int

__all__ = ["AmplitudeOpt", "BracketOpt", "OmegaOpt", "PeriodsOpt"]

BracketOpt = Annotated[
    str,
    typer.Option(
        "--bracket",
        metavar="I,J",
        help="The two fields whose bracket the loop realises (1-based, different).",
    ),
]
OmegaOpt = Annotated[
    float, typer.Option("--omega", metavar="W", help="Angular frequency ω of the loop (> 0).",
                        parser=bounded_float("--omega", 0.0, open_low=True))
]
AmplitudeOpt = Annotated[
    float, typer.Option("--amplitude", metavar="A", help="Loop amplitude A (> 0).",
                        parser=bounded_float("--amplitude", 0.0, open_low=True))
]
PeriodsOpt = Annotated[
    int,
    typer.Option("--periods", metavar="K",
                 help=f"Number of whole periods (1 to {MAX_PERIODS}).",
                 parser=bounded_int("--periods", 1, MAX_PERIODS)),
]
