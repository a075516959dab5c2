r"""The Reeds–Shepp guide for a car pulling one trailer (``planner="reeds-shepp"``).

For ``car-trailers:1`` (coordinates ``x, y, θ0, θ1``; fields
``X1 = cos θ0 ∂x + sin θ0 ∂y + sin(θ0 − θ1)/d ∂θ1``, ``X2 = ∂θ0``) the **trailer is a
kinematic car**: its axle centre ``P1 = (x, y) − d (cos θ1, sin θ1)`` moves along
``(cos θ1, sin θ1)`` at the speed ``v1 = u1 cos φ`` and turns at
``θ̇1 = u1 sin φ / d = v1 tan φ / d``, with ``φ = θ0 − θ1`` the hitch angle in the role
of the steering angle and ``d`` in that of the wheelbase; and ``φ̇ = u2 − θ̇1``.  So
``(x1, y1, θ1, φ)`` (:func:`to_car`, :func:`from_car`) are the coordinates of the car of
:mod:`nilpotent.planning.guide`, with the hitch limit ``|φ| ≤ φ_max`` (1.4 rad for the
built-in model) as its steering limit, and the car's guide applies to the trailer as it
is: Reeds–Shepp paths of the trailer's pose, of radius ``d / tan φ_g``.  Its two motions
are exact motions of the true system:

* a **leg** of curvature ``κ = tan φ / d`` (``φ`` fixed) driven for the trailer's signed
  arc length ``s1``: the car drives ``s0 = s1 / cos φ`` with the constant controls
  ``u = (s0, s0 sin φ / d)`` for a unit time (``θ̇0 = θ̇1`` keeps ``φ``);
* a **turn at rest**: ``u = (0, Δφ)``, the car turning on the spot about its axle centre,
  the trailer still.

:func:`trailer_guide_path` takes the Reeds–Shepp curve from the start to the goal when it is
admitted, else searches with OMPL RRTConnect (two trees: the goal's grows out of a
parking slot, where RRT*'s one tree took 16 s to over 43 s for a first path on a loaded
machine), grown anew for :data:`TRAILER_IMPROVE_SECONDS` after the first path, the
shortest lifted path kept, in the trailer's Reeds–Shepp poses
``(x1, y1, θ1)`` **and hitch angles** ``φ`` (a compound space, ``|Δφ|`` weighted by
:data:`PHI_WEIGHT`): a state is valid when its configuration is, under the checker with the
guide's margin (none when the start or the goal lacks it); a curve between two states
(:func:`_validator`) is the car turning at rest from the first state's ``φ`` to its first
leg's, its legs (solved as the lifting solves them,
:func:`~nilpotent.planning.guide.edge_legs`) each at its hitch angle with turns at rest
between them, and a turn at rest to the second state's ``φ``, every configuration checked
with the cover of its steps (:func:`motion_pieces`).  A vertex's hitch angle is thus what
its curves need, not a fixed ``φ = 0`` (then every vertex demanded a turn at rest to and
from ``0``: in the parking slot, where the car cannot swing towards the curb, no right
turn could end or start there and the search stalled); the lifted path turns at a vertex
from one curve's last hitch angle straight to the next one's first, within the two turns
checked through the vertex's own angle.  OMPL's simplifier cuts curves at new vertices
whose turns it never passes to the validator, so the simplified path is kept only if the
whole lifted motion passes the check in the exact pieces' steps (:func:`_lifted`), else
the path with its vertices reduced (every curve checked), else the search's own.  The
waypoints are mapped back to the model's coordinates; :func:`trailer_exact_piece` drives
a piece between two of them exactly (else the piece is steered by the nilpotent steering,
as for any path).  ``car-trailers:2`` and more are not covered (their relative angles
cannot all be held on a Reeds–Shepp arc entered at rest).
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.core.model.outline import Limits
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import OptionError, PlanningError
from nilpotent.planning import budget
from nilpotent.planning.guide import (
    GUIDE_MARGIN,
    IMPROVE_FRACTION,
    PHI_MARGIN,
    GuidePath,
    Leg,
    edge_legs,
    edge_poses,
    leg_end,
    lift_legs,
    merge_legs,
)
from nilpotent.planning.holonomic_path import (
    SIMPLIFY_SECONDS,
    SLICE_SECONDS,
    box,
)
from nilpotent.planning.verify import Checker

__all__ = [
    "TRAILER_COORDINATES", "TRAILER_PHI", "TrailerGeometry", "from_car", "motion_pieces",
    "to_car", "trailer_exact_piece", "trailer_geometry", "trailer_guide_path",
]

#: Coordinates of a one-trailer model, in order.
TRAILER_COORDINATES = ("x", "y", "theta0", "theta1")
#: The guide's hitch angle ``φ_g`` (rad) on its arcs, at most the hitch limit less
#: ``PHI_MARGIN``: the trailer's turning radius is ``d / tan φ_g``.
TRAILER_PHI = 1.2
#: Largest arc length of the trailer between the samples of an exact leg.
EXACT_STEP = 0.002


@dataclass(frozen=True)
class TrailerGeometry:
    """What the trailer guide needs of a one-trailer model.

    Attributes
    ----------
    hitch:
        ``d``, the hitch length (car's axle centre to the trailer's).
    phi_max:
        The hitch limit used, ``|θ0 − θ1| ≤ phi_max``.
    """

    hitch: float
    phi_max: float

    @property
    def phi_guide(self) -> float:
        """The guide's hitch angle on its arcs, ``min(TRAILER_PHI, phi_max − PHI_MARGIN)``."""
        return min(TRAILER_PHI, self.phi_max - PHI_MARGIN)

    @property
    def radius(self) -> float:
        """The trailer's turning radius on the guide's arcs, ``d / tan φ_g``."""
        return self.hitch / math.tan(self.phi_guide)


def trailer_geometry(system: ControlSystem, checker: Checker) -> TrailerGeometry:
    """The hitch length and limit of a one-trailer model (module doc), with the limits of
    ``checker``.

    Raises
    ------
    OptionError
        The model is not ``car-trailers:1``-like, or has no hitch limit below ``π/2``.
    """
    why = _not_trailer_like(system)
    if why:
        raise OptionError(
            "--planner reeds-shepp needs a car-like model, a car with one trailer "
            "(coordinates x, y, theta0, theta1, e.g. car-trailers:1) or the built-in "
            f"car-trailers:2: model {system.name} {why}")
    th0, th1 = system.coordinates[2:]
    hitch = float(sp.simplify(sp.sin(th0 - th1) / system.specialized_fields[0][3]))
    assert checker.limits is not None
    lo, hi = -math.inf, math.inf
    for name in (b[0] for b in checker.limits.bounds):
        if name in ("theta0", "theta1"):
            raise OptionError(f"--planner reeds-shepp: the trailer guide takes no limit on "
                              f"{name} (only on theta0 - theta1)")
    # linear relative limits are normalised where they are made (Limits): every form of the
    # hitch angle (2*theta0 - 2*theta1, theta1 - theta0, ...) is theta0 - theta1 here
    other = []
    for label, expr, lo_r, hi_r in checker.limits.relative:
        if sp.expand(expr - (th0 - th1)) == 0:
            lo, hi = max(lo, lo_r), min(hi, hi_r)
        elif expr.free_symbols & {th0, th1}:
            other.append(label)
    phi_max = min(-lo, hi)
    if not (PHI_MARGIN < phi_max < math.pi / 2):
        unread = (f" (the guide reads the hitch limit only from a linear one, a*(theta0 - "
                  f"theta1) + b; not from {', '.join(map(repr, other))})" if other else "")
        raise OptionError(
            f"--planner reeds-shepp needs a hitch limit |theta0 - theta1| <= phi_max with "
            f"{PHI_MARGIN:g} < phi_max < pi/2; "
            f"model {system.name} has theta0 - theta1 in [{lo:g}, {hi:g}]{unread}")
    return TrailerGeometry(hitch, phi_max)


def is_trailer_like(system: ControlSystem) -> bool:
    """Whether ``system`` is a car with one trailer (module doc)."""
    return not _not_trailer_like(system)


def _not_trailer_like(system: ControlSystem) -> str:
    """Why ``system`` is not a car with one trailer ('' when it is)."""
    if system.coordinate_names != TRAILER_COORDINATES:
        return f"has coordinates {', '.join(system.coordinate_names)}"
    if system.m != 2:
        return f"has {system.m} fields, not 2"
    _, _, th0, th1 = system.coordinates
    drive, steer = system.specialized_fields
    if tuple(steer) != (0, 0, 1, 0):
        return "has a second field other than d/dtheta0"
    ratio = sp.simplify(sp.sin(th0 - th1) / drive[3]) if drive[3] != 0 else sp.nan
    if (sp.simplify(drive[0] - sp.cos(th0)) != 0 or sp.simplify(drive[1] - sp.sin(th0)) != 0
            or drive[2] != 0 or not ratio.is_number or not bool(ratio > 0)):
        return ("has a first field other than cos(theta0), sin(theta0), 0, "
                "sin(theta0 - theta1)/d (d > 0)")
    return ""


def to_car(q: np.ndarray, hitch: float) -> np.ndarray:
    """Model coordinates ``(x, y, θ0, θ1)`` (``(..., 4)``) to the trailer's car coordinates
    ``(x1, y1, θ1, φ = θ0 − θ1)``."""
    q = np.asarray(q, dtype=float)
    x, y, th0, th1 = np.moveaxis(q, -1, 0)
    return np.stack([x - hitch * np.cos(th1), y - hitch * np.sin(th1), th1, th0 - th1],
                    axis=-1)


def from_car(s: np.ndarray, hitch: float) -> np.ndarray:
    """The inverse of :func:`to_car`."""
    s = np.asarray(s, dtype=float)
    x1, y1, th1, phi = np.moveaxis(s, -1, 0)
    return np.stack([x1 + hitch * np.cos(th1), y1 + hitch * np.sin(th1), th1 + phi, th1],
                    axis=-1)


def _stand_in(checker: Checker, geometry: TrailerGeometry) -> Checker:
    """A checker of the built-in car with wheelbase ``d`` and steering limit
    ``φ_g + PHI_MARGIN``, in the world of ``checker``: what
    :func:`~nilpotent.planning.holonomic_path.box` reads (the coordinates' names, the
    world's bounds) for the trailer's axle; its validity is never used."""
    from nilpotent.models import get_model

    car = get_model("car", {"L": sp.Float(geometry.hitch), "rmin": sp.Float(geometry.radius)})
    limit = geometry.phi_guide + PHI_MARGIN
    return Checker(car, checker.world, Limits((("phi", -limit, limit),)))


#: Steps of the validator's motion check (:func:`motion_pieces`): arc length of the trailer
#: between the poses of a leg, hitch angle (rad) between the configurations of a turn at
#: rest.  Each piece is checked with the cover of :meth:`~nilpotent.planning.verify.Checker.
#: valid_motion` (half the largest step of an outline point) on top of the guide's margin.
MOTION_STEP = 0.01
SWEEP_STEP = 0.02
#: Steps of the final check of the whole lifted path, as fine as the exact pieces'
#: (:func:`trailer_exact_piece`: :data:`EXACT_STEP` of the trailer's arc, the turns at rest
#: in steps of ``PHI_MARGIN``).
FINAL_SWEEP_STEP = PHI_MARGIN
#: Arc length between the samples of a curve whose legs are solved (validator and lifting
#: alike, so that both drive the same legs; five times the car guide's
#: ``LEG_SAMPLE_STEP``: the samples cost most of a motion check, and a leg shorter than a
#: step is still found by :func:`~nilpotent.planning.guide.edge_legs`, else the curve is
#: refused).
LEG_STEP = 0.01
#: Seconds (at most ``IMPROVE_FRACTION`` of the search's) of new RRTConnect trees after the
#: first path, the shortest lifted path kept: the exact pieces of a path (about 200
#: waypoints in the parking slot) take 10-20 s more to drive and verify on a loaded machine
#: (benchmarks/RESULTS.md, 60 s per query).
TRAILER_IMPROVE_SECONDS = 10.0
#: Weight of the hitch angle's change (length units per rad) in the distance between two
#: OMPL states (Reeds–Shepp length of the trailer ``+ PHI_WEIGHT |Δφ|``; the trees' nearest
#: neighbours).
PHI_WEIGHT = 0.1


def motion_pieces(pose: Sequence[float] | np.ndarray, legs: Sequence[Leg], phi_from: float,
                  phi_to: float, hitch: float, step: float = MOTION_STEP,
                  sweep: float = SWEEP_STEP) -> list[np.ndarray]:
    """The configurations ``(x1, y1, θ1, φ)`` driven along ``legs`` from the trailer's
    ``pose (3,)`` with the hitch angle ``phi_from``, ending with ``phi_to``: before each leg
    a turn at rest from the hitch angle held to the leg's ``atan(d κ)`` (``d = hitch``; the
    angle :func:`~nilpotent.planning.guide.lift_legs` gives it), the leg's poses at that
    angle (closed form), and a turn at rest to ``phi_to`` after the last one.

    Returns the pieces, each ``(N_i, 4)``: a turn at rest sampled every ``sweep`` of ``φ``
    at most, a leg every ``step`` of arc length of the trailer at most, both ends included
    (consecutive pieces share their ends); a turn by no angle is left out; with no leg and
    no turn, one piece of the one configuration.
    """
    pieces: list[np.ndarray] = []
    here = np.asarray(pose, dtype=float)[:3]
    phi = float(phi_from)

    def turn(to: float) -> None:
        if to != phi:
            k = max(1, math.ceil(abs(to - phi) / sweep))
            pieces.append(np.array([(*here, float(p)) for p in np.linspace(phi, to, k + 1)]))

    for leg in legs:
        new = math.atan(hitch * leg.kappa)
        turn(new)
        phi = new
        k = max(1, math.ceil(abs(leg.length) / step))
        pieces.append(_arc(here, leg.kappa, np.linspace(0.0, leg.length, k + 1), phi))
        here = leg_end(here, leg.kappa, leg.length)
    turn(float(phi_to))
    return pieces or [np.array([(*here, phi)])]


def _arc(pose: np.ndarray, kappa: float, s: np.ndarray, phi: float) -> np.ndarray:
    """``(len(s), 4)``: the poses of :func:`~nilpotent.planning.guide.leg_end` from ``pose``
    after the arc lengths ``s`` (its closed form on an array), with the hitch angle ``phi``."""
    x, y, th = (float(c) for c in pose)
    if kappa == 0.0:
        return np.column_stack([x + s * math.cos(th), y + s * math.sin(th), np.full_like(s, th),
                                np.full_like(s, phi)])
    end = th + kappa * s
    return np.column_stack([x + (np.sin(end) - math.sin(th)) / kappa,
                            y - (np.cos(end) - math.cos(th)) / kappa, end, np.full_like(s, phi)])


def _admitted(checker: Checker, hitch: float, pieces: Sequence[np.ndarray]) -> bool:
    """Whether the motion of :func:`motion_pieces` is admissible under ``checker`` with the
    cover of its largest step (:meth:`~nilpotent.planning.verify.Checker.valid_motion` on
    the pieces joined; every :data:`PRECHECK`-th configuration checked first, without the
    cover: most rejected motions are rejected there, at a fraction of the cost)."""
    q = from_car(np.concatenate(pieces), hitch)
    return bool(np.all(checker.valid(q[::PRECHECK]))) and checker.valid_motion(q)


#: Stride of the quick check of :func:`_admitted`.
PRECHECK = 8


def trailer_guide_path(
    checker: Checker,
    x0: np.ndarray,
    xg: np.ndarray,
    seconds: float,
    seed: int | None = None,
    resolution: float = 0.05,
    valid: Callable[[np.ndarray], np.ndarray] | None = None,
    held: Sequence[int] = (),
) -> GuidePath:
    """The Reeds–Shepp guide of the trailer from ``x0`` to ``xg`` (module doc), its points
    in the model's coordinates.

    Parameters as :func:`~nilpotent.planning.guide.guide_path` (``seconds``: the search's
    budget, new trees grown after the first path for ``IMPROVE_FRACTION`` of it, at most
    :data:`TRAILER_IMPROVE_SECONDS`); ``resolution``, ``valid`` and ``held`` are ignored
    (the checker's validity with the guide's margin, none when the start or the goal lacks
    it; each curve checked as :func:`_validator`, the whole path as :func:`_lifted`).

    Returns the waypoints (the model's coordinates, ``x0`` and ``xg`` included), the
    trailer's Reeds–Shepp length (the legs' arc lengths summed), ``(seconds, length)`` of
    each shorter lifted path found, and the trailer's turning radius ``d / tan φ_g``.

    Raises
    ------
    OptionError
        The model is not a car with one trailer.
    PlanningError
        No path within ``seconds``; a path turning the heading by another multiple of
        ``2π`` than the goal asks; or, at once, the start's or the goal's trailer pose
        admits no turn of the car at rest to ``+φ_g`` nor to ``−φ_g`` (unless one straight
        leg joins the start to the goal: :func:`_straight_between`).
    """
    del resolution, valid, held
    geometry = trailer_geometry(checker.system, checker)
    d, phi_g = geometry.hitch, geometry.phi_guide
    s0, sg = to_car(x0, d), to_car(xg, d)
    # the guide's margin unless the start or the goal lacks it
    ends = np.array([x0, xg], dtype=float)
    margin = GUIDE_MARGIN if bool(np.all(checker.valid(ends, GUIDE_MARGIN))) else 0.0
    kept = dataclasses.replace(checker, clearance=checker.clearance + margin)
    admitted = functools.partial(_admitted, kept, d)
    for what, s in (("start", s0), ("goal", sg)):
        # with neither turn admissible, only a straight leg exactly on the pose's axis
        # leaves it, and OMPL would search the whole time
        turns = [motion_pieces(s[:3], [], float(s[3]), sign * phi_g, d) for sign in (1, -1)]
        if not any(admitted(t) for t in turns) and not _straight_between(admitted, d, s0, sg):
            raise PlanningError(
                f"the {what}'s trailer pose admits no turn of the car at rest to the hitch "
                f"angle +-{phi_g:.3g} of the trailer guide ("
                + "; ".join(_turn_failure(checker, kept, d, margin, t) for t in turns)
                + "): the guide's curves cannot start or end there")
    return _search(checker, kept, geometry, s0, sg, seconds, seed, (x0, xg))


def _search(checker: Checker, kept: Checker, geometry: TrailerGeometry, s0: np.ndarray,
            sg: np.ndarray, seconds: float, seed: int | None,
            ends: tuple[np.ndarray, np.ndarray]) -> GuidePath:
    """The direct curve, else OMPL RRTConnect, in the trailer's Reeds–Shepp poses and hitch
    angles (module doc), each path simplified and lifted (:func:`_simplified`)."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    d, radius = geometry.hitch, geometry.radius
    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    if seed is not None:
        ou.RNG.setSeed(int(seed) + 1)  # OMPL refuses seed 0
    poses = ob.ReedsSheppStateSpace(radius)
    lo, hi = box(_stand_in(checker, geometry), s0, sg)
    bounds = ob.RealVectorBounds(2)
    for axis in range(2):
        bounds.setLow(axis, float(lo[axis]))
        bounds.setHigh(axis, float(hi[axis]))
    poses.setBounds(bounds)
    angles = ob.RealVectorStateSpace(1)
    reach = max(geometry.phi_guide, abs(float(s0[3])), abs(float(sg[3])))
    angle_bounds = ob.RealVectorBounds(1)
    angle_bounds.setLow(-reach)
    angle_bounds.setHigh(reach)
    angles.setBounds(angle_bounds)
    space = ob.CompoundStateSpace()
    space.addSubspace(poses, 1.0)
    space.addSubspace(angles, PHI_WEIGHT)
    si = ob.SpaceInformation(space)

    def state_valid(state: Any) -> bool:
        pose = state[0]
        q = np.array([[pose.getX(), pose.getY(), pose.getYaw(), state[1][0]]])
        return bool(kept.valid(from_car(q, d))[0])

    si.setStateValidityChecker(state_valid)
    si.setMotionValidator(_validator(kept, d, radius, poses, si))
    si.setup()
    start: Any = space.allocState()  # compound states (the stubs say State)
    goal: Any = space.allocState()
    for st, s in ((start, s0), (goal, sg)):
        st[0].setX(float(s[0]))
        st[0].setY(float(s[1]))
        st[0].setYaw(float(s[2]))
        st[1][0] = float(s[3])
    what = f"a Reeds-Shepp path of the trailer (radius {radius:.3g})"
    lift = functools.partial(_lifted, checker, d, radius, poses, s0=s0, sg=sg)
    pdef = ob.ProblemDefinition(si)
    pdef.setStartAndGoalStates(start, goal)
    planner = og.RRTConnect(si)
    planner.setProblemDefinition(pdef)
    planner.setup()
    improve = min(IMPROVE_FRACTION * seconds, TRAILER_IMPROVE_SECONDS)
    found: list[tuple[list[np.ndarray], float]] = []
    history: list[tuple[float, float]] = []
    t0 = time.perf_counter()
    first: float | None = None
    rejected = 0
    try:
        # the Reeds-Shepp curve from the start to the goal, when admitted, is the shortest;
        # else two trees (the goal's grows out of the parking slot), grown anew after each
        # path for the improvement time: the shortest lifted path is kept
        direct = lift([start, goal]) if si.checkMotion(start, goal) else None
        if direct is not None:
            found.append(direct)
            history.append((time.perf_counter() - t0, direct[1]))
        while direct is None:
            spent = time.perf_counter() - t0
            end = seconds if first is None else min(seconds, first + improve)
            try:
                _first_path(planner, pdef, end - spent, what)
            except PlanningError as e:
                if first is None:
                    raise PlanningError(f"{e} ({rejected} failed the final motion check)"
                                        if rejected else str(e)) from None
                break
            best = min((f[1] for f in found), default=math.inf)
            solution: Any = pdef.getSolutionPath()  # a geometric path (the stubs say Path)
            lifted = _simplified(si, og.PathGeometric(solution), seconds, lift,
                                 lambda v, best=best: _length(poses, v) < best)
            planner.clear()
            pdef.clearSolutionPaths()
            if lifted is None:
                rejected += not found  # not expected: every curve passed the validator
                continue
            first = time.perf_counter() - t0 if first is None else first
            if not found or lifted[1] < min(f[1] for f in found):
                history.append((time.perf_counter() - t0, lifted[1]))
            found.append(lifted)
    finally:
        # break the references between Python objects and OMPL's (no leak at exit)
        planner.clear()
        pdef.clearSolutionPaths()
        del planner, pdef
    points, length = min(found, key=lambda f: f[1])
    out = [from_car(np.array(p), d) for p in points]
    out[0], out[-1] = np.asarray(ends[0], dtype=float), np.asarray(ends[1], dtype=float)
    return GuidePath(tuple(tuple(float(c) for c in p) for p in out), length,
                     tuple(history), radius)


def _first_path(planner: Any, pdef: Any, seconds: float, what: str) -> None:
    """Run ``planner`` (RRTConnect) in slices of ``SLICE_SECONDS`` until an exact solution
    (the budget in force checked before each slice).

    Raises
    ------
    PlanningError
        None within ``seconds``.
    """
    t0 = time.perf_counter()
    while not pdef.hasExactSolution():
        left = seconds - (time.perf_counter() - t0)
        if left <= 0:
            raise PlanningError(
                f"no collision-free {what.removeprefix('a ')} from OMPL RRTConnect within "
                f"{seconds:.3g} s; raise --time-limit, or check that start and goal are "
                "connected in the free space")
        budget.check(f"looking for {what} with OMPL RRTConnect")
        planner.solve(float(min(SLICE_SECONDS, left)))


def _simplified(si: Any, raw: Any, seconds: float,
                lift: Callable[[Sequence[Any]], tuple[list[np.ndarray], float] | None],
                shorter: Callable[[Sequence[Any]], bool]
                ) -> tuple[list[np.ndarray], float] | None:
    """``lift`` (:func:`_lifted`) of the path ``raw`` simplified by OMPL; OMPL's shortcuts
    and smoothing cut curves at new vertices whose turns at rest from the cut curve's hitch
    angle it never checks, so that path is kept only if it passes the final check, else
    the path with its vertices reduced (every curve checked), else ``raw``; ``None`` when
    none passes, or when the first whose vertices are ``shorter`` is not (a longer path than
    one already found is not lifted)."""
    from ompl import geometric as og

    simplifier = og.PathSimplifier(si)

    def smooth() -> Any:
        path: Any = og.PathGeometric(raw)
        simplifier.simplify(path, float(min(SIMPLIFY_SECONDS, seconds)))
        return path

    def reduced() -> Any:
        path: Any = og.PathGeometric(raw)
        simplifier.reduceVertices(path)
        simplifier.collapseCloseVertices(path)
        return path

    for make in (smooth, reduced, lambda: raw):
        path = make()
        vertices = [path.getState(i) for i in range(path.getStateCount())]
        if not shorter(vertices):
            return None
        lifted = lift(vertices)
        if lifted is not None:
            return lifted
    return None


def _length(space: Any, vertices: Sequence[Any]) -> float:
    """The Reeds–Shepp length of the curves between OMPL's ``vertices`` (compound states),
    ``space`` their Reeds–Shepp part: the length of their lifted legs."""
    return sum(float(space.distance(a[0], b[0])) for a, b in itertools.pairwise(vertices))


def _lifted(checker: Checker, hitch: float, radius: float, space: Any,
            vertices: Sequence[Any], *, s0: np.ndarray, sg: np.ndarray
            ) -> tuple[list[np.ndarray], float] | None:
    """The waypoints (car coordinates of the trailer) of :func:`~nilpotent.planning.guide.
    lift_legs` along the curves between OMPL's ``vertices`` (compound states) from ``s0`` to
    ``sg``, and the trailer's Reeds–Shepp length; ``None`` when a curve's legs are not
    solved, the heading turns by another multiple of ``2π``, or the motion they drive (the
    legs and the turns at rest between them, not through the vertices' own hitch angles)
    fails ``checker``'s motion check in the steps of the exact pieces (:data:`EXACT_STEP`,
    :data:`FINAL_SWEEP_STEP`): exactly what :func:`trailer_exact_piece` will drive."""
    try:
        legs = merge_legs([leg for a, b in itertools.pairwise(vertices)
                           for leg in edge_legs(edge_poses(space, a[0], b[0], LEG_STEP), radius,
                                                float(space.distance(a[0], b[0])))])
        points = lift_legs(legs, s0, sg, hitch)
    except PlanningError:
        return None
    pieces = motion_pieces(s0[:3], legs, float(s0[3]), float(sg[3]), hitch, EXACT_STEP,
                           FINAL_SWEEP_STEP)
    if not _admitted(checker, hitch, pieces):
        return None
    return points, sum(abs(leg.length) for leg in legs)


def _turn_failure(checker: Checker, kept: Checker, hitch: float, margin: float,
                  pieces: Sequence[np.ndarray]) -> str:
    """Why the car's turn at rest ``pieces`` (:func:`motion_pieces`) is not admissible, in
    words: the first hitch angle that fails under ``kept`` (the checker with the guide's
    margin) and what fails there under ``checker`` (a limit, an obstacle, the car touching
    its trailer), else only the guide's ``margin`` or the cover between samples."""
    turn = np.concatenate(pieces)
    bad = np.flatnonzero(~kept.valid(from_car(turn, hitch)))
    row = turn[int(bad[0])] if bad.size else turn[-1]
    why = checker.why_invalid(from_car(row, hitch))
    if not why:
        why = (f"it comes within the guide's margin {margin:g} of an obstacle" if bad.size
               else "the motion between its samples comes too close")
    return f"at theta0 - theta1 = {row[3]:.3g}, {why}"


def _straight_between(admitted: Callable[[list[np.ndarray]], bool], hitch: float,
                      s0: np.ndarray, sg: np.ndarray) -> bool:
    """Whether one straight leg of the trailer joins the start ``s0`` to the goal ``sg``
    (car coordinates: same heading, the goal on the start's axis) with the turns at rest
    from the start's hitch angle to ``0`` and from ``0`` to the goal's admissible: the one
    curve that needs no turn at rest to ``±φ_g`` at an end (a narrow corridor)."""
    d = np.asarray(sg[:2], dtype=float) - np.asarray(s0[:2], dtype=float)
    th = float(s0[2])
    along = float(d[0] * math.cos(th) + d[1] * math.sin(th))
    across = float(-d[0] * math.sin(th) + d[1] * math.cos(th))
    if abs(float(sg[2]) - th) > 1e-9 or abs(across) > 1e-9:
        return False
    return admitted(motion_pieces(s0[:3], [Leg(0.0, along)], float(s0[3]), float(sg[3]),
                                  hitch))


def _validator(checker: Checker, hitch: float, radius: float, poses: Any, si: Any) -> Any:
    """OMPL's motion validator of the trailer guide, between two states ``(pose, φ)``: the
    legs of the Reeds–Shepp curve between the poses solved as the lifting will solve them
    (:func:`~nilpotent.planning.guide.edge_legs`; a curve whose legs are not solved is
    invalid), driven from the first state's hitch angle to the second's
    (:func:`motion_pieces`), every piece admissible under ``checker`` with its cover.  At a
    vertex the lifted path turns at rest from the hitch angle of one curve's last leg
    directly to the next one's first, a turn within the two that the validator checked
    (through the vertex's own angle)."""
    from ompl import base as ob

    class Validator(ob.MotionValidator):  # type: ignore[misc]
        def checkMotion(self, a: Any, b: Any, *rest: Any) -> bool:
            pa, pb = a[0], b[0]
            try:
                legs = edge_legs(edge_poses(poses, pa, pb, LEG_STEP), radius,
                                 float(poses.distance(pa, pb)))
            except PlanningError:
                return False
            pose = (pa.getX(), pa.getY(), pa.getYaw())
            return _admitted(checker, hitch,
                             motion_pieces(pose, legs, float(a[1][0]), float(b[1][0]), hitch))

    return Validator(si)


#: Largest change of the trailer's pose between two waypoints of one turn at rest.
AT_REST = 1e-9


def trailer_exact_piece(checker: Checker, x: np.ndarray, prev: np.ndarray, w: np.ndarray,
                        tol: float, points: int, geometry: TrailerGeometry) -> Any:
    """The exact motion between two consecutive waypoints of :func:`trailer_guide_path`
    (module doc: one leg, or one turn at rest) from the state ``x`` reached, if it lands
    within ``tol`` of ``w`` and is admissible; else ``None`` (the piece is then steered).
    Returns a :class:`~nilpotent.planning.iterative.Plan` of the piece."""
    from nilpotent.errors import IntegrationError
    from nilpotent.planning.controls import constant_segment
    from nilpotent.planning.iterative import Plan
    from nilpotent.planning.simulation import simulate_path
    from nilpotent.simulation.trajectory import Trajectory

    d = geometry.hitch
    a, b = to_car(prev, d), to_car(w, d)
    delta = b - a
    if float(np.abs(delta[:3]).max()) <= AT_REST:
        u = (0.0, float(w[2] - x[2]))
        # the car's body sweeps about its axle centre: steps of φ as the car guide's
        points = max(points, math.ceil(abs(u[1]) / PHI_MARGIN) + 1)
    elif abs(float(delta[3])) <= AT_REST:
        phi = float(a[3])
        kappa = math.tan(phi) / d
        if abs(kappa) > 1e-12:
            s1 = float(delta[2]) / kappa
        else:
            s1 = float(delta[0] * math.cos(a[2]) + delta[1] * math.sin(a[2]))
        if not math.isfinite(s1) or abs(s1) < 0.5 * float(np.hypot(delta[0], delta[1])):
            return None  # not one leg (e.g. a halved piece across a switch)
        s0 = s1 / math.cos(phi)
        u = (s0, s0 * math.sin(phi) / d)
        # the car moves 1/cos φ as far as the trailer: samples every EXACT_STEP of its path
        points = max(points, math.ceil(abs(s0) / EXACT_STEP) + 1)
    else:
        return None
    segs = (constant_segment(np.array(u), 1.0),)
    try:
        times, states = simulate_path(checker.system, x, segs, points)
    except IntegrationError:
        return None
    error = float(np.linalg.norm(states[-1] - w))
    if not (error <= tol and checker.valid_motion(states)):
        return None
    return Plan(checker.system, tuple(map(float, x)), tuple(map(float, w)), segs,
                tuple(map(float, states[-1])), error, (), Trajectory(times, states), tol=tol,
                initial_error=float(np.linalg.norm(w - x)))
