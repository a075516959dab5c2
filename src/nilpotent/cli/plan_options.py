"""Options and set-up shared by ``nilpotent plan`` and ``nilpotent execute``.

Commands do not import one another: what both need lives here.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from nilpotent.cli.app import MAX_SEED, bounded_float, bounded_int
from nilpotent.errors import OptionError

if TYPE_CHECKING:
    from nilpotent.planning.ocp import OcpRefine

MIN_MAX_PIECE = 1e-3
"""Shortest ``--max-piece``: the global path is cut into ``length / D`` pieces, each
steered on its own (a D of 1e-9 asked for billions of pieces, 4 GB before any work)."""

FromOpt = Annotated[
    str | None,
    typer.Option("--from", metavar="P", help="Start NAME=VALUE,... (default: the origin)."),
]

ToOpt = Annotated[
    str,
    typer.Option("--to", metavar="Q", help="Goal NAME=VALUE,...; unnamed coordinates are 0."),
]

WorldOpt = Annotated[
    Path | None,
    typer.Option("--world", metavar="W",
                 help="World file (workspace bounds and obstacles), or a built-in world's "
                      "name: room, parking, corner."),
]

LimitOpt = Annotated[
    list[str] | None,
    typer.Option("--limit", metavar="NAME=LO:HI",
                 help="Limit a coordinate to [LO, HI] (repeatable; adds to or tightens the "
                      "model's limits)."),
]

MarginOpt = Annotated[
    float,
    typer.Option("--singular-margin", metavar="M",
                 help="Keep the model's singular margin >= M (trident-snake-joints: |det M|).",
                 parser=bounded_float("--singular-margin", 0.0)),
]

TimeLimitOpt = Annotated[
    float,
    typer.Option("--time-limit", metavar="S",
                 help="Give up (exit 2, kind computation-limit, nothing written) when no "
                      "plan is found within S seconds, counted from the start of the command.",
                 parser=bounded_float("--time-limit", 0.0, open_low=True)),
]

ClearanceOpt = Annotated[
    float,
    typer.Option("--clearance", metavar="D",
                 help="Keep the robot more than D (model length units) from every obstacle.",
                 parser=bounded_float("--clearance", 0.0)),
]

PlannerOpt = Annotated[
    str,
    typer.Option("--planner", metavar="NAME",
                 help="Holonomic stage: auto (default: reeds-shepp for car-like models, "
                      "trident-ocp for trident-snake when CasADi is installed, else "
                      "rrtconnect), rrtconnect (OMPL RRTConnect, shortest Euclidean path), "
                      "rrtstar (OMPL RRT* under the sub-Riemannian ball-box cost, "
                      "anytime), reeds-shepp (car-like models, and car-trailers:1 through "
                      "its trailer: an OMPL Reeds-Shepp path lifted to the model's "
                      "configurations; car-trailers:2: a lattice search over exact "
                      "motions) or trident-ocp (trident-snake: RRTConnect's path, "
                      "each piece driven by optimal control of the body path; needs the "
                      "ocp extra)."),
]

SeedOpt = Annotated[
    int,
    typer.Option("--seed", metavar="N", help=f"Seed of the global planner (0 to {MAX_SEED}).",
                 parser=bounded_int("--seed", 0, MAX_SEED, above=OptionError)),
]

MaxPieceOpt = Annotated[
    float,
    typer.Option("--max-piece", metavar="D",
                 help="Longest piece of the global path steered at once (configuration space; "
                      f"at least {MIN_MAX_PIECE:g}; the trident-ocp planner's pieces are up "
                      "to max(D, 3) long).",
                 parser=bounded_float("--max-piece", 0.0, open_low=True, floor=MIN_MAX_PIECE,
                                      what=" (each piece is steered on its own: shorter "
                                           "pieces cost unbounded time and memory)")),
]


MaxSpeedOpt = Annotated[
    str | None,
    typer.Option("--max-speed", metavar="V",
                 help="Re-time the plan (TOPP-RA) with |u_i| <= V for every input, or per "
                      "input u1=V1,u2=V2 (inputs left out: no speed bound); needs --max-accel."),
]

MaxAccelOpt = Annotated[
    str | None,
    typer.Option("--max-accel", metavar="A",
                 help="Re-time the plan (TOPP-RA) with |du_i/dt| <= A for every input, or "
                      "u1=A1,u2=A2 naming every input; adds \"trajectory\" to --json."),
]

TrajectoryOutOpt = Annotated[
    Path | None,
    typer.Option("--trajectory-out", metavar="FILE",
                 help="Write the re-timed trajectory as CSV (t, coordinates, inputs); needs "
                      "--max-accel."),
]

TrajectoryStepOpt = Annotated[
    float | None,
    typer.Option("--trajectory-step", metavar="DT",
                 help="Largest time between trajectory samples (default: duration / 500).",
                 parser=bounded_float("--trajectory-step", 0.0, open_low=True)),
]


MIN_WEIGHT, MAX_WEIGHT = 1e-6, 1e6
"""Range of ``--input-weights`` (:data:`nilpotent.planning.ocp.MIN_WEIGHT`, ``MAX_WEIGHT``)."""

MAX_REFINE_STARTS = 32
"""Most ``--refine-starts`` (:data:`nilpotent.planning.ocp.MAX_STARTS`, not imported here:
the command line starts without CasADi)."""

InputWeightsOpt = Annotated[
    str | None,
    typer.Option("--input-weights", metavar="W",
                 help="With --refine ocp: weight the inputs in the refinement's metric, "
                      "energy = integral of sum (w_i u_i)^2; u1=W1,u2=W2 (inputs left out: 1), "
                      "e.g. u2=1/10 makes steering cheap."),
]

RefineStartsOpt = Annotated[
    int | None,
    typer.Option("--refine-starts", metavar="N",
                 help="With --refine ocp: IPOPT starts (the plan, the straight line of "
                      "states, then perturbations seeded by --seed); the cheapest verified "
                      "one is kept (default 1).",
                 parser=bounded_int("--refine-starts", 1, MAX_REFINE_STARTS,
                                    what=" (each start is one IPOPT solve)", above=OptionError)),
]

ReversalCostOpt = Annotated[
    float | None,
    typer.Option("--reversal-cost", metavar="C",
                 help="With --refine ocp, vehicle models: add C per reversal of the drive "
                      "input to the cost by which refined candidates are chosen (default 0).",
                 parser=bounded_float("--reversal-cost", 0.0)),
]


RefineSmoothOpt = Annotated[
    bool,
    typer.Option("--refine-smooth",
                 help="With --refine ocp: each input a cosine series (one segment, inputs "
                      "continuous: a re-timed trajectory rests only at the ends and at "
                      "reversals) instead of 48 constant pieces."),
]


def parse_weights_option(text: str, system) -> tuple[float, ...]:
    """``--input-weights``: ``W`` (every input) or ``u1=W1,u2=W2`` (inputs left out: 1);
    values are expressions (``1/10``), each positive and finite.

    Raises
    ------
    OptionError
        Malformed text, an unknown or repeated input, a weight not positive and finite.
    """
    from nilpotent.core.model.expressions import parse_expression, real_value
    from nilpotent.planning.timing import input_names

    names = input_names(system.m)

    def number(piece: str) -> float:
        if not piece.strip():
            raise OptionError(f"--input-weights {text[:60]!r}: a weight is missing")
        value = float(real_value(parse_expression(piece, {}, where="--input-weights"),
                                 where="--input-weights"))
        if not (math.isfinite(value) and value > 0):
            raise OptionError(f"--input-weights: a weight must be a positive number, got "
                              f"{value:g}")
        if not MIN_WEIGHT <= value <= MAX_WEIGHT:
            raise OptionError(f"--input-weights: a weight must be from {MIN_WEIGHT:g} to "
                              f"{MAX_WEIGHT:g} (only their ratios matter), got {value:g}")
        return value

    if "=" not in text:
        return (number(text),) * system.m
    named: dict[str, float] = {}
    for part in text.split(","):
        name, eq, value = part.partition("=")
        name = name.strip()
        if not (eq and name):
            raise OptionError(f"--input-weights {text!r}: expected W or u1=W1,u2=W2")
        if name not in names:
            raise OptionError(f"--input-weights: unknown input {name[:40]!r} (inputs: "
                              f"{', '.join(names)})")
        if name in named:
            raise OptionError(f"--input-weights: {name} given twice")
        named[name] = number(value)
    return tuple(named.get(k, 1.0) for k in names)


def refine_from_options(refine: str, system, seed: int, input_weights: str | None,
                        refine_starts: int | None, reversal_cost: float | None,
                        smooth: bool = False):
    """``--refine`` with ``--input-weights``, ``--refine-starts``, ``--reversal-cost``,
    ``--refine-smooth``: the refinement's name, or its
    :class:`~nilpotent.planning.ocp.OcpRefine` options.

    Raises
    ------
    OptionError
        One of the three without ``--refine ocp``; a value out of range; a reversal cost
        for a model without a drive input.
    """
    from nilpotent.planning.ocp import MAX_STARTS, OcpRefine
    from nilpotent.planning.timing import drive_reversals

    given = [name for name, v in (("--input-weights", input_weights),
                                  ("--refine-starts", refine_starts),
                                  ("--reversal-cost", reversal_cost),
                                  ("--refine-smooth", True if smooth else None))
             if v is not None]
    if not given:
        return refine
    if refine != "ocp":
        raise OptionError(f"{given[0]} needs --refine ocp (it sets how the optimal-control "
                          "refinement runs)")
    if refine_starts is not None and not 1 <= refine_starts <= MAX_STARTS:
        raise OptionError(f"--refine-starts must be an integer from 1 to {MAX_STARTS}; got "
                          f"{refine_starts}")
    if reversal_cost is not None and drive_reversals(system, ()) is None:
        raise OptionError(f"--reversal-cost: model {system.name} has no drive input (only "
                          "the built-in vehicle models unicycle, car, car-trailers:K, or a "
                          "model file with their fields, have one)")
    weights = None if input_weights is None else parse_weights_option(input_weights, system)
    return OcpRefine(input_weights=weights, starts=refine_starts or 1,
                     reversal_cost=reversal_cost or 0.0, seed=seed, smooth=smooth)


def parse_bound_option(text: str | None, system, option: str, *, every: bool = False
                       ) -> tuple[float, ...] | None:
    """``--max-speed``/``--max-accel``: ``V`` (every input) or ``u1=V1,u2=V2``; values are
    expressions (``pi/2``), checked by :func:`nilpotent.planning.timing.bound_values`."""
    from nilpotent.core.model.expressions import parse_expression, real_value
    from nilpotent.core.model.points import check_magnitude
    from nilpotent.planning.timing import bound_values

    if text is None:
        return None

    def number(piece: str) -> float:
        where = option
        if not piece.strip():
            raise OptionError(f"{option} {text!r}: a bound is missing")
        return check_magnitude(real_value(parse_expression(piece, {}, where=where), where=where),
                               where)

    if "=" not in text:
        return bound_values(system.m, number(text), option, every=every)
    named: dict[str, float] = {}
    for part in text.split(","):
        name, eq, value = part.partition("=")
        name = name.strip()
        if not (eq and name):
            raise OptionError(f"{option} {text!r}: expected V or u1=V1,u2=V2")
        if name in named:
            raise OptionError(f"{option}: {name} given twice")
        named[name] = number(value)
    return bound_values(system.m, named, option, every=every)


def parse_limit_options(texts: list[str] | None, system) -> dict[str, tuple[float, float]]:
    """``--limit NAME=LO:HI`` (repeatable) → ``{name: (lo, hi)}``; LO, HI are expressions."""
    from nilpotent.core.model.expressions import parse_expression, real_value
    from nilpotent.core.model.points import check_magnitude

    out: dict[str, tuple[float, float]] = {}
    for text in texts or []:
        name, eq, rng = text.partition("=")
        lo_text, colon, hi_text = rng.partition(":")
        name = name.strip()
        if not (eq and colon and name and lo_text.strip() and hi_text.strip()):
            raise OptionError(f"--limit {text!r}: expected NAME=LO:HI, e.g. phi1=-1.2:1.2")
        if name not in system.coordinate_names:
            raise OptionError(
                f"--limit {text!r}: {name!r} is not a coordinate of {system.name} "
                f"(coordinates: {', '.join(system.coordinate_names)})"
            )
        where = f"--limit {name}"
        lo, hi = (check_magnitude(real_value(parse_expression(t, {}, where=where), where=where),
                                  where)
                  for t in (lo_text, hi_text))
        if lo > hi:
            raise OptionError(f"--limit {text!r}: LO = {lo:g} is above HI = {hi:g}")
        if name in out:
            raise OptionError(f"--limit {name} given twice")
        out[name] = (lo, hi)
    return out


def command_budget(time_limit: float):
    """The time budget (:func:`nilpotent.planning.budget.time_budget`) of a command that
    takes ``--time-limit``: counted from the start of the process when the process is
    this command line (the console script or ``python -m nilpotent``: start-up is part of
    the wait), else (in-process calls) from now."""
    import sys

    from nilpotent.planning.budget import process_age, time_budget

    main_run = getattr(sys.modules.get("__main__"), "run", None)
    entry = getattr(main_run, "__module__", None) in ("nilpotent.entry", "nilpotent.cli")
    return time_budget(time_limit, already=process_age() if entry else 0.0)


def plan_from_options(system, start, goal, tol, world, limit, singular_margin, time_limit, seed,
                      max_piece, *, anchor="auto", max_iterations=30, clearance=0.0,
                      objective="reach", refine: str | OcpRefine = "none", max_speed=None,
                      max_accel=None,
                      trajectory_step=None, planner="rrtconnect"):
    """Load the world, merge the limits and run the global planner (shared with ``execute``)."""
    from nilpotent.planning.global_planner import plan_global
    from nilpotent.planning.world import load_world

    if not (math.isfinite(singular_margin) and singular_margin >= 0):
        raise OptionError(f"--singular-margin must be >= 0, got {singular_margin}")
    if not (math.isfinite(clearance) and clearance >= 0):
        raise OptionError(f"--clearance must be >= 0, got {clearance}")
    if clearance > 0 and world is None:
        raise OptionError("--clearance needs a --world (there is nothing to keep away from)")
    limits = system.limits.tightened(parse_limit_options(limit, system))
    the_world = load_world(world) if world is not None else None
    return plan_global(
        system, start, goal, tol, world=the_world, limits=limits,
        singular_margin=singular_margin, time_limit=time_limit, seed=seed,
        max_piece=max_piece, anchor=anchor, max_iterations=max_iterations, clearance=clearance,
        objective=objective, refine=refine, max_speed=max_speed, max_accel=max_accel,
        trajectory_step=trajectory_step, planner=planner,
    )
