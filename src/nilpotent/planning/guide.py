r"""A Reeds–Shepp guide for car-like models: the holonomic stage ``planner="reeds-shepp"``.

The holonomic stages of :mod:`nilpotent.planning.optimal_planner` plan in
``(x, y, θ, φ)`` as if the car could move sideways; the nilpotent steering of
each piece then has to make the sideways motion with manoeuvres that wander.
For a car, the shortest paths of bounded curvature are known (Reeds & Shepp,
"Optimal paths for a car that goes both forwards and backwards", Pacific J.
Math. 145(2), 1990): this stage plans with them and hands the steering pieces
the car can follow exactly.

1. **Search** (:func:`guide_path`): OMPL RRT* (path length; after its first path it
   improves it for :data:`IMPROVE_FRACTION` of its time, at most :data:`IMPROVE_SECONDS`,
   and never past :data:`IMPROVE_FRACTION` of its time from the start; the tree grows
   from the end with the smaller clearance, the goal in a parking slot: the reversed path
   is a Reeds–Shepp path too;
   a tree with no path after :data:`RESTART_SECONDS` is cleared and grown anew)
   in ``ob.ReedsSheppStateSpace(r_g)``, ``r_g = L / tan φ_g`` with
   ``φ_g = φ_max −`` :data:`PHI_MARGIN` (0.56 % above the car's least turning radius),
   bounds from the world (else the box of
   :func:`~nilpotent.planning.holonomic_path.box`); a pose is valid when the
   configuration ``(x, y, θ, φ)`` is, for each ``φ ∈ {−φ_g, 0, φ_g}`` (every steering
   angle the lifted path can take), under the checker's validity with the extra clearance
   :data:`GUIDE_MARGIN` (not the 0.2 that plan_global keeps for steered pieces: the legs
   are driven exactly).  The path is simplified by OMPL.
2. **Lift** (:func:`lift_legs`): the legs of each Reeds–Shepp curve of the path
   (curvature ``κ ∈ {−1/r_g, 0, 1/r_g}``, direction of travel) are classified from its
   samples and their lengths solved so that they end exactly at the curve's end
   (:func:`edge_legs`); along each leg ``φ = atan(L κ)`` (``θ̇ = v tan φ / L``), with
   waypoints every :data:`WAYPOINT_STEP` on the leg (closed form, :func:`leg_end`); where
   ``κ`` changes, waypoints at the same pose with ``φ`` from the old to the new value, in
   steps of at most :data:`PHI_STEP`: the car turns its wheels at rest (the steering
   field ``∂_φ``).  The heading is a real number from the start's ``θ``.  When a curve's
   legs cannot be solved, the path sampled every :data:`SAMPLE_STEP` is cut into legs
   instead (:func:`lift`, the fallback: waypoints on the samples).
3. The waypoints are the path :func:`~nilpotent.planning.global_planner.plan_global`
   follows piece by piece and verifies, as for the other holonomic stages; a piece that is
   one leg or one turn at rest is driven by that exact motion (:func:`exact_piece`),
   the others are steered.

**Car-like** (:func:`car_geometry`): a model with coordinates named
``x, y, theta, phi`` and two fields, ``X1 = cos θ ∂x + sin θ ∂y + (tan φ / L) ∂θ``
(``L > 0`` a number, read from the field once the parameters are substituted) and
``X2 = ∂φ``, with a limit ``|φ| ≤ φ_max < π/2`` (the built-in ``car``, whose default
limit is ``atan(L / rmin)``, or a model file with the same fields); its least turning
radius is ``L / tan φ_max`` (the smaller side of an asymmetric limit).
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import OptionError, PlanningError
from nilpotent.planning.holonomic_path import SIMPLIFY_SECONDS, anytime_solve, box
from nilpotent.planning.verify import Checker

__all__ = [
    "CAR_COORDINATES", "PHI_MARGIN", "CarGeometry", "GuidePath", "Leg", "car_geometry",
    "edge_legs", "edge_poses", "exact_piece", "guide_path", "leg_end", "lift", "lift_legs",
    "merge_legs",
]

#: Coordinates of a car-like model, in order.
CAR_COORDINATES = ("x", "y", "theta", "phi")
#: The guide's steering angle ``φ_g`` is this far (rad) below the limit: its turning radius
#: is ``L / tan φ_g`` (0.56 % above the least one for the built-in car).  The legs are driven
#: exactly, so this is only room for the motion check's cover between samples of a turn of
#: the wheels at rest that ends at ``±φ_g`` (:func:`exact_piece`).  (When every piece was
#: steered, 1.2 × the least radius was needed: the steering overshot ``φ``.)
PHI_MARGIN = 2.5e-3
#: Arc length between the samples of the Reeds–Shepp path that are classified.
SAMPLE_STEP = 0.01
#: Arc length between the samples of one Reeds–Shepp curve whose legs are solved
#: (:func:`edge_legs`), the Gauss–Newton steps on their lengths, and the pose error left.
LEG_SAMPLE_STEP = 0.002
LEG_ITERATIONS = 20
LEG_TOL = 1e-11
#: How far a step's ``κ r`` may be from ``−1, 0, 1`` (and ``1 −`` its share along the
#: heading) for it to be classified (:func:`edge_legs`).
CLEAN_TOL = 0.1
#: How much longer than OMPL's curve its solved legs may be (a leg shorter than a sample
#: step is missed; a curve with four or five legs has a family of solutions, the least-norm
#: one is kept: measured ``≤ 1e-4`` longer).
LEG_LENGTH_TOL = 1e-3
#: Largest distance between the end of the solved legs and the goal's pose
#: (:func:`lift_legs`; each curve's legs end within :data:`LEG_TOL` of its end).
LEG_END_TOL = 1e-8
#: Largest arc length between two waypoints of one leg.
WAYPOINT_STEP = 0.25
#: Largest change of ``φ`` between two waypoints where the wheels turn at rest (the
#: tolerance at a waypoint is a tenth of the piece: small turns leave the car on the path).
PHI_STEP = 0.1
#: Share of its time RRT* spends improving its first path, at most :data:`IMPROVE_SECONDS`
#: (benchmarks/plan_world.py, 30 s per query, the stage's 0.8 of it: about 11 s of
#: improvement, within 1.02 × Reeds–Shepp RRT* run for the whole 30 s on 8 pairs).  The
#: improvement also stops at that fraction of the time counted from the search's start: on
#: a loaded machine (load 6-8 on 2 cores) a late first path plus 11 s of improvement left
#: too little of 30 s for driving the legs and the verification (6 of 6 corner pairs ran
#: out of time re-simulating; with 30 s on a quieter machine, 17-18 s in all).
IMPROVE_FRACTION = 0.5
IMPROVE_SECONDS = 15.0
#: Seconds of RRT* without a first path after which its tree is cleared and grown anew
#: (:func:`~nilpotent.planning.holonomic_path.anytime_solve`): a tree can stall at a narrow
#: goal, its goal's neighbours retrying the same failing curves (the trailer guide of
#: :mod:`~nilpotent.planning.trailer_guide` before its states carried the hitch angle: the
#: ``parking`` goal (1.7, -0.55) from (-2.5, 1, 0.1, 0.1), seed 0, no path in 84 s; with the
#: restart, one at 20 s, on its second tree; that guide now searches otherwise).
RESTART_SECONDS = 15.0
#: Largest step (length units) at which OMPL checks the poses along a motion.
CHECK_STEP = 0.02
#: Extra clearance of the guide's poses (without a validity check given): OMPL's check
#: every :data:`CHECK_STEP` leaves the body up to about half a step between samples
#: unchecked, and the exact legs are then checked with a cover (:func:`exact_piece`); with no
#: margin, legs grazing the corner's wall failed that check and were steered (10 reversals).
GUIDE_MARGIN = CHECK_STEP
#: Largest arc length between the samples of an exact leg (:func:`exact_piece`).
EXACT_STEP = 0.002


@dataclass(frozen=True)
class CarGeometry:
    """What the guide needs of a car-like model.

    Attributes
    ----------
    wheelbase:
        ``L`` (rear axle to front axle).
    phi_max:
        The steering limit used, ``|φ| ≤ phi_max``.
    """

    wheelbase: float
    phi_max: float

    @property
    def min_radius(self) -> float:
        """The least turning radius of the rear axle's centre, ``L / tan φ_max``."""
        return self.wheelbase / math.tan(self.phi_max)


def car_geometry(system: ControlSystem, checker: Checker) -> CarGeometry:
    """The wheelbase and steering limit of a car-like model (module doc), with the limits of
    ``checker``.

    Raises
    ------
    OptionError
        The model is not car-like, or has no steering limit below ``π/2``.
    """
    why = _not_car_like(system)
    if why:
        raise OptionError(
            f"--planner reeds-shepp needs a car-like model (coordinates x, y, theta, phi; "
            f"fields cos(theta) d/dx + sin(theta) d/dy + tan(phi)/L d/dtheta and d/dphi, e.g. "
            f"the built-in car; or a car with one trailer, e.g. car-trailers:1): "
            f"model {system.name} {why}")
    fields = system.specialized_fields
    theta, phi = system.coordinates[2], system.coordinates[3]
    wheelbase = float(sp.simplify(sp.tan(phi) / fields[0][2]).subs(theta, 0))
    assert checker.limits is not None
    bounds = {name: (lo, hi) for name, lo, hi in checker.limits.bounds}
    lo, hi = bounds.get("phi", (-math.inf, math.inf))
    phi_max = min(-lo, hi)
    if not (0.0 < phi_max < math.pi / 2):
        raise OptionError(
            f"--planner reeds-shepp needs a steering limit |phi| <= phi_max < pi/2 (a least "
            f"turning radius); model {system.name} has phi in [{lo:g}, {hi:g}]")
    return CarGeometry(wheelbase, phi_max)


def _not_car_like(system: ControlSystem) -> str:
    """Why ``system`` is not car-like ('' when it is)."""
    if system.coordinate_names != CAR_COORDINATES:
        return f"has coordinates {', '.join(system.coordinate_names)}"
    if system.m != 2:
        return f"has {system.m} fields, not 2"
    _, _, theta, phi = system.coordinates
    drive, steer = system.specialized_fields
    if tuple(steer) != (0, 0, 0, 1):  # sympy numbers compare equal to ints
        return "has a second field other than d/dphi"
    ratio = sp.simplify(sp.tan(phi) / drive[2]) if drive[2] != 0 else sp.nan
    if (sp.simplify(drive[0] - sp.cos(theta)) != 0 or sp.simplify(drive[1] - sp.sin(theta)) != 0
            or drive[3] != 0 or not ratio.is_number or not bool(ratio > 0)):
        return "has a first field other than cos(theta), sin(theta), tan(phi)/L, 0 (L > 0)"
    return ""


@dataclass(frozen=True)
class GuidePath:
    """The lifted Reeds–Shepp path and how its length went down.

    Attributes
    ----------
    points:
        Waypoints ``(x, y, θ, φ)``, start and goal included.
    length:
        Length of the Reeds–Shepp path (rear axle; OMPL's, after simplification).
    length_history:
        ``(seconds since RRT* started, best length)`` after each slice with a solution.
    radius:
        The guide's turning radius ``r_g``.
    """

    points: tuple[tuple[float, ...], ...]
    length: float
    length_history: tuple[tuple[float, float], ...]
    radius: float


def guide_path(
    checker: Checker,
    x0: np.ndarray,
    xg: np.ndarray,
    seconds: float,
    seed: int | None = None,
    resolution: float = 0.05,
    valid: Callable[[np.ndarray], np.ndarray] | None = None,
    held: Sequence[int] = (),
) -> GuidePath:
    """The Reeds–Shepp guide from ``x0`` to ``xg`` (module doc), within ``seconds``.

    Parameters as :func:`~nilpotent.planning.holonomic_path.ompl_path` (``held`` is
    ignored: ``φ`` is set by the lifting, from ``x0``'s to ``xg``'s); without ``valid``,
    the checker's validity with the extra clearance :data:`GUIDE_MARGIN` (none when the
    start or the goal lacks it); OMPL checks the poses along a curve every
    :data:`CHECK_STEP`.  (:mod:`nilpotent.planning.trailer_guide` runs its own search, with
    the hitch angle in the state, on this module's legs and lifting.)

    Raises
    ------
    OptionError
        The model is not car-like.
    PlanningError
        No exact solution within ``seconds``, or a path whose heading turns by another
        multiple of ``2π`` than the goal asks (``θ`` is a real number).
    """
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    car = car_geometry(checker.system, checker)
    phi_g = car.phi_max - PHI_MARGIN
    radius = car.wheelbase / math.tan(phi_g)
    own = valid is None  # the model's own configurations are checked (not a stand-in's)
    if valid is None:
        # the margin unless the start or the goal lacks it (a car parked close to a wall)
        ends = np.array([[*q[:3], phi] for q in (x0, xg) for phi in (-phi_g, 0.0, phi_g)])
        margin = GUIDE_MARGIN if bool(np.all(checker.valid(ends, GUIDE_MARGIN))) else 0.0
        valid = functools.partial(checker.valid, extra_clearance=margin)
    is_valid = valid
    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    if seed is not None:
        ou.RNG.setSeed(int(seed) + 1)  # OMPL refuses seed 0
    space = ob.ReedsSheppStateSpace(radius)
    lo, hi = box(checker, x0, xg)
    bounds = ob.RealVectorBounds(2)
    for axis in range(2):
        bounds.setLow(axis, float(lo[axis]))
        bounds.setHigh(axis, float(hi[axis]))
    space.setBounds(bounds)
    si = ob.SpaceInformation(space)
    steer = np.array([-phi_g, 0.0, phi_g])

    def pose_valid(state: Any) -> bool:
        q = np.empty((3, 4))
        q[:, 0], q[:, 1], q[:, 2], q[:, 3] = state.getX(), state.getY(), state.getYaw(), steer
        return bool(np.all(is_valid(q)))

    si.setStateValidityChecker(pose_valid)
    step = min(resolution, CHECK_STEP)
    si.setStateValidityCheckingResolution(step / max(space.getMaximumExtent(), 1e-12))
    si.setup()
    start: Any = space.allocState()  # SE(2) states (the stubs say State)
    goal: Any = space.allocState()
    for st, q in ((start, x0), (goal, xg)):
        st.setX(float(q[0]))
        st.setY(float(q[1]))
        st.setYaw(float(q[2]))
    for what, st, q in (("start", start, x0), ("goal", goal, xg)):
        if not pose_valid(st):
            rows = np.array([[*q[:3], p] for p in steer])
            row = rows[int(np.flatnonzero(~is_valid(rows))[0])]
            why = (checker.why_invalid(row) or "it comes within the guide's margin "
                   f"{GUIDE_MARGIN:g} of an obstacle") if own else ""
            raise PlanningError(f"the {what}'s pose is not admissible for every steering angle "
                                f"|phi| <= {phi_g:.3g} of the Reeds-Shepp guide"
                                + (f" (at phi = {row[3]:.3g}, {why})" if why else ""))
    # grown from the tighter end (the path is reversible: a Reeds-Shepp curve driven
    # backwards is one; OMPL checks poses alone here)
    backward = bool(_clearance(checker, xg) < _clearance(checker, x0))
    pdef = ob.ProblemDefinition(si)
    pdef.setStartAndGoalStates(*((goal, start) if backward else (start, goal)))
    pdef.setOptimizationObjective(ob.PathLengthOptimizationObjective(si))
    planner = og.RRTstar(si)
    planner.setProblemDefinition(pdef)
    planner.setup()
    t0 = time.perf_counter()
    improve = min(IMPROVE_FRACTION * seconds, IMPROVE_SECONDS)
    try:
        history = anytime_solve(planner, pdef, seconds, improve,
                                f"a Reeds-Shepp path (radius {radius:.3g})", RESTART_SECONDS,
                                improve_by=IMPROVE_FRACTION * seconds)
        solution: Any = pdef.getSolutionPath()  # a geometric path (the stubs say Path)
        path: Any = og.PathGeometric(solution)
        simplifier = og.PathSimplifier(si)
        simplifier.simplify(path, float(min(SIMPLIFY_SECONDS, seconds)))
        if not path.check():  # OMPL's smoothing does not check every curve it makes
            path = og.PathGeometric(solution)
            simplifier.reduceVertices(path)  # each shortcut checked
        length = float(path.length())
        vertices = [path.getState(i) for i in range(path.getStateCount())]
        try:
            legs = [leg for a, b in itertools.pairwise(vertices)
                    for leg in edge_legs(edge_poses(space, a, b), radius,
                                         float(space.distance(a, b)))]
        except PlanningError:
            legs = None  # a curve not solved: its dense samples lifted instead
        path.interpolate(max(2, math.ceil(length / SAMPLE_STEP) + 1))
        poses = np.array([[s.getX(), s.getY(), s.getYaw()]
                          for s in (path.getState(i) for i in range(path.getStateCount()))])
        if backward:  # the same curves, driven from the start
            poses = poses[::-1]
            if legs is not None:
                legs = [Leg(leg.kappa, -leg.length) for leg in reversed(legs)]
    finally:
        # break the references between Python objects and OMPL's (no leak at exit)
        planner.clear()
        pdef.clearSolutionPaths()
        del planner, pdef
    if history and length < history[-1][1]:
        history.append((time.perf_counter() - t0, length))
    points = None
    if legs is not None:
        with contextlib.suppress(PlanningError):  # lift raises the heading's error again
            points = lift_legs(merge_legs(legs), x0, xg, car.wheelbase)
    if points is None:
        points = lift(poses, x0, xg, car.wheelbase, radius)
    return GuidePath(tuple(tuple(float(c) for c in p) for p in points), length,
                     tuple(history), radius)


def _clearance(checker: Checker, q: np.ndarray) -> float:
    """The clearance of the pose ``q[:3]`` with ``φ = 0`` (``+inf`` without a world)."""
    return float(checker.measures(np.array([[*np.asarray(q, float)[:3], 0.0]]))[0][0])


def edge_poses(space: Any, a: Any, b: Any, step: float = LEG_SAMPLE_STEP) -> np.ndarray:
    """Dense samples ``(N, 3)`` of the Reeds–Shepp curve from state ``a`` to ``b``, every
    ``step`` of arc length at most (default :data:`LEG_SAMPLE_STEP`)."""
    n = max(2, math.ceil(float(space.distance(a, b)) / step) + 1)
    out: Any = space.allocState()
    poses = np.empty((n, 3))
    for i, t in enumerate(np.linspace(0.0, 1.0, n)):
        space.interpolate(a, b, float(t), out)
        poses[i] = out.getX(), out.getY(), out.getYaw()
    return poses


def merge_legs(legs: Sequence[Leg]) -> list[Leg]:
    """Consecutive legs of the same curvature and direction of travel as one."""
    out: list[Leg] = []
    for leg in legs:
        if out and out[-1].kappa == leg.kappa and (out[-1].length > 0) == (leg.length > 0):
            out[-1] = Leg(leg.kappa, out[-1].length + leg.length)
        else:
            out.append(leg)
    return out


@dataclass(frozen=True)
class Leg:
    """One leg of a Reeds–Shepp path: curvature ``kappa`` (``0`` or ``±1/r``, positive to
    the left) driven for the signed arc length ``length`` (negative: backwards)."""

    kappa: float
    length: float


def leg_end(pose: Sequence[float] | np.ndarray, kappa: float, s: float) -> np.ndarray:
    """The pose ``(x, y, θ)`` reached from ``pose`` along an arc of curvature ``kappa``
    (a straight line when ``0``) after the signed arc length ``s`` (closed form; ``θ``
    is a real number, not reduced modulo ``2π``)."""
    x, y, th = (float(c) for c in pose)
    if kappa == 0.0:
        return np.array([x + s * math.cos(th), y + s * math.sin(th), th])
    end = th + kappa * s
    return np.array([x + (math.sin(end) - math.sin(th)) / kappa,
                     y - (math.cos(end) - math.cos(th)) / kappa, end])


def edge_legs(poses: np.ndarray, radius: float, length: float | None = None) -> list[Leg]:
    """The legs of one Reeds–Shepp curve from its dense samples ``poses (N, 3)`` (yaw modulo
    ``2π``, first and last the curve's ends), with their lengths solved exactly.

    Each step between samples whose curvature ``κ r ∈ {−1, 0, 1}`` and direction of travel
    are clear (within :data:`CLEAN_TOL`; a step across a switch or a cusp mixes two legs and
    is left out) is classified; runs of one class are the legs, their summed steps the
    first guess of their lengths.  The lengths are then corrected by least-norm
    Gauss–Newton so that the legs, driven in closed form (:func:`leg_end`) from the first
    pose, end at the last one (``≤`` :data:`LEG_TOL`).  Two structures are tried: with
    every run, and without the runs of one step (a mixed step that looked clear); if
    neither converges with lengths of the classified signs, each class of leg in place of
    each mixed step (a leg shorter than two steps).  The shortest solution is kept.
    OMPL's Python bindings expose a Reeds–Shepp curve's length but not its type or its
    legs' lengths, hence the classification.

    ``length``: the curve's length (OMPL's ``distance``), when given the legs' total
    ``|length|`` must be within :data:`LEG_LENGTH_TOL` of it (the same curve, up to a leg
    shorter than a step).

    Raises
    ------
    PlanningError
        No structure converges within ``length`` (the caller keeps the sampled path).
    """
    d = np.diff(poses[:, :2], axis=0)
    dyaw = np.angle(np.exp(1j * np.diff(poses[:, 2])))
    ds = np.linalg.norm(d, axis=1)
    along = d[:, 0] * np.cos(poses[:-1, 2]) + d[:, 1] * np.sin(poses[:-1, 2])
    sign = np.where(along >= 0, 1.0, -1.0)
    moving = ds > 1e-12
    with np.errstate(divide="ignore", invalid="ignore"):
        turn = np.where(moving, dyaw * radius / (sign * ds), np.nan)
        clean = (moving & (np.abs(turn - np.rint(turn)) <= CLEAN_TOL)
                 & (np.abs(turn) <= 1 + CLEAN_TOL) & (np.abs(along) >= (1 - CLEAN_TOL) * ds))
    steps = {int(i): (float(np.rint(turn[i])), float(sign[i]), float(ds[i]))
             for i in np.flatnonzero(clean)}
    if not np.any(moving):
        return []
    found: list[list[Leg]] = []
    tried: list[list[tuple[float, float]]] = []

    def attempt(classified: dict[int, tuple[float, float, float]], drop_single: bool) -> None:
        runs = _runs([classified[i] for i in sorted(classified)], drop_single)
        if runs and [r[:2] for r in runs] not in tried:
            tried.append([r[:2] for r in runs])
            legs = _solve_legs(runs, radius, poses[0], poses[-1])
            if legs is not None and (length is None or sum(abs(leg.length) for leg in legs)
                                     <= length + LEG_LENGTH_TOL):
                found.append(legs)

    for drop_single in (False, True):
        attempt(steps, drop_single)
    if not found:
        # a leg shorter than two steps can hide in a mixed step: try each class there
        for i in np.flatnonzero(moving & ~clean):
            for k, direction in itertools.product((-1.0, 0.0, 1.0), (-1.0, 1.0)):
                attempt({**steps, int(i): (k, direction, 0.5 * float(ds[i]))}, False)
    if not found:
        raise PlanningError("a Reeds-Shepp curve's legs could not be solved from its samples")
    return min(found, key=lambda legs: sum(abs(leg.length) for leg in legs))


def _runs(steps: Sequence[tuple[float, float, float]], drop_single: bool
          ) -> list[tuple[float, float, float]]:
    """``(κ r, direction, length)`` of the runs of classified steps ``(κ r, direction, ds)``
    (without the runs of one step if ``drop_single`` and more than one run)."""
    runs: list[list[float]] = []  # [turn, sign, length, steps]
    for turn, sign, ds in steps:
        if runs and runs[-1][0] == turn and runs[-1][1] == sign:
            runs[-1][2] += ds
            runs[-1][3] += 1
        else:
            runs.append([turn, sign, ds, 1])
    if drop_single and len(runs) > 1:
        runs = [r for r in runs if r[3] > 1]
    merged: list[list[float]] = []
    for r in runs:
        if merged and merged[-1][:2] == r[:2]:
            merged[-1][2] += r[2]
        else:
            merged.append(r)
    return [(r[0], r[1], r[2]) for r in merged]


def _solve_legs(runs: Sequence[tuple[float, float, float]], radius: float, start: np.ndarray,
                target: np.ndarray) -> list[Leg] | None:
    """The legs of ``runs`` (:func:`_runs`) with their lengths corrected by Gauss–Newton to
    end at ``target`` from ``start`` (``None``: no convergence, or a length of the wrong
    sign)."""
    kappa = np.array([r[0] / radius for r in runs])
    direction = np.array([r[1] for r in runs])
    lengths = np.array([r[2] for r in runs])

    def residual(ls: np.ndarray) -> np.ndarray:
        q = start
        for k, s in zip(kappa, direction * ls, strict=True):
            q = leg_end(q, float(k), float(s))
        r = q - target
        r[2] = math.remainder(float(r[2]), 2 * math.pi)
        return r

    for _ in range(LEG_ITERATIONS):
        r = residual(lengths)
        if float(np.abs(r).max()) <= LEG_TOL:
            break
        jac = np.empty((3, len(lengths)))
        for j in range(len(lengths)):
            h = np.zeros(len(lengths))
            h[j] = 1e-7
            jac[:, j] = (residual(lengths + h) - r) / 1e-7
        lengths = lengths - np.linalg.lstsq(jac, r, rcond=None)[0]
    if not (float(np.abs(residual(lengths)).max()) <= LEG_TOL and np.all(lengths > -LEG_TOL)):
        return None
    return [Leg(float(k), float(s)) for k, s in zip(kappa, direction * np.maximum(lengths, 0.0),
                                                    strict=True) if abs(s) > LEG_TOL]


def lift_legs(legs: Sequence[Leg], x0: np.ndarray, xg: np.ndarray, wheelbase: float
              ) -> list[np.ndarray]:
    """Waypoints ``(x, y, θ, φ)`` of the legs driven from ``x0`` (module doc, step 2).

    Along a leg of curvature ``κ``, ``φ = atan(L κ)``; waypoints every
    :data:`WAYPOINT_STEP` of arc length, on the leg (closed form); between legs of
    different ``κ``, waypoints at the same pose turning ``φ`` to the new value in steps of
    at most :data:`PHI_STEP` (the wheels turned at rest).  The last waypoint is ``xg``
    (its ``φ`` reached at rest).

    Raises
    ------
    PlanningError
        The legs do not end at ``xg``'s pose (within :data:`LEG_END_TOL`; or the heading
        turned by another multiple of ``2π`` than ``xg`` asks: headings are real numbers).
    """
    out = [np.asarray(x0, dtype=float).copy()]
    for leg in legs:
        phi = math.atan(wheelbase * leg.kappa)
        _turn(out, phi)
        pose = out[-1][:3]
        k = max(1, math.ceil(abs(leg.length) / WAYPOINT_STEP - 1e-9))
        for j in range(1, k + 1):
            out.append(np.array([*leg_end(pose, leg.kappa, leg.length * j / k), phi]))
    end = np.asarray(xg, dtype=float)
    miss = out[-1][:3] - end[:3]
    if abs(float(miss[2])) > 1e-3:
        raise PlanningError(
            f"the Reeds-Shepp path turns the heading by {out[-1][2] - x0[2]:.4g}, the goal "
            f"asks for {xg[2] - x0[2]:.4g} (headings are real numbers, not angles modulo 2 pi)")
    if float(np.abs(miss).max()) > LEG_END_TOL:
        raise PlanningError(f"the Reeds-Shepp legs end {float(np.abs(miss).max()):.3g} from "
                            "the goal's pose")
    if len(out) > 1:
        out[-1][:3] = end[:3]  # the legs end at the goal's pose up to rounding
    _turn(out, float(end[3]))
    out[-1] = end.copy()
    return out


def lift(poses: np.ndarray, x0: np.ndarray, xg: np.ndarray, wheelbase: float,
         radius: float) -> list[np.ndarray]:
    """Waypoints ``(x, y, θ, φ)`` of a Reeds–Shepp path sampled densely: the fallback of
    :func:`lift_legs` when a curve's legs cannot be solved (module doc, step 2).

    ``poses (N, 3)``: ``(x, y, yaw)`` along the path (yaw modulo ``2π``), from ``x0``'s pose
    to ``xg``'s; ``radius``: the path's turning radius.  The first waypoint is ``x0``, the
    last ``xg`` (their ``φ`` reached by turning the wheels at rest).

    Raises
    ------
    PlanningError
        The unwrapped heading does not end at ``xg``'s ``θ`` (another turn of ``2π``).
    """
    d = np.diff(poses[:, :2], axis=0)
    dyaw = np.angle(np.exp(1j * np.diff(poses[:, 2])))
    theta = float(x0[2]) + np.concatenate(([0.0], np.cumsum(dyaw)))
    if abs(theta[-1] - float(xg[2])) > 1e-3:
        raise PlanningError(
            f"the Reeds-Shepp path turns the heading by {theta[-1] - x0[2]:.4g}, the goal asks "
            f"for {xg[2] - x0[2]:.4g} (headings are real numbers, not angles modulo 2 pi)")
    ds = np.linalg.norm(d, axis=1)
    along = d[:, 0] * np.cos(theta[:-1]) + d[:, 1] * np.sin(theta[:-1])
    moving = ds > 1e-9
    sign = np.where(along >= 0, 1, -1)
    with np.errstate(divide="ignore", invalid="ignore"):
        turn = np.rint(np.where(moving, dyaw * radius / (sign * ds), 0.0)).clip(-1, 1)
    phis = np.arctan(wheelbase * turn / radius)
    pts = np.column_stack([poses[:, 0], poses[:, 1], theta])
    out = [np.asarray(x0, dtype=float).copy()]

    def add(i: int, phi: float) -> None:
        q = np.array([*pts[i], phi])
        if float(np.linalg.norm(q[:3] - out[-1][:3])) <= 1e-9:
            _turn(out, phi)
        elif float(np.linalg.norm(q - out[-1])) > 1e-9:
            out.append(q)

    legs = [i for i in range(len(ds)) if moving[i]]
    since = 0.0
    for k, i in enumerate(legs):
        phi = float(phis[i])
        if k == 0 or (turn[i], sign[i]) != (turn[legs[k - 1]], sign[legs[k - 1]]):
            add(i, phi)  # the start of a leg: the wheels turned at rest, if needed
            since = 0.0
        since += float(ds[i])
        last = k == len(legs) - 1 or (turn[legs[k + 1]], sign[legs[k + 1]]) != (turn[i], sign[i])
        if since >= WAYPOINT_STEP or last:
            add(i + 1, phi)
            since = 0.0
    end = np.asarray(xg, dtype=float)
    if len(out) > 1:
        out[-1][:3] = end[:3]  # the sampled end is the goal's pose up to rounding
    _turn(out, float(end[3]))
    out[-1] = end.copy()
    return out


def _turn(out: list[np.ndarray], phi: float) -> None:
    """Append to ``out`` the wheels turning at rest from its last ``φ`` to ``phi``, in steps
    of at most :data:`PHI_STEP`."""
    q = out[-1]
    k = math.ceil(abs(phi - float(q[3])) / PHI_STEP - 1e-9)
    for j in range(1, k + 1):
        out.append(np.array([*q[:3], float(q[3]) + (phi - float(q[3])) * j / k]))


#: Largest change of the pose (x, y, θ) between two waypoints of one turn at rest.
AT_REST = 1e-9


def exact_piece(checker: Checker, x: np.ndarray, prev: np.ndarray, w: np.ndarray,
                tol: float, points: int, wheelbase: float) -> Any:
    """The car's exact motion between two consecutive lifted waypoints, if it lands within
    ``tol`` of ``w`` and is admissible; else ``None`` (the piece is then steered).

    Between waypoints ``prev`` and ``w`` of :func:`lift` the car either turns its wheels
    at rest (same pose: ``u = (0, Δφ)`` for a unit time) or drives one leg with ``φ``
    fixed (``u = (s, 0)``, ``s`` the signed arc length: ``Δθ / κ`` on an arc of curvature
    ``κ = tan φ / L``, the displacement along the heading on a straight leg), from the
    state ``x`` reached so far.  These are the Reeds–Shepp path's own motions, so no
    steering manoeuvre is added (steering a straight piece of 0.26 drove 0.41 with 5
    reversals).  ``wheelbase``: ``L`` of the car-like model (:func:`car_geometry`, computed
    once per plan).  Returns a :class:`~nilpotent.planning.iterative.Plan` of the piece.
    """
    from nilpotent.errors import IntegrationError
    from nilpotent.planning.controls import constant_segment
    from nilpotent.planning.iterative import Plan
    from nilpotent.planning.simulation import simulate_path
    from nilpotent.simulation.trajectory import Trajectory

    system = checker.system
    d = w - prev
    if float(np.abs(d[:3]).max()) <= AT_REST:
        u = (0.0, float(w[3] - x[3]))
        # φ is linear in time (the limit's cover is exact), the wheels' outline turns on
        # arcs: steps of at most PHI_MARGIN keep that cover small
        points = max(points, math.ceil(abs(u[1]) / PHI_MARGIN) + 1)
    elif abs(float(d[3])) <= AT_REST:
        kappa = math.tan(float(prev[3])) / wheelbase
        if abs(kappa) > 1e-12:
            s = float(d[2]) / kappa
        else:
            s = float(d[0] * math.cos(prev[2]) + d[1] * math.sin(prev[2]))
        if not math.isfinite(s) or abs(s) < 0.5 * float(np.hypot(d[0], d[1])):
            return None  # not one leg (e.g. a halved piece across a switch)
        u = (s, 0.0)
        # samples every EXACT_STEP of arc length: the motion check's cover between them
        # stays within the guide's margin (GUIDE_MARGIN)
        points = max(points, math.ceil(abs(s) / EXACT_STEP) + 1)
    else:
        return None
    segs = (constant_segment(np.array(u), 1.0),)
    try:
        times, states = simulate_path(system, x, segs, points)
    except IntegrationError:
        return None
    error = float(np.linalg.norm(states[-1] - w))
    if not (error <= tol and checker.valid_motion(states)):
        return None
    return Plan(system, tuple(map(float, x)), tuple(map(float, w)), segs,
                tuple(map(float, states[-1])), error, (), Trajectory(times, states), tol=tol,
                initial_error=float(np.linalg.norm(w - x)))
