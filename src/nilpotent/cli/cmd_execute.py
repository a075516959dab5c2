"""``nilpotent execute``: plan, then run the plan on a perturbed robot with re-planning."""

from __future__ import annotations

import math
from typing import Annotated

import typer

from nilpotent.cli.app import (
    MAX_CORRECTIONS,
    JsonOpt,
    ModelArg,
    ParamOpt,
    app,
    bounded_float,
    bounded_int,
    cli_errors,
    emit_json,
    literal,
    load_model_option,
    parse_point_option,
    print_heading,
    stdout_console,
    work,
)
from nilpotent.cli.plan_options import (
    ClearanceOpt,
    FromOpt,
    LimitOpt,
    MarginOpt,
    MaxPieceOpt,
    PlannerOpt,
    SeedOpt,
    TimeLimitOpt,
    ToOpt,
    WorldOpt,
    command_budget,
    plan_from_options,
)
from nilpotent.errors import OptionError

MismatchOpt = Annotated[
    str | None,
    typer.Option("--mismatch", metavar="P=F,...",
                 help="True parameters off by fractions: r=0.05,l=-0.05 means r·1.05, l·0.95 "
                      "(each between -0.5 and 1)."),
]
NoiseOpt = Annotated[
    float,
    typer.Option("--noise", metavar="SIGMA",
                 help="Standard deviation of the state measurement noise (model units).",
                 parser=bounded_float("--noise", 0.0)),
]
ExecTolOpt = Annotated[
    float,
    typer.Option("--tol", metavar="T",
                 help="Correct until the measured distance to the goal is at most T.",
                 parser=bounded_float("--tol", 0.0, open_low=True)),
]
#: Exit status of an execution that ran but did not succeed (goal not reached within --tol,
#: or a violation by the true motion); documented in docs/planning.md.
EXIT_NOT_REACHED = 3

CorrOpt = Annotated[
    int,
    typer.Option("--max-corrections", metavar="N",
                 help=f"Most re-plans toward the goal (0 to {MAX_CORRECTIONS}).",
                 parser=bounded_int("--max-corrections", 0, MAX_CORRECTIONS)),
]


def parse_mismatch(text: str | None) -> dict[str, float]:
    """``r=0.05,l=-0.05`` → ``{"r": 0.05, "l": -0.05}`` (values: expressions of the grammar,
    read by the one ``NAME=VALUE,...`` parser: each name once)."""
    from nilpotent.core.model.expressions import real_value
    from nilpotent.core.model.points import parse_assignments

    if not text:
        return {}
    pairs = parse_assignments(text, "--mismatch", OptionError, "--mismatch r=0.05,l=-0.05")
    return {name: real_value(value, where=f"--mismatch {name}") for name, value in pairs}


@app.command("execute")
@cli_errors
def execute_command(
    model: ModelArg,
    to: ToOpt,
    from_: FromOpt = None,
    param: ParamOpt = None,
    world: WorldOpt = None,
    limit: LimitOpt = None,
    singular_margin: MarginOpt = 0.0,
    clearance: ClearanceOpt = 0.0,
    time_limit: TimeLimitOpt = 60.0,
    seed: SeedOpt = 0,
    max_piece: MaxPieceOpt = 1.0,
    planner: PlannerOpt = "auto",
    mismatch: MismatchOpt = None,
    noise: NoiseOpt = 0.0,
    tol: ExecTolOpt = 1e-3,
    max_corrections: CorrOpt = 10,
    json_out: JsonOpt = False,
) -> None:
    """Plan MODEL from --from to --to, then execute the plan on a perturbed robot.

    The true robot has its parameters off by --mismatch and its state measured
    with --noise; after each piece of the plan the rest is re-planned from the
    measured state, then corrections toward the goal until the measured error
    is at most --tol.  Reports the closed-loop and the open-loop final errors
    and every violation of limits, obstacles and singular margin by the true
    motion (schema nilpotent/execution@1).  --time-limit bounds the whole
    command (planning and execution).  Exit status 0: the goal was reached
    without violations ("success": true); 3: the execution ran but did not
    succeed (the report is printed all the same); 2: an error.
    """
    from nilpotent.planning.execute import execute_plan

    if not (math.isfinite(noise) and noise >= 0):
        raise OptionError(f"--noise must be >= 0, got {noise}")
    if not (math.isfinite(tol) and tol > 0):
        raise OptionError(f"--tol must be a positive number, got {tol}")
    fractions = parse_mismatch(mismatch)
    system = load_model_option(model, param)
    from nilpotent.planning.execute import perturbed_system

    perturbed_system(system, fractions)  # refuse bad names before planning
    start = parse_point_option(from_, system, option="--from")
    goal = parse_point_option(to, system, option="--to")
    if not (math.isfinite(time_limit) and time_limit > 0):
        raise OptionError(f"--time-limit must be a positive number of seconds, got {time_limit}")
    from nilpotent.planning.optimal_planner import PLANNERS

    if planner not in PLANNERS:
        raise OptionError(
            f"--planner must be {' or '.join(PLANNERS)}; got {literal(planner, 60)!r}")
    with command_budget(time_limit):  # one limit for planning and execution together
        with work(f"plan {system.name}"):
            glob = plan_from_options(system, start, goal, min(1e-8, tol), world, limit,
                                     singular_margin, time_limit, seed, max_piece,
                                     clearance=clearance, planner=planner)
        with work(f"execute on the perturbed {system.name}"):
            result = execute_plan(glob, fractions, noise, seed, tol, max_corrections,
                                  time_limit)
    if json_out:
        emit_json(result.to_json())
        if not result.reached:
            raise typer.Exit(EXIT_NOT_REACHED)
        return
    console = stdout_console()
    c, o = result.closed_loop, result.open_loop
    mism = ", ".join(f"{k} {v:+.3g}" for k, v in fractions.items()) or "none"
    print_heading(console, system.name, f": mismatch {literal(mism)}, noise {noise:g}, seed {seed}")
    console.print(f"closed loop: error {c.error:.3e} (measured {result.measured_error:.3e}) "
                  f"after {result.replans} re-plans; violations: "
                  f"{'; '.join(result.violations) or 'none'}")
    console.print(f"open loop:   error {o.error:.3e}; violations: "
                  f"{'; '.join(result.open_loop_violations) or 'none'}")
    verdict = "reached" if result.reached else "NOT reached"
    stop = " (corrections stopped by the time limit)" if result.stopped_by_time_limit else ""
    console.print(f"goal {verdict} within {tol:g}{stop}")
    if not result.reached:
        raise typer.Exit(EXIT_NOT_REACHED)


