"""Global planning among obstacles and limits: OMPL path, nilpotent steering, subdivision.

The classical approximation of a holonomic path (Laumond, Sekhavat, Lamiraux, "Guidelines
in nonholonomic motion planning for mobile robots", 1998; Laumond et al. 1994):

1. a collision-free path in configuration space, ignoring the nonholonomic
   constraints, from OMPL's RRTConnect (``ompl.geometric``) with a validity
   checker for the limits, the world (robot outline vs obstacles, shapely)
   and the singular margin (:class:`~nilpotent.planning.verify.Checker`),
   simplified, then cut into pieces no longer than ``max_piece``;
2. each piece is steered from the state actually reached to its end waypoint by the
   iterated nilpotent steering (:func:`nilpotent.planning.iterative.plan`); the steered
   motion is re-simulated and checked at dense samples; progress on stderr counts the
   pieces steered (:func:`nilpotent.progress.report`);
3. a piece whose steered motion leaves the free space or the limits (or that
   cannot be steered) is halved (its chord's midpoint becomes a waypoint) and
   retried; intermediate waypoints are reached within
   ``min(MID_TOL, MID_TOL_FRACTION · piece length)``, and when the state reached
   is further than that from the chord, it is first steered back onto the
   chord's start.  The nilpotent motions shrink with the distance (homogeneity:
   a displacement ``ε`` in a weight-``w`` direction costs motions of size
   ``ε^{1/w}``), so the steered motion of a short enough piece stays in any
   open tube around the chord and subdivision terminates on paths with
   positive clearance.

Before that, a **direct** attempt: when the goal is within ``DIRECT_RADIUS``
and the straight chord from start to goal is admissible, the single nilpotent
plan of ``plan()`` (the old behaviour of ``nilpotent plan``) is kept if its
motion is admissible; this keeps earlier results unchanged for small problems.
Every returned plan is re-simulated as a whole (:func:`~nilpotent.planning.verify.verify_segments`,
100 samples per segment) and refused unless admissible and within ``tol`` of the goal.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from nilpotent.core.model.outline import Limits
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import (
    ComputationLimitError,
    IntegrationError,
    OptionError,
    PlanningError,
    SingularPointError,
)
from nilpotent.numeric.settings import IntegrationSettings, resolve_settings
from nilpotent.numeric.types import State
from nilpotent.planning import budget
from nilpotent.planning.controls import Segment
from nilpotent.planning.grid_distance import refuse_unreachable
from nilpotent.planning.holonomic_path import ompl_path
from nilpotent.planning.iterative import Iteration, Plan, PlanFigure, Trajectory, plan
from nilpotent.planning.nilpotent import StepTooHighError
from nilpotent.planning.ocp import OcpRefine, Refinement, check_refine, refine_route
from nilpotent.planning.optimal_planner import HolonomicStage, planner_json
from nilpotent.planning.simulation import PLANNING_SETTINGS, simulate_path
from nilpotent.planning.timing import TimedTrajectory, input_bounds, motion_fields, retime
from nilpotent.planning.verify import Checker, Verification, verify_segments
from nilpotent.planning.world import World
from nilpotent.progress import ProgressEvent
from nilpotent.progress import report as report_progress
from nilpotent.strict_json import json_safe

__all__ = [
    "GlobalPlan", "Piece", "ompl_path", "plan_global", "plan_json", "shape_held_path",
    "shape_indices", "steer_admissible",
]

#: Largest tolerance at intermediate waypoints (the next piece starts from the state reached).
MID_TOL = 0.05
#: ... and at most this fraction of the piece's length (so that halving converges).
MID_TOL_FRACTION = 0.1
#: Clearance the global (holonomic) path keeps beyond the required one (model length units),
#: except within ``PATH_END_ZONE`` of the start and the goal: room for the steered motions.
PATH_CLEARANCE = 0.2
PATH_END_ZONE = 1.0
#: Default longest piece (Euclidean in configuration space) before steering.
MAX_PIECE = 1.0
#: Pieces are not halved below this length: then planning fails.
MIN_PIECE = 1e-3
#: Most pieces a global path is cut into (each steered on its own, in 0.1-1 s; memory).
MAX_PIECES = 10_000
#: Samples per segment when a piece's motion is checked / the whole plan is verified.
CHECK_POINTS = 40
VERIFY_POINTS = 100
#: Samples per segment of the second, denser check of a piece whose samples are all
#: admissible but whose cover between samples (Checker.valid_motion) was too wide.
DENSE_CHECK_POINTS = 200
#: The direct attempt (one nilpotent plan) is made for goals this close (Euclidean distance).
DIRECT_RADIUS = 2.0
#: Configurations checked at once along a straight chord (memory).
CHORD_CHUNK = 20_000


@dataclass(frozen=True)
class Piece:
    """One steered piece: its end waypoint, the segments it added, its error, its iterations."""

    target: tuple[float, ...]
    first_segment: int
    segments: int
    error: float
    iterations: int
    halvings: int


@dataclass(frozen=True, eq=False)
class GlobalPlan(PlanFigure):
    """A plan among limits and obstacles, verified by dense re-simulation.

    Attributes
    ----------
    plan:
        The whole plan as a :class:`~nilpotent.planning.iterative.Plan`
        (segments in order from the start; ``trajectory`` the dense
        re-simulation; ``iterations`` those of all pieces, each measuring the
        distance to its own piece's end).
    world, limits, singular_margin:
        What the plan respects.
    waypoints:
        The configuration-space path (start, the global path's vertices and the
        midpoints inserted by subdivision, goal).
    pieces:
        The steered pieces.
    verification:
        The dense re-simulation: clearance, limit margin, singular margin, error.
    route:
        ``"direct"`` (one nilpotent plan, no global path needed) or ``"global"``.
    planner_seconds:
        Time spent in OMPL.
    time_limit:
        The wall-clock budget the planning was given (seconds; ``inf``: none).
    seconds:
        Wall-clock time of the whole planning.
    clearance_required:
        The distance robot–obstacles the motion had to exceed (``clearance`` of
        :func:`plan_global`; model length units).
    refinement:
        What the optimal-control refinement did (``refine="ocp"`` of :func:`plan_global`:
        :class:`~nilpotent.planning.ocp.Refinement`), or ``None`` when none was asked for.
    timed:
        The plan re-timed under the input bounds of :func:`plan_global`
        (:func:`~nilpotent.planning.timing.retime`), or ``None`` when none were given.
    planner, path_cost, cost_history:
        The holonomic stage (``optimal_planner.PLANNERS``); its path's ball–box cost
        (rrtstar) or Reeds–Shepp length (reeds-shepp), the best ``(seconds, cost)`` per slice.
    """

    plan: Plan
    world: World | None
    limits: Limits
    singular_margin: float
    waypoints: tuple[tuple[float, ...], ...]
    pieces: tuple[Piece, ...]
    verification: Verification
    route: str
    planner_seconds: float = 0.0
    time_limit: float = math.inf
    seconds: float = field(default=0.0)
    clearance_required: float = 0.0
    refinement: Refinement | None = None
    timed: TimedTrajectory | None = None
    planner: str = "rrtconnect"
    path_cost: float | None = None
    cost_history: tuple[tuple[float, float], ...] = ()

    @property
    def error(self) -> float:
        return self.verification.error

    # --- display in Jupyter: the whole plan's start, goal, point reached, iterations ---
    def to_latex(self) -> str:
        """:meth:`Plan.to_latex` of the whole plan (:attr:`plan`)."""
        return self.plan.to_latex()

    def _repr_latex_(self) -> str:
        return self.to_latex()

    def _repr_html_(self) -> str:
        return self.plan._repr_html_()

    def to_json(self) -> dict[str, Any]:
        """``nilpotent/plan@1`` (the interface page) with ``world``, ``limits``, ``waypoints``,
        ``clearance``, ``limits_ok``, ``min_singular_margin`` and more; no NaN/Infinity
        (undefined numbers are null, ``null_reasons`` says why)."""
        v = self.verification
        out = self.plan.json_fields()
        reasons: dict[str, str] = dict(self.plan.length_fields[1])
        if v.clearance is None:
            reasons["clearance"] = "no world given: no obstacles to measure against"
        if v.self_clearance is None:
            reasons["self_clearance"] = f"model {self.plan.system.name} names no body pairs"
        if v.min_singular_margin is None:
            reasons["min_singular_margin"] = f"model {self.plan.system.name} defines no " \
                "singular margin"
        out.update({
            "reached": list(v.reached), "error": v.error,
            "converged": bool(v.error <= self.plan.tol),
            "world": None if self.world is None else self.world.name,
            "limits": {k: [lo, hi] for k, (lo, hi) in self.limits.as_dict().items()},
            "relative_limits": {k: list(b) for k, b in self.limits.relative_dict().items()},
            "waypoints": [list(w) for w in self.waypoints],
            "clearance": v.clearance, "limits_ok": v.limits_ok, "limit_margin": v.limit_margin,
            "self_clearance": v.self_clearance, "self_collision_ok": v.self_collision_ok,
            "min_singular_margin": v.min_singular_margin,
            "singular_margin": self.singular_margin,
            "clearance_required": self.clearance_required,
            "route": self.route,
            "planner_seconds": self.planner_seconds,
            **planner_json(self.planner, self.path_cost, self.cost_history, reasons),
            "seconds": self.seconds,
            "pieces": [
                {"target": list(p.target), "first_segment": p.first_segment,
                 "segments": p.segments, "error": p.error, "iterations": p.iterations,
                 "halvings": p.halvings}
                for p in self.pieces
            ],
        })
        if self.world is not None:
            out["world_definition"] = self.world.to_json()
        if self.refinement is not None:
            out["refinement"] = self.refinement.to_json()
        out.update(motion_fields(self.plan.system, self.plan.segments, self.timed, reasons))
        return plan_json(out, reasons)


def plan_json(out: dict[str, Any], reasons: dict[str, str] | None = None) -> dict[str, Any]:
    """``out`` made strict JSON (:func:`nilpotent.strict_json.json_safe`: non-finite
    numbers become ``null``, listed under ``undefined``), with ``null_reasons`` saying why
    the fields in ``reasons`` are ``null``."""
    undefined: list[str] = []
    clean = json_safe(out, undefined=undefined)
    if undefined:
        clean["undefined"] = {
            "paths": undefined,
            "why": "not finite numbers (NaN or infinity), hence null; e.g. Newton refinement "
                   "steps compute no homogeneous distance",
        }
    if reasons:
        clean["null_reasons"] = dict(reasons)
    return clean


def shape_indices(checker: Checker) -> tuple[int, ...]:
    """Indices of the shape coordinates: those with box limits, other than ``x`` and ``y``
    (the trident's joint angles ``φ_i``; none for the car with trailers)."""
    assert checker.limits is not None
    names = checker.system.coordinate_names
    limited = {name for name, _, _ in checker.limits.bounds}
    return tuple(j for j, name in enumerate(names) if name in limited and name not in ("x", "y"))


def shape_held_path(
    checker: Checker,
    x0: np.ndarray,
    xg: np.ndarray,
    seconds: float,
    seed: int | None,
    valid: Callable[[np.ndarray], np.ndarray],
    held: Sequence[int],
    path_fn: Callable[..., list[np.ndarray]] = ompl_path,
    chord: bool = True,
) -> list[np.ndarray]:
    """A path that moves the other coordinates with the ``held`` (shape) ones at the start's
    values, then changes the shape to the goal's at the goal's pose (a last straight chord).

    OMPL then samples only the body pose (a lower-dimensional, easier query), and the
    steered pieces need no shape correction on the way: only the last piece does.
    ``path_fn``: the OMPL stage (signature of :func:`ompl_path`); ``chord``: take a free chord.

    Raises
    ------
    PlanningError
        The goal's pose with the start's shape, or the last chord, is not admissible
        (under ``valid``), or OMPL finds no path within ``seconds``.
    """
    held = list(held)
    xe = xg.copy()
    xe[held] = x0[held]
    if not valid(xe[None, :])[0]:
        raise PlanningError("the goal's pose with the start's shape is not admissible")
    if not _chord_valid(valid, xe, xg):
        raise PlanningError("the shape cannot change at the goal's pose")
    if chord and _chord_valid(valid, x0, xe):
        path = [x0.copy(), xe]
    else:
        path = path_fn(checker, x0, xe, seconds, seed, valid=valid, held=held)
    if float(np.linalg.norm(xg - xe)) > 0.0:
        path.append(xg.copy())
    return path


def _densify(points: Sequence[np.ndarray], max_piece: float) -> list[np.ndarray]:
    count = sum(math.ceil(float(np.linalg.norm(b - a)) / max_piece)
                for a, b in itertools.pairwise(points))
    if count > MAX_PIECES:
        raise ComputationLimitError(
            f"the global path would be cut into {count:,} pieces of at most --max-piece "
            f"{max_piece:g}, above the limit {MAX_PIECES:,}; raise --max-piece or bring the "
            "goal closer")
    out = [points[0]]
    for a, b in itertools.pairwise(points):
        k = max(1, math.ceil(float(np.linalg.norm(b - a)) / max_piece))
        out += [a + (b - a) * (i / k) for i in range(1, k)] + [b.copy()]
    return out


def _chord_valid(
    valid: Callable[[np.ndarray], np.ndarray], a: np.ndarray, b: np.ndarray, step: float = 0.01
) -> bool:
    """Every configuration ``step`` apart on the chord ``a → b`` valid (checked in chunks of
    :data:`CHORD_CHUNK`, within the time budget; stops at the first invalid one)."""
    k = max(2, math.ceil(float(np.linalg.norm(b - a)) / step) + 1)
    for lo in range(0, k, CHORD_CHUNK):
        budget.check("checking a straight chord of the configuration space")
        t = (np.arange(lo, min(k, lo + CHORD_CHUNK), dtype=float) / (k - 1))[:, None]
        if not np.all(valid(a + t * (b - a))):
            return False
    return True


def _roomy(
    checker: Checker, x0: np.ndarray, xg: np.ndarray, extra: float, near: float
) -> Callable[[np.ndarray], np.ndarray]:
    """Validity with ``extra`` clearance, except within ``near`` of the start or the goal
    (configuration space), where the plain validity suffices."""

    def valid(q: np.ndarray) -> np.ndarray:
        q = np.atleast_2d(q)
        ok = checker.valid(q)
        far = ok & (np.linalg.norm(q - x0, axis=1) > near) & (np.linalg.norm(q - xg, axis=1) > near)
        if far.any():
            ok[far] = checker.valid(q[far], extra_clearance=extra)
        return ok

    return valid


def steer_admissible(
    system: ControlSystem, checker: Checker, x: np.ndarray, w: np.ndarray, tol: float,
    options: dict[str, Any],
    endpoints_singular_raise: bool = False,
) -> Plan | None:
    """The nilpotent plan from ``x`` to ``w`` if its densely sampled motion is admissible.

    ``endpoints_singular_raise``: a singular ``x`` or ``w`` raises
    :class:`SingularPointError` (for the user's start and goal) instead of
    failing the piece.
    """
    try:
        p = plan(system, x, w, tol, trajectory_points=CHECK_POINTS, **options)
    except SingularPointError as exc:
        if endpoints_singular_raise and not str(exc).startswith("the path meets"):
            raise
        return None
    except StepTooHighError:
        raise  # the objective does not apply to this system: no smaller piece helps
    except (PlanningError, IntegrationError):
        return None
    states = p.trajectory.states
    if checker.valid_motion(states):
        return p
    if not np.all(checker.valid(states)):
        return None
    # every sample is admissible, only the cover of the motion between samples (margins
    # from its steps and bends) failed: sample more densely (smaller steps, smaller covers)
    _, dense = simulate_path(system, x, list(p.segments), DENSE_CHECK_POINTS,
                             options.get("settings", PLANNING_SETTINGS))
    if not checker.valid_motion(dense):
        return None
    return p


def plan_global(
    sys: ControlSystem,
    start: Sequence[object] | State,
    goal: Sequence[object] | State,
    tol: float = 1e-8,
    *,
    world: World | None = None,
    limits: Limits | None = None,
    singular_margin: float = 0.0,
    time_limit: float = 60.0,
    seed: int | None = 0,
    max_piece: float = MAX_PIECE,
    engine: str | None = None,
    direct: bool = True,
    anchor: str = "auto",
    max_iterations: int = 30,
    clearance: float = 0.0,
    path_clearance: float = PATH_CLEARANCE,
    hold_shape: bool = True,
    objective: str = "reach",
    refine: str | OcpRefine = "none",
    max_speed: float | Sequence[float] | dict[str, float] | None = None,
    max_accel: float | Sequence[float] | dict[str, float] | None = None,
    trajectory_step: float | None = None,
    settings: IntegrationSettings | None = None,
    planner: str = "auto",
) -> GlobalPlan:
    """Plan from ``start`` to ``goal`` within ``limits``, outside the ``world``'s obstacles.

    Parameters
    ----------
    sys : ControlSystem
        The model; its ``geometry`` (outline) is needed with a ``world``.
    start, goal:
        Configurations (model coordinates).
    tol:
        Final Euclidean error allowed.
    world:
        Obstacles and bounds, or ``None``.
    limits:
        Box limits (default: the model's own, e.g. the trident's ``|φ_i| ≤ 5π/6``).
    singular_margin:
        Required margin from the singular set (models that define one).
    time_limit:
        Seconds for the whole planning (OMPL gets at most half).
    seed:
        Seed of OMPL's random sampling (``None``: OMPL's own).
    max_piece:
        Longest piece steered at once (configuration-space Euclidean length; not the guide's).
    engine : str or None
        The loose form of ``settings.engine`` (kept for one release; pass
        ``settings=IntegrationSettings(engine=...)`` instead): an integration engine
        (:data:`nilpotent.numeric.engines.ENGINES`, or ``"auto"``).
    direct:
        Try the single nilpotent plan first (see the module doc).
    anchor, max_iterations:
        Passed to :func:`~nilpotent.planning.iterative.plan` for every piece.
    clearance:
        Required distance robot–obstacles along the motion (> this; default 0:
        no contact).
    path_clearance:
        Extra clearance the OMPL path keeps (except within ``PATH_END_ZONE`` of
        the start and the goal, configuration space): the tube in which the
        steered motions of the pieces have room (Laumond's approximation needs
        a path with positive clearance; a path that grazes obstacles needs
        tiny pieces, whose number grows like ``clearance^{-r}`` for a system of step ``r``).
    hold_shape:
        Look for the global path first with the shape coordinates
        (:func:`shape_indices`: the limited ones other than ``x``, ``y``) held at
        the start's values, changing them to the goal's only at the goal's pose
        (:func:`shape_held_path`; a quarter of the remaining time), then, if that
        fails, in the whole configuration space.  A path whose shape wanders
        forces every piece to correct it with loops of size ``√(piece length)``.
    objective:
        The local steering's objective, ``"reach"`` or ``"length"``
        (:data:`nilpotent.planning.length.OBJECTIVES`; passed to
        :func:`~nilpotent.planning.iterative.plan`).
    settings : IntegrationSettings or None
        How the true system is integrated, in the steering of every piece and in the
        final verification (default
        :data:`~nilpotent.planning.simulation.PLANNING_SETTINGS`: adaptive DOP853 at
        ``rtol = 1e-12``; its ``max_steps`` counts per segment of the controls).
    refine : str or OcpRefine
        ``"none"`` (default), ``"ocp"``, or :class:`~nilpotent.planning.ocp.OcpRefine`
        options: the plan found is refined by direct optimal control of the true system
        (:func:`nilpotent.planning.ocp.refine_segments`; the ``ocp`` extra; obstacles are not
        constraints of that problem), kept only if it verifies and is shorter
        (:attr:`GlobalPlan.refinement` says what happened).
    max_speed, max_accel : float, sequence of float, dict or None
        Bounds on the inputs of the re-timed motion, ``|ũ_i| ≤ V_i`` and
        ``|dũ_i/dt| ≤ A_i``: a number (every input), ``m`` numbers, or
        ``{"u1": V, ...}`` (a speed bound may leave inputs out: unbounded; an
        acceleration bound must name them all).  Given, the verified plan is
        re-timed by TOPP-RA (:func:`~nilpotent.planning.timing.retime`) into
        :attr:`GlobalPlan.timed`; ``max_speed`` needs ``max_accel``.
    trajectory_step : float or None
        Largest time between the samples of the re-timed motion (default: its
        duration / 500).
    planner:
        ``"auto"`` (the best for the model), ``"rrtconnect"``, ``"rrtstar"``, ``"reeds-shepp"``
        or ``"trident-ocp"``: :class:`~nilpotent.planning.optimal_planner.HolonomicStage`.

    Raises
    ------
    OptionError
        A bad option, ``settings`` included (:class:`IntegrationSettings`).
    PlanningError
        Start or goal not admissible, no path, a piece
        that cannot be steered inside the free space even when short, or a
        final verification that fails (never returns an unverified plan).
    ComputationLimitError
        The time limit ran out before a plan was found and verified (every
        step is bounded by it: :mod:`nilpotent.planning.budget`), or the plan
        would need more than :data:`MAX_PIECES` pieces.
    MissingExtraError
        ``refine="ocp"`` without CasADi.
    """
    check_refine(refine)
    if not (time_limit > 0 and math.isfinite(time_limit)):
        raise OptionError(f"time limit must be a positive number of seconds, got {time_limit}")
    chosen = resolve_settings(settings, PLANNING_SETTINGS, engine=engine)
    bounds = input_bounds(sys.m, max_speed, max_accel, step=trajectory_step)
    with budget.time_budget(time_limit):
        result = _plan_global(
            sys, start, goal, tol, world=world, limits=limits,
            singular_margin=singular_margin, time_limit=time_limit, seed=seed,
            max_piece=max_piece, settings=chosen, direct=direct, anchor=anchor,
            max_iterations=max_iterations, clearance=clearance,
            path_clearance=path_clearance, hold_shape=hold_shape, objective=objective,
            refine=refine, planner=planner)
        if bounds is None:
            return result
        p = result.plan
        timed = retime(sys, p.start, p.segments, bounds, step=trajectory_step,
                       reached=p.reached, settings=chosen)
        return dataclasses.replace(result, timed=timed)


def _plan_global(
    sys: ControlSystem,
    start: Sequence[object] | State,
    goal: Sequence[object] | State,
    tol: float,
    *,
    world: World | None,
    limits: Limits | None,
    singular_margin: float,
    time_limit: float,
    seed: int | None,
    max_piece: float,
    settings: IntegrationSettings,
    direct: bool,
    anchor: str,
    max_iterations: int,
    clearance: float,
    path_clearance: float,
    hold_shape: bool,
    objective: str,
    refine: str | OcpRefine,
    planner: str = "auto",
) -> GlobalPlan:
    t0 = time.perf_counter()
    if not (tol > 0 and math.isfinite(tol)):
        raise OptionError(f"tol must be a positive number, got {tol}")
    if not (max_piece > 0 and math.isfinite(max_piece)):
        raise OptionError(f"max_piece must be > 0, got {max_piece}")
    options: dict[str, Any] = {"settings": settings, "anchor": anchor,
                               "max_iterations": max_iterations, "objective": objective}
    checker = Checker(sys, world, limits, singular_margin, clearance)
    assert checker.limits is not None
    x0 = np.array([float(v) for v in start])  # type: ignore[arg-type]
    xg = np.array([float(v) for v in goal])  # type: ignore[arg-type]
    for what, q in (("start", x0), ("goal", xg)):
        why = checker.why_invalid(q)
        if why:
            raise PlanningError(f"the {what} is not admissible: {why}")
    distance = float(np.linalg.norm(xg - x0))
    if distance / max_piece > MAX_PIECES:
        # the path is at least as long as the chord: refused before anything is allocated
        raise ComputationLimitError(
            f"the goal is {distance:.3g} away: at least {math.ceil(distance / max_piece):,} "
            f"pieces of --max-piece {max_piece:g}, above the limit of {MAX_PIECES:,} pieces; "
            "raise --max-piece or plan to a nearer goal"
        )

    stage = HolonomicStage(planner, max_piece, checker)  # the OMPL stage (path, cost)
    planner = stage.planner  # "auto": the one chosen
    refuse_unreachable(checker, x0, xg)  # a goal caged by obstacles, where decided soundly

    def finish(segments: list[Segment], iterations: list[Iteration], waypoints, pieces,
               route: str, planner_s: float, last: Plan) -> GlobalPlan:
        # the plan found is verified before any refinement, so that a refinement that
        # runs the time limit out leaves a plan to return (the final check needs time too)
        v = verify_segments(checker, x0, segments, xg, VERIFY_POINTS, settings)
        refinement = refine_route(refine, checker, x0, xg, segments, tol, settings)
        if refinement is not None and refinement[1].applied:
            segments, v = refinement[0], refinement[1].verification  # verified as below
        assert v is not None
        if not v.admissible:
            raise PlanningError(
                "the re-simulated plan is not admissible (clearance "
                f"{v.clearance}, limit margin {v.limit_margin}, self-clearance "
                f"{v.self_clearance}, singular margin {v.min_singular_margin}); no plan returned"
            )
        if not v.error <= tol:
            raise PlanningError(f"the re-simulated plan misses the goal by {v.error:.3g} > tol "
                                f"{tol:g} (with an estimate of the integration error added; a "
                                "tol near 1e-12 cannot be certified)")
        whole = Plan(
            system=sys, start=tuple(x0), goal=tuple(xg), segments=tuple(segments),
            reached=v.reached, error=v.error, iterations=tuple(iterations),
            trajectory=Trajectory(v.times, v.states), tol=tol, anchor=last.anchor,
            builder=last.builder, initial_error=float(np.linalg.norm(xg - x0)),
            seconds=time.perf_counter() - t0, objective=objective,
        )
        return GlobalPlan(whole, world, checker.limits, singular_margin,  # type: ignore[arg-type]
                          tuple(tuple(float(c) for c in w) for w in waypoints), tuple(pieces),
                          v, route, planner_s, time_limit, time.perf_counter() - t0,
                          checker.clearance, None if refinement is None else refinement[1],
                          **stage.fields())

    # 1. direct attempt (old behaviour)
    near = float(np.linalg.norm(xg - x0)) <= DIRECT_RADIUS
    if direct and near and _chord_valid(checker.valid, x0, xg):
        p = steer_admissible(sys, checker, x0, xg, tol, options, endpoints_singular_raise=True)
        if p is not None and p.converged:
            piece = Piece(tuple(xg), 0, len(p.segments), p.error, len(p.iterations), 0)
            try:
                return finish(list(p.segments), list(p.iterations), [x0, xg], [piece],
                              "direct", 0.0, p)
            except PlanningError:
                pass
    # 2. a path in configuration space, with room around it where possible
    planner_s = 0.0
    path_valid = checker.valid
    if world is not None and path_clearance > 0:
        path_valid = _roomy(checker, x0, xg, path_clearance, PATH_END_ZONE)
    if planner == "rrtconnect" and _chord_valid(path_valid, x0, xg):
        path = [x0, xg]
    else:
        t_ompl = time.perf_counter()
        path = None
        held = shape_indices(checker) if hold_shape and stage.car is None else ()
        if held:
            # first with the shape held (body pose only), then in the whole space
            budget.check("looking for a path with OMPL")
            seconds = max(0.1, 0.25 * budget.seconds_left())
            try:
                path = shape_held_path(checker, x0, xg, seconds, seed, path_valid, held,
                                       stage.path, chord=planner == "rrtconnect")
            except PlanningError:
                path = None
        if path is None:
            budget.check("looking for a path with OMPL")
            seconds = max(0.1, stage.share * budget.seconds_left())
            path = stage.path(checker, x0, xg, seconds, seed, valid=path_valid)
        planner_s = time.perf_counter() - t_ompl
    pieces_needed = sum(math.ceil(float(np.linalg.norm(b - a)) / max_piece)
                        for a, b in itertools.pairwise(path))
    if pieces_needed > MAX_PIECES:
        raise ComputationLimitError(
            f"the path found needs {pieces_needed:,} pieces of --max-piece {max_piece:g}, above "
            f"the limit of {MAX_PIECES:,}; raise --max-piece or plan to a nearer goal"
        )
    # a guide's waypoints bound exact legs (a chord's midpoint is on none: it is steered)
    waypoints = list(path) if stage.car is not None else _densify(path, stage.piece)
    # 3. steer piece by piece, halving pieces whose motion is not admissible
    targets: deque[tuple[np.ndarray, int]] = deque((w, 0) for w in waypoints[1:])
    x, prev = x0.copy(), x0.copy()
    used = [x0]
    segments: list[Segment] = []
    iterations: list[Iteration] = []
    pieces: list[Piece] = []
    last: Plan | None = None
    while targets:
        budget.check(f"steering piece {len(pieces) + 1} of about {len(pieces) + len(targets)}")
        w, halvings = targets[0]
        final = len(targets) == 1
        length = float(np.linalg.norm(w - prev))
        piece_tol = tol if final else max(tol, min(MID_TOL, MID_TOL_FRACTION * length))
        p = (stage.exact(checker, x, prev, w, piece_tol, CHECK_POINTS, final)
             or steer_admissible(sys, checker, x, w, piece_tol, options))
        if p is None or (final and not p.converged):
            off = float(np.linalg.norm(x - prev))
            if length == 0.0:
                # cannot steer back onto the path: continue from the state reached when the
                # straight chord from it to the next waypoint is admissible (the path is
                # re-anchored there; every motion is still checked), else give up
                targets.popleft()
                if not targets or not _chord_valid(checker.valid, x, targets[0][0]):
                    raise PlanningError(
                        f"cannot steer back onto the path at {np.array2string(w, precision=3)} "
                        f"from {off:.3g} away ({checker.constraints_near(x)})")
                prev = x.copy()
                continue
            if off > max(tol, MID_TOL_FRACTION * length):
                # the state reached is far off the path relative to this piece: back onto it
                targets.appendleft((prev.copy(), halvings))
                continue
            if length < MIN_PIECE:
                raise PlanningError(  # what constrains the motion there, not a guess
                    f"cannot steer near {np.array2string(w, precision=3)}: pieces down to "
                    f"{MIN_PIECE:g} fail ({checker.constraints_near(x)})")
            targets.appendleft(((prev + w) / 2, halvings + 1))
            continue
        targets.popleft()
        pieces.append(Piece(tuple(float(c) for c in w), len(segments), len(p.segments),
                            p.error, len(p.iterations), halvings))
        segments.extend(p.segments)
        iterations.extend(p.iterations)
        x = np.array(p.reached)
        prev = w
        used.append(w)
        last = p
        report_progress(ProgressEvent("pieces steered", len(pieces), len(pieces) + len(targets)))
    assert last is not None
    return finish(segments, iterations, used, pieces, "global", planner_s, last)
