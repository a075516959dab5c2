"""``nilpotent plan``: steer a system from one point to another, within limits and among
obstacles (OMPL global path + iterated nilpotent steering, verified by re-simulation)."""

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
    bounded_float,
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
from nilpotent.cli.plan_options import (
    ClearanceOpt,
    FromOpt,
    InputWeightsOpt,
    LimitOpt,
    MarginOpt,
    MaxAccelOpt,
    MaxPieceOpt,
    MaxSpeedOpt,
    PlannerOpt,
    RefineSmoothOpt,
    RefineStartsOpt,
    ReversalCostOpt,
    SeedOpt,
    TimeLimitOpt,
    ToOpt,
    TrajectoryOutOpt,
    TrajectoryStepOpt,
    WorldOpt,
    command_budget,
    parse_bound_option,
    plan_from_options,
    refine_from_options,
)
from nilpotent.errors import OptionError

TolOpt = Annotated[
    float,
    typer.Option("--tol", metavar="T",
                 help="Stop when the Euclidean distance to the goal is at most T (> 0).",
                 parser=bounded_float("--tol", 0.0, open_low=True)),
]
AnimateOpt = Annotated[
    Path | None,
    typer.Option("--animate", metavar="FILE",
                 help="Write an animation of the motion (.gif, .mp4 or .html)."),
]
AnchorOpt = Annotated[
    str,
    typer.Option("--anchor", metavar="WHERE",
                 help="Where to approximate: current (every iterate), goal, start, or auto."),
]
MaxItOpt = Annotated[
    int,
    typer.Option("--max-iterations", metavar="N",
                 help=f"Most nilpotent steps, and most Newton steps of the final "
                      f"refinement (1 to {MAX_ITERATIONS}).",
                 parser=bounded_int("--max-iterations", 1, MAX_ITERATIONS)),
]

ObjectiveOpt = Annotated[
    str,
    typer.Option("--objective", metavar="WHAT",
                 help="Local steering: reach (straight segment and loops, default) or length "
                      "(shortest normal geodesics of the nilpotent approximation: closed form "
                      "for step 2, shooting above)."),
]

RefineOpt = Annotated[
    str,
    typer.Option("--refine", metavar="HOW",
                 help="none (default) or ocp: shorten a direct plan by optimal control of the "
                      "true system (CasADi + IPOPT; needs pip install \"nilpotent[ocp]\"), "
                      "kept only if it verifies and is shorter."),
]

ANIMATION_SUFFIXES = (".gif", ".mp4", ".html")


def _check_outputs(plot: Path | None, animate: Path | None) -> None:
    check_plot_path(plot)
    if animate is not None and animate.suffix.lower() not in ANIMATION_SUFFIXES:
        raise OptionError(
            f"--animate {literal(animate)}: unknown animation type "
            f"(use {', '.join(ANIMATION_SUFFIXES)})"
        )
    if animate is not None and animate.suffix.lower() == ".mp4":
        from matplotlib import animation

        if not animation.writers.is_available("ffmpeg"):
            raise OptionError(
                f"--animate {literal(animate)}: writing .mp4 needs ffmpeg (use .gif or .html)"
            )
    check_writable(animate, "--animate")


def _print_plan(glob) -> None:
    from rich.table import Table

    result = glob.plan
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
    v = glob.verification
    console.print(
        f"route {glob.route}: {len(glob.waypoints)} waypoint(s), {len(glob.pieces)} piece(s)"
        + (f", world {literal(glob.world.name)}" if glob.world is not None else "")
    )
    # the relative limits too (a hitch angle): "none" only where nothing is limited
    lim = ", ".join(f"{literal(k)} in [{lo:.4g}, {hi:.4g}]" for k, (lo, hi) in
                    [*glob.limits.as_dict().items(), *glob.limits.relative_dict().items()])
    console.print(f"limits: {lim or 'none'}; limits kept: {v.limits_ok}")
    if v.clearance is not None:
        console.print(f"clearance to obstacles: {v.clearance:.4g}")
    if v.min_singular_margin is not None:
        console.print(f"smallest singular margin: {v.min_singular_margin:.4g}")
    ref = glob.refinement
    if ref is not None:
        metric = "length" if ref.input_weights is None else (
            f"weighted length (weights {', '.join(f'{w:g}' for w in ref.input_weights)})")
        after = "none" if ref.length_refined is None else f"{ref.length_refined:.6g}"
        console.print(f"refinement ocp: {'applied' if ref.applied else 'not applied'}, {metric} "
                      f"{ref.length_before:.6g} -> {after}; {ref.controls}; starts "
                      f"{ref.starts_run} of {ref.starts}, {ref.candidates} candidate(s)"
                      + (f"; cost with reversals {ref.cost_before:.6g} -> {ref.cost_refined:.6g}"
                         if ref.reversal_cost and ref.cost_refined is not None else "")
                      + (f" ({ref.reason})" if ref.reason else ""))
    if glob.timed is not None:
        timed = glob.timed
        console.print(
            f"re-timed (TOPP-RA): duration {timed.duration:.4g}, {timed.times.size} samples, "
            f"{len(timed.stops)} stops; max |u| {float(abs(timed.inputs).max()):.4g}")
    verdict = "reached" if v.error <= result.tol else "NOT reached"
    console.print(f"goal {verdict}: error {v.error:.3e} (tol {result.tol:g}; re-simulated)")


@app.command("plan")
@cli_errors
def plan_command(
    model: ModelArg,
    to: ToOpt,
    from_: FromOpt = None,
    tol: TolOpt = 1e-8,
    param: ParamOpt = None,
    world: WorldOpt = None,
    limit: LimitOpt = None,
    singular_margin: MarginOpt = 0.0,
    clearance: ClearanceOpt = 0.0,
    time_limit: TimeLimitOpt = 60.0,
    seed: SeedOpt = 0,
    max_piece: MaxPieceOpt = 1.0,
    anchor: AnchorOpt = "auto",
    max_iterations: MaxItOpt = 30,
    objective: ObjectiveOpt = "reach",
    planner: PlannerOpt = "auto",
    refine: RefineOpt = "none",
    input_weights: InputWeightsOpt = None,
    refine_starts: RefineStartsOpt = None,
    reversal_cost: ReversalCostOpt = None,
    refine_smooth: RefineSmoothOpt = False,
    max_speed: MaxSpeedOpt = None,
    max_accel: MaxAccelOpt = None,
    trajectory_out: TrajectoryOutOpt = None,
    trajectory_step: TrajectoryStepOpt = None,
    plot: PlotOpt = None,
    animate: AnimateOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Steer MODEL from --from to --to within its limits and around the --world's obstacles.

    Small problems are solved by iterated exact steering of nilpotent
    approximations; otherwise a collision-free path from OMPL (RRTConnect, RRT* with
    --planner rrtstar, or a Reeds-Shepp path for a car with --planner reeds-shepp) is
    steered piece by piece, halving pieces whose motion leaves the free space
    (--planner trident-ocp: the trident snake's pieces by optimal control of its body path).
    Every plan is re-simulated densely and checked (clearance, limits, error).
    --json gives the controls as segments (schema nilpotent/plan@1):
    u_i(t) = constant + Σ_k cos[k-1]·cos(kωt) + sin[k-1]·sin(kωt).
    """
    from nilpotent.planning.iterative import ANCHORS
    from nilpotent.planning.length import OBJECTIVES
    from nilpotent.planning.ocp import check_refine
    from nilpotent.planning.optimal_planner import PLANNERS

    if not (math.isfinite(tol) and tol > 0):
        raise OptionError(f"--tol must be a positive number, got {tol}")
    if anchor != "auto" and anchor not in ANCHORS:
        raise OptionError(
            f"--anchor must be auto, {', '.join(ANCHORS)}; got {literal(anchor, 60)!r}")
    if max_iterations < 1:
        raise OptionError(f"--max-iterations must be >= 1, got {max_iterations}")
    if objective not in OBJECTIVES:
        raise OptionError(
            f"--objective must be {' or '.join(OBJECTIVES)}; got {literal(objective, 60)!r}")
    if planner not in PLANNERS:
        raise OptionError(
            f"--planner must be {', '.join(PLANNERS[:-1])} or {PLANNERS[-1]}; "
            f"got {literal(planner, 60)!r}")
    check_refine(refine)
    if not (math.isfinite(time_limit) and time_limit > 0):
        raise OptionError(f"--time-limit must be a positive number of seconds, got {time_limit}")
    if not (math.isfinite(max_piece) and max_piece > 0):
        raise OptionError(f"--max-piece must be a positive number, got {max_piece}")
    _check_outputs(plot, animate)
    check_writable(trajectory_out, "--trajectory-out")
    system = load_model_option(model, param)
    start = parse_point_option(from_, system, option="--from")
    goal = parse_point_option(to, system, option="--to")
    refine_how = refine_from_options(refine, system, seed, input_weights, refine_starts,
                                     reversal_cost, refine_smooth)
    speed = parse_bound_option(max_speed, system, "--max-speed")
    accel = parse_bound_option(max_accel, system, "--max-accel", every=True)
    if accel is None and (speed is not None or trajectory_out is not None
                          or trajectory_step is not None):
        given = "--max-speed" if speed is not None else (
            "--trajectory-out" if trajectory_out is not None else "--trajectory-step")
        raise OptionError(f"{given} needs --max-accel (the re-timed inputs are continuous "
                          "only with bounded accelerations)")
    with command_budget(time_limit), work(f"plan {system.name}"):  # the bar sees the limit
        result = plan_from_options(
            system, start, goal, tol, world, limit, singular_margin, time_limit, seed,
            max_piece, anchor=anchor, max_iterations=max_iterations,
            clearance=clearance, objective=objective, refine=refine_how, max_speed=speed,
            max_accel=accel, trajectory_step=trajectory_step, planner=planner,
        )
    write_pictures(result, plot, animate)
    if trajectory_out is not None and result.timed is not None:
        with write_atomically(trajectory_out) as tmp:
            tmp.write_text(result.timed.to_csv(), encoding="utf-8")
    if json_out:
        emit_json(result.to_json())
        return
    _print_plan(result)


def write_pictures(result, plot: Path | None, animate: Path | None) -> None:
    """``--plot`` and ``--animate`` of a global plan (world, outline, joint limits)."""
    if plot is not None:
        # user texts shown literally: the model's name and the world's (titles)
        names = (result.plan.system.name,) + ((result.world.name,) if result.world else ())
        save_figure(result.plot(), plot, names)  # the figure of GlobalPlan.plot()
    if animate is not None:
        import matplotlib

        from nilpotent.viz.plan_world import animate_plan_world

        # no mathtext: a model name such as $\frac{a}$ stays literal
        with write_atomically(animate) as tmp, matplotlib.rc_context({"text.parse_math": False}):
            animate_plan_world(result, tmp, animate.suffix.lower())
