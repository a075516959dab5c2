"""``nilpotent plan``: steer a system from one point to another (iterated nilpotent steering)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer

from nilpotent.cli.app import (
    MAX_ITERATIONS,
    JsonOpt,
    ModelArg,
    ParamOpt,
    PlotOpt,
    app,
    bounded_int,
    check_plot_path,
    check_writable,
    cli_errors,
    emit_json,
    literal,
    load_model_option,
    parse_point_option,
    print_heading,
    save_figure,
    stdout_console,
    work,
    write_atomically,
)
from nilpotent.errors import OptionError

FromOpt = Annotated[
    str | None,
    typer.Option("--from", metavar="P", help="Start NAME=VALUE,... (default: the origin)."),
]
ToOpt = Annotated[
    str,
    typer.Option("--to", metavar="Q", help="Goal NAME=VALUE,...; unnamed coordinates are 0."),
]
TolOpt = Annotated[
    float,
    typer.Option("--tol", metavar="T",
                 help="Stop when the Euclidean distance to the goal is at most T (> 0)."),
]
AnimateOpt = Annotated[
    Path | None,
    typer.Option("--animate", metavar="FILE", help="Write an animation of the motion (.gif)."),
]
AnchorOpt = Annotated[
    str,
    typer.Option("--anchor", metavar="WHERE",
                 help="Where to approximate: current (every iterate), goal, start, or auto."),
]
MaxItOpt = Annotated[
    int,
    typer.Option("--max-iterations", metavar="N",
                 help=f"Most nilpotent steps (1 to {MAX_ITERATIONS}).",
                 parser=bounded_int("--max-iterations", 1, MAX_ITERATIONS)),
]


def _check_outputs(plot: Path | None, animate: Path | None) -> None:
    check_plot_path(plot)
    if animate is not None and animate.suffix.lower() != ".gif":
        raise OptionError(
            f"--animate {literal(animate)}: the animation is written as GIF (use .gif)")
    check_writable(animate, "--animate")


def _print_plan(result) -> None:
    from rich.table import Table

    console = stdout_console()
    sys = result.system
    print_heading(
        console, sys.name,
        f": {len(result.iterations)} iteration(s), "
        f"{len(result.segments)} segment(s), total time {result.duration:.4g}; "
        f"approximation {result.builder}, anchor {result.anchor}"
    )
    table = Table(title="error after each iteration")
    for col in ("iteration", "distance to goal", "damping", "segments", "seconds"):
        table.add_column(col)
    table.add_row("0", f"{result.initial_error:.3e}", "", "", "")
    for k, it in enumerate(result.iterations, start=1):
        table.add_row(str(k), f"{it.error:.3e}", f"{it.damping:g}", str(it.segments),
                      f"{it.seconds:.3f}")
    console.print(table)
    pts = Table(title="points (model coordinates)")
    for col in ("coordinate", "from", "to", "reached"):
        pts.add_column(col)
    for k, name in enumerate(sys.coordinate_names):
        pts.add_row(name, f"{result.start[k]: .10g}", f"{result.goal[k]: .10g}",
                    f"{result.reached[k]: .10g}")
    console.print(pts)
    verdict = "reached" if result.converged else "NOT reached"
    console.print(f"goal {verdict}: error {result.error:.3e} (tol {result.tol:g})")


@app.command("plan")
@cli_errors
def plan_command(
    model: ModelArg,
    to: ToOpt,
    from_: FromOpt = None,
    tol: TolOpt = 1e-8,
    param: ParamOpt = None,
    anchor: AnchorOpt = "auto",
    max_iterations: MaxItOpt = 30,
    plot: PlotOpt = None,
    animate: AnimateOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Steer MODEL from --from to --to by iterated exact steering of nilpotent approximations.

    Prints the error after each iteration; --json gives the controls as segments
    (schema nilpotent/plan@1): u_i(t) = constant + Σ_k cos[k-1]·cos(kωt) + sin[k-1]·sin(kωt).
    """
    from nilpotent.planning import plan
    from nilpotent.planning.iterative import ANCHORS

    if not (math.isfinite(tol) and tol > 0):
        raise OptionError(f"--tol must be a positive number, got {tol}")
    if anchor != "auto" and anchor not in ANCHORS:
        raise OptionError(
            f"--anchor must be auto, {', '.join(ANCHORS)}; got {literal(anchor, 60)!r}")
    if max_iterations < 1:
        raise OptionError(f"--max-iterations must be >= 1, got {max_iterations}")
    _check_outputs(plot, animate)
    system = load_model_option(model, param)
    start = parse_point_option(from_, system, option="--from")
    goal = parse_point_option(to, system, option="--to")
    with work(f"plan {system.name}"):
        result = plan(system, start, goal, tol, anchor=anchor, max_iterations=max_iterations)
    if plot is not None:
        from nilpotent.viz.plan import plot_plan

        save_figure(plot_plan(result), plot, (system.name,))
    if animate is not None:
        import matplotlib

        from nilpotent.viz.plan import animate_plan

        # the plan's figures use no mathtext: a model name such as $\frac{a}$ stays literal
        with write_atomically(animate) as tmp, matplotlib.rc_context({"text.parse_math": False}):
            animate_plan(result, tmp)
    if json_out:
        emit_json(result.to_json())
        return
    _print_plan(result)
