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

:func:`trailer_guide_path` runs :func:`~nilpotent.planning.guide.guide_path` on a stand-in
checker of the built-in ``car`` (``L = d``, ``|φ| ≤`` :data:`TRAILER_PHI` ``+`` the guide's
``PHI_MARGIN``) whose validity is that of the trailer model with the guide's margin: a pose
valid at ``φ = 0``, a Reeds–Shepp curve valid with the hitch angle of each of its legs and
the car's turns at rest between them (an OMPL motion validator, :func:`_validator`); it maps
the waypoints back to the model's coordinates; :func:`trailer_exact_piece` drives a piece
between two of them exactly (else the piece is steered by the nilpotent steering, as for
any path).  ``car-trailers:2`` and more are not covered (their relative angles cannot all
be held on a Reeds–Shepp arc entered at rest).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.core.model.outline import Limits
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import OptionError, PlanningError
from nilpotent.planning.guide import (
    GUIDE_MARGIN,
    PHI_MARGIN,
    GuidePath,
    Leg,
    guide_path,
    leg_end,
)
from nilpotent.planning.verify import Checker

__all__ = [
    "TRAILER_COORDINATES", "TRAILER_PHI", "TrailerGeometry", "from_car", "to_car",
    "trailer_exact_piece", "trailer_geometry", "trailer_guide_path",
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
            "--planner reeds-shepp needs a car-like model or a car with one trailer "
            f"(coordinates x, y, theta0, theta1, e.g. car-trailers:1): model {system.name} {why}")
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
    ``φ_g + PHI_MARGIN``: what :func:`~nilpotent.planning.guide.guide_path` reads (the
    geometry, the world's bounds); its validity is never used."""
    from nilpotent.models import get_model

    car = get_model("car", {"L": sp.Float(geometry.hitch), "rmin": sp.Float(geometry.radius)})
    limit = geometry.phi_guide + PHI_MARGIN
    return Checker(car, checker.world, Limits((("phi", -limit, limit),)))


def _valid(checker: Checker, hitch: float, margin: float, s: np.ndarray) -> np.ndarray:
    """The validity of configurations ``s (N, 4)`` in the trailer's car coordinates; for the
    guide's pose check (``N = 3``: one pose at the hitch angles ``−φ_g, 0, φ_g``) that of
    ``φ = 0`` alone, the angles taken on a curve being checked with it (:func:`_validator`)."""
    ok = checker.valid(from_car(s, hitch), extra_clearance=margin)
    return np.full(3, bool(ok[1])) if len(ok) == 3 else ok


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

    Parameters as :func:`~nilpotent.planning.guide.guide_path`; ``valid`` and ``held`` are
    ignored (the checker's validity with the guide's margin, none when the start or the
    goal lacks it, at the hitch angle 0; each curve with the hitch angles of its legs and
    the turns at rest between them: :func:`_validator`).

    Raises
    ------
    OptionError
        The model is not a car with one trailer.
    PlanningError
        As :func:`~nilpotent.planning.guide.guide_path`; or, at once, the start's or the
        goal's trailer pose admits no turn of the car at rest to ``+φ_g`` nor to ``−φ_g``
        (unless one straight leg joins the start to the goal: :func:`_straight_between`).
    """
    del valid, held
    geometry = trailer_geometry(checker.system, checker)
    d, phi_g = geometry.hitch, geometry.phi_guide
    s0, sg = to_car(x0, d), to_car(xg, d)
    # the guide's margin unless the start or the goal lacks it (at the hitch angle 0)
    ends = np.array([[*s[:3], 0.0] for s in (s0, sg)])
    margin = GUIDE_MARGIN if bool(np.all(checker.valid(from_car(ends, d), GUIDE_MARGIN))) \
        else 0.0
    check = functools.partial(_valid, checker, d, margin)
    for what, s in (("start", s0), ("goal", sg)):
        # every curve starts and ends with a turn at rest from / to φ = 0 (_validator):
        # with neither turn admissible, only a curve ending in a straight leg exactly on
        # the pose's axis reaches it, and OMPL would search the whole time
        k = max(4, math.ceil(phi_g / SWEEP_STEP) + 1)  # not 3 rows: _valid's pose check
        turns = [np.array([[*s[:3], p] for p in np.linspace(0.0, sign * phi_g, k)])
                 for sign in (1.0, -1.0)]
        if not any(bool(np.all(check(t))) for t in turns) \
                and not _straight_between(check, s0, sg):
            raise PlanningError(
                f"the {what}'s trailer pose admits no turn of the car at rest to the hitch "
                f"angle +-{phi_g:.3g} of the trailer guide ("
                + "; ".join(_turn_failure(checker, check, d, margin, t) for t in turns)
                + "): the guide's curves cannot start or end there")
    motion = functools.partial(_validator, check, phi_g, geometry.radius)
    found = guide_path(_stand_in(checker, geometry), s0, sg, seconds, seed, resolution,
                       valid=check, motion=motion)
    points = [from_car(np.array(p), d) for p in found.points]
    points[0], points[-1] = np.asarray(x0, dtype=float), np.asarray(xg, dtype=float)
    return GuidePath(tuple(tuple(float(c) for c in p) for p in points), found.length,
                     found.length_history, found.radius)


def _turn_failure(checker: Checker, check: Callable[[np.ndarray], np.ndarray], hitch: float,
                  margin: float, turn: np.ndarray) -> str:
    """Why the car's turn at rest ``turn`` (rows ``(x1, y1, θ1, φ)``) is not admissible, in
    words: the first hitch angle that fails and what fails there (a limit, an obstacle, the
    car touching its trailer, or only the guide's ``margin`` from an obstacle)."""
    bad = np.flatnonzero(~check(turn))
    row = turn[int(bad[0])] if bad.size else turn[-1]
    why = checker.why_invalid(from_car(row, hitch))
    if not why:
        why = f"it comes within the guide's margin {margin:g} of an obstacle"
    return f"at theta0 - theta1 = {row[3]:.3g}, {why}"


def _straight_between(check: Callable[[np.ndarray], np.ndarray], s0: np.ndarray,
                      sg: np.ndarray) -> bool:
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

    def sweep(pose: np.ndarray, a: float, b: float) -> list[tuple[float, ...]]:
        k = max(1, math.ceil(abs(b - a) / SWEEP_STEP))
        return [(*pose, float(p)) for p in np.linspace(a, b, k + 1)]

    rows = sweep(np.asarray(s0[:3], dtype=float), float(s0[3]), 0.0)
    rows += [(*p[:3], 0.0) for p in _motion_configs(s0[:3], [Leg(0.0, along)], 0.0, 1.0)]
    rows += sweep(np.asarray(sg[:3], dtype=float), 0.0, float(sg[3]))
    rows = rows + rows[:1] if len(rows) == 3 else rows  # not 3 rows: _valid's pose check
    return bool(np.all(check(np.array(rows))))


#: Steps of the motion check along a Reeds-Shepp curve (arc length of the trailer) and of
#: the hitch angle where the car turns at rest.
MOTION_STEP = 0.02
SWEEP_STEP = 0.05


def _validator(check: Callable[[np.ndarray], np.ndarray], phi_g: float, radius: float,
               space: Any, si: Any) -> Any:
    """OMPL's motion validator of the trailer guide: the legs of the Reeds–Shepp curve
    solved as the lifting will solve them (:func:`~nilpotent.planning.guide.edge_legs`; a
    curve whose legs are not solved is invalid), each leg's poses every
    :data:`MOTION_STEP` at its hitch angle, the car's turn at rest before each leg, and the
    turns from and to ``φ = 0`` at the curve's ends (so that any turn at a vertex of the
    path, from one curve's last angle to the next one's first, is covered)."""
    from ompl import base as ob

    from nilpotent.planning.guide import edge_legs, edge_poses

    class Validator(ob.MotionValidator):  # type: ignore[misc]
        def checkMotion(self, a: Any, b: Any, *rest: Any) -> bool:
            distance = float(space.distance(a, b))
            poses = edge_poses(space, a, b)
            try:
                legs = edge_legs(poses, radius, distance)
            except PlanningError:
                return False
            return bool(np.all(check(_motion_configs(poses[0], legs, phi_g, radius))))

    return Validator(si)


def _motion_configs(pose: np.ndarray, legs: Sequence[Leg], phi_g: float,
                    radius: float) -> np.ndarray:
    """Configurations ``(x1, y1, θ1, φ)`` to check along the ``legs`` driven from ``pose``
    (:func:`_validator`): turns at rest in steps of at most :data:`SWEEP_STEP`, each leg's
    poses every :data:`MOTION_STEP` of arc length at ``φ = ±φ_g`` or ``0``."""
    rows: list[tuple[float, ...]] = []
    phi = 0.0
    pose = np.asarray(pose, dtype=float)

    def sweep(to: float) -> None:
        k = max(1, math.ceil(abs(to - phi) / SWEEP_STEP))
        rows.extend((*pose, float(p)) for p in np.linspace(phi, to, k + 1))

    for leg in legs:
        turn = phi_g * float(np.sign(leg.kappa)) if abs(leg.kappa) * radius > 0.5 else 0.0
        sweep(turn)
        phi = turn
        k = max(1, math.ceil(abs(leg.length) / MOTION_STEP))
        rows.extend((*leg_end(pose, leg.kappa, leg.length * j / k), phi)
                    for j in range(1, k + 1))
        pose = leg_end(pose, leg.kappa, leg.length)
    sweep(0.0)
    return np.array(rows)


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
