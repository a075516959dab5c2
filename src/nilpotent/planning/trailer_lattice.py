r"""A lattice search over exact motions for a car with two trailers (``planner="reeds-shepp"``).

For ``car-trailers:2`` (coordinates ``x, y, θ0, θ1, θ2``, hitch lengths ``d1, d2``; the
on-axle hitching of Laumond, "Controllability of a multibody mobile robot", IEEE Trans.
Robot. Autom. 9(6), 1993, and Altafini, "Some properties of the general n-trailer", Int. J.
Control 74(4), 2001) the Reeds–Shepp guide of :mod:`nilpotent.planning.trailer_guide` does not
apply: ``φ2 = θ1 − θ2`` changes only while the vehicle moves.  This stage searches instead,
as the hybrid A* of Dolgov, Thrun, Montemerlo, Diebel ("Path planning for autonomous vehicles
in unknown semi-structured environments", IJRR 29(5), 2010), over two **exact motions** of
the true system:

* a **turn at rest** ``u = (0, Δθ0)`` for a unit time: the car turns on the spot about its
  axle centre ``P0``, the trailers still; it sets the hitch angle ``φ1 = θ0 − θ1``;
* a **drive with** ``φ1`` **held**: ``u = (s0, s0 sin φ1 / d1)`` for a unit time
  (``θ̇0 = θ̇1``).  Trailer 1's axle centre ``P1 = P0 − d1 (cos θ1, sin θ1)`` runs on a
  circle of curvature ``κ = tan φ1 / d1`` for the arc length ``s1 = s0 cos φ1``, and
  trailer 2 follows as a caster: along ``s1``, ``dφ2/ds1 = κ − sin φ2 / d2``, a scalar
  ODE with constant coefficients solved in closed form (:func:`~nilpotent.planning.
  trailer_hitch.hitch_flow`: with
  ``t = tan(φ2/2)`` a Riccati equation ``dt/ds1 = (κ t² − 2 t/d2 + κ)/2``).  Backwards
  the caster is unstable (``φ2`` leaves the equilibrium ``sin φ2 = κ d2``); each drive is
  short and checked against the hitch limits.

The search (:func:`lattice_path`) is a weighted A* grown **from the goal** (in a parking
slot, where room is scarce; the motions are reversible, so the path found is run backwards:
waypoints reversed, controls negated).  A node's children turn the car at rest to each hitch
angle of :data:`HITCH_ANGLES` (and keep the present one: in a slot no turn may have room)
and drive :data:`FORWARD_STEP` forwards or :data:`REVERSE_STEP` backwards; nodes binned on
trailer 1's pose and ``φ2`` (:data:`BIN_XY`, :data:`BIN_ANGLE`); cost the arc length of
trailer 1 (switches and turns penalised); heuristic the largest of the Reeds–Shepp distances
(Reeds & Shepp 1990, OMPL's ``ReedsSheppStateSpace``, radius :data:`HEURISTIC_RADIUS`
``· d2``) of trailer 1's and trailer 2's poses to theirs at the start and of their axle
centres' grid distances among the obstacles
(:func:`~nilpotent.planning.grid_distance.grid_distance`).  Every motion is checked on
samples (turns every :data:`TURN_STEP` rad, drives every :data:`DRIVE_STEP` of the car's
path, both denser near an obstacle) with the extra clearance :data:`MARGIN` (less near an
obstacle, at least :data:`MIN_MARGIN`) against the obstacles, the hitch limits and the
self-collisions (the project's :class:`~nilpotent.planning.verify.Checker`).  A node in free
space (:data:`APPROACH_CLEARANCE`) with trailer 1 headed roughly as at the start, or within
:data:`GOAL_REGION` of it, is joined to the start **exactly** (:func:`final_approach`): the
parameters ``(φ1, s1)`` of :data:`APPROACH_DRIVES` drives from the start (forwards: better
conditioned) are solved by least squares so that trailer 1's pose and ``φ2`` land on the
node's, and a turn at rest sets ``θ0``; else from the node to the start.  The search ends with a
:class:`~nilpotent.errors.ComputationLimitError` when its seconds run out, a
:class:`~nilpotent.errors.PlanningError` when every reachable bin was expanded.

The path's waypoints are the states between the motions (drives cut every
:data:`WAYPOINT_STEP`), each piece's constant controls kept in :class:`LatticePath`;
:func:`lattice_exact_piece` drives a piece by them (else the pipeline steers it), and the
whole plan is verified as every plan of
:func:`~nilpotent.planning.global_planner.plan_global`.
"""

from __future__ import annotations

import heapq
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ComputationLimitError, OptionError, PlanningError
from nilpotent.planning import budget
from nilpotent.planning.grid_distance import grid_distance
from nilpotent.planning.trailer_hitch import hitch_flow, limit_slack, within_limits
from nilpotent.planning.verify import Checker
from nilpotent.progress import ProgressEvent
from nilpotent.progress import report as report_progress

__all__ = ["LATTICE_COORDINATES", "LatticeGeometry", "LatticePath", "arc_states", "drive_controls",
           "final_approach", "hitch_flow", "is_lattice_model", "lattice_exact_piece",
           "lattice_geometry", "lattice_path", "turn_states"]

#: Coordinates of a two-trailer model, in order.
LATTICE_COORDINATES = ("x", "y", "theta0", "theta1", "theta2")
#: Hitch angles ``φ1`` (rad) the car turns to at rest before a drive.
HITCH_ANGLES = (-1.2, -0.8, -0.4, 0.0, 0.4, 0.8, 1.2)
#: Trailer 1's arc length of a forward / a reverse drive of the search.
FORWARD_STEP = 0.4
REVERSE_STEP = 0.4
#: Cost factors: reverse arc length, a change of direction, a radian of turn at rest.
REVERSE_COST = 1.0
SWITCH_COST = 0.5
TURN_COST = 0.1
#: Weight of the heuristic (weighted A*), and the radius of its Reeds–Shepp curves in units
#: of ``d2``: trailer 2 follows a circle of trailer 1 at a constant hitch angle only if its
#: radius is at least ``d2`` (``sin φ2 = κ d2``), so turning the train round costs more than
#: trailer 1's least radius suggests.
HEURISTIC_WEIGHT = 2.0
HEURISTIC_RADIUS = 1.0
#: Bins of the closed set: trailer 1's axle centre, its heading and ``φ2``.
BIN_XY = 0.15
BIN_ANGLE = 0.15
#: Sampling of the motion check: rad of a turn at rest, car's path length of a drive; and
#: the extra clearance (obstacles, limits, bodies) that covers the motion between samples.
TURN_STEP = 0.1
DRIVE_STEP = 0.04
MARGIN = 0.04
#: The least margin, near an obstacle (the samples are then denser: :func:`_margin`).
MIN_MARGIN = 0.002
#: A node this close to the start (trailer 1's axle centre, its heading, ``φ2``; each
#: coordinate) is joined to it by :func:`final_approach` (the search grows from the goal).
GOAL_REGION = 0.3
#: ... and so is a node this far from every obstacle (free space, where the approach's
#: long drives have room), once per bin of :data:`APPROACH_BIN` (trailer 1's pose, ``φ2``).
APPROACH_CLEARANCE = 0.5
APPROACH_BIN = 0.5
#: ... with trailer 1's heading this close to the end's and ``|φ2|`` at most this (rad):
#: the least squares of a farther node mostly ends in a local minimum.
APPROACH_HEADING = 0.8
APPROACH_HITCH = 0.6
#: Largest hitch angle of the final approach's drives; the number of drives it solves.
APPROACH_PHI = 1.25
APPROACH_DRIVES = 6
#: Longest drive of the approach (trailer 1's arc length).
APPROACH_LENGTH = 4.0
#: The approach's drives keep ``|φ2| ≤ phi_max −`` this at :data:`APPROACH_PROBES` points
#: each (a penalty of the least squares).
APPROACH_SLACK = 0.2
APPROACH_PROBES = 6
#: ... and the axle centres and the car's front (:func:`_axles`) this far from the obstacles.
APPROACH_ROOM = 0.3
APPROACH_MARGIN = 0.01  #: the approach's margin (checked once: denser samples are cheap)
#: Most evaluations of each least-squares run (one per initial guess).
APPROACH_EVALS = 100
#: Cell of the obstacle-aware grid heuristic, and the clearance its free cells keep (about
#: half a trailer's width).
GRID = 0.1
GRID_RADIUS = 0.15
#: Trailer 1's arc length between the waypoints of a drive, and the car's turn (rad) between
#: those of a turn at rest: pieces shorter than plan_global's ``max_piece`` (1, configuration
#: space), which it would cut at their chords' midpoints (then steered, not driven exactly).
WAYPOINT_STEP = 0.1
TURN_WAYPOINT_STEP = 0.5
#: Largest change of another coordinate than ``θ0`` in a piece that is a turn at rest.
AT_REST = 1e-9
#: Car's path length (drive) / rad (turn) between the samples of an exact piece's check.
EXACT_STEP = 0.002


@dataclass(frozen=True)
class LatticeGeometry:
    """What the lattice search needs of a two-trailer model.

    Attributes
    ----------
    hitches:
        ``(d1, d2)``, the hitch lengths (axle centre to axle centre, model length units).
    phi_max:
        The hitch limit, ``|θ0 − θ1|, |θ1 − θ2| ≤ phi_max`` (rad).
    """

    hitches: tuple[float, float]
    phi_max: float


@dataclass(frozen=True)
class LatticePath:
    """The path found: waypoints ``(N, 5)`` (model coordinates), the constant controls
    ``(u1, u2)`` (unit time) of the exact motion from each waypoint to the next (``None``:
    none, steered), trailer 1's arc length, nodes expanded, seconds."""

    points: tuple[tuple[float, ...], ...]
    controls: tuple[tuple[float, float] | None, ...]
    length: float
    expanded: int
    seconds: float
    length_history: tuple[tuple[float, float], ...] = field(default=())


def is_lattice_model(system: ControlSystem) -> bool:
    """Whether ``system`` has the coordinates of a car with two trailers (module doc)."""
    return system.coordinate_names == LATTICE_COORDINATES


def lattice_geometry(system: ControlSystem, checker: Checker) -> LatticeGeometry:
    """The hitch lengths and limit of a ``car-trailers:2``-like model (module doc).

    Raises
    ------
    OptionError
        Other fields than those of ``car-trailers:2``, limits on absolute angles, or a hitch
        limit not in ``(0.3, π/2)``.
    """
    if not is_lattice_model(system) or system.m != 2:
        raise OptionError(f"the lattice search needs a car with two trailers (coordinates "
                          f"{', '.join(LATTICE_COORDINATES)}); model {system.name} is not")
    _, _, a, b, c = system.coordinates
    drive, steer = system.specialized_fields
    try:
        d1 = float(sp.simplify(sp.sin(a - b) / drive[3]))
        d2 = float(sp.simplify(sp.cos(a - b) * sp.sin(b - c) / drive[4]))
    except (TypeError, ZeroDivisionError) as e:
        raise OptionError(f"--planner reeds-shepp: model {system.name} is not a car with two "
                          "trailers hitched on axle") from e
    expected = (sp.cos(a), sp.sin(a), 0, sp.sin(a - b) / d1,
                sp.cos(a - b) * sp.sin(b - c) / d2)
    if tuple(steer) != (0, 0, 1, 0, 0) or not (d1 > 0 and d2 > 0) or any(
            sp.simplify(f - e) != 0 for f, e in zip(drive, expected, strict=True)):
        raise OptionError(f"--planner reeds-shepp: model {system.name} has other fields than "
                          "car-trailers:2")
    assert checker.limits is not None
    if checker.limits.bounds:
        raise OptionError("--planner reeds-shepp: the lattice search takes no limit on "
                          "absolute coordinates (only on theta0 - theta1, theta1 - theta2)")
    phi_max = math.inf
    for pair in ((a, b), (b, c)):
        lo, hi = -math.inf, math.inf
        for _, expr, lo_r, hi_r in checker.limits.relative:
            if sp.simplify(expr - (pair[0] - pair[1])) == 0:
                lo, hi = max(lo, lo_r), min(hi, hi_r)
            elif sp.simplify(expr + (pair[0] - pair[1])) == 0:
                lo, hi = max(lo, -hi_r), min(hi, -lo_r)
        phi_max = min(phi_max, -lo, hi)
    if not (max(HITCH_ANGLES) + MARGIN < phi_max < math.pi / 2):
        raise OptionError(f"--planner reeds-shepp needs hitch limits |theta0 - theta1|, "
                          f"|theta1 - theta2| <= phi_max with {max(HITCH_ANGLES) + MARGIN:g} < "
                          f"phi_max < pi/2 (model {system.name}: {phi_max:g})")
    return LatticeGeometry((d1, d2), phi_max)


def arc_states(q: np.ndarray, s1: np.ndarray, geometry: LatticeGeometry) -> np.ndarray:
    """States ``(len(s1), 5)`` of the drive with ``φ1 = θ0 − θ1`` held from ``q`` after
    trailer 1's signed arc lengths ``s1`` (module doc; closed form)."""
    d1, d2 = geometry.hitches
    s1 = np.asarray(s1, dtype=float)
    x, y, th0, th1, th2 = (float(v) for v in q)
    phi1 = th0 - th1
    kappa = math.tan(phi1) / d1
    x1, y1 = x - d1 * math.cos(th1), y - d1 * math.sin(th1)
    th = th1 + kappa * s1
    if abs(kappa) > 1e-9:
        px = x1 + (np.sin(th) - math.sin(th1)) / kappa
        py = y1 - (np.cos(th) - math.cos(th1)) / kappa
    else:  # the chord, with the curvature's first-order term
        px = x1 + s1 * np.cos(th1 + kappa * s1 / 2)
        py = y1 + s1 * np.sin(th1 + kappa * s1 / 2)
    phi2 = hitch_flow(th1 - th2, kappa, d2, s1)
    return np.stack([px + d1 * np.cos(th), py + d1 * np.sin(th), th + phi1, th, th - phi2],
                    axis=-1)


def turn_states(q: np.ndarray, theta0: float, step: float) -> np.ndarray:
    """States of the turn at rest from ``q`` to the car's heading ``theta0``, every ``step``
    rad at most, both ends included."""
    k = max(1, math.ceil(abs(theta0 - float(q[2])) / step))
    out = np.repeat(np.asarray(q, dtype=float)[None, :], k + 1, axis=0)
    out[:, 2] = np.linspace(float(q[2]), theta0, k + 1)
    return out


def drive_controls(q: np.ndarray, s1: float, geometry: LatticeGeometry) -> tuple[float, float]:
    """The constant controls (unit time) of the drive of trailer 1's arc length ``s1``
    from ``q`` (``φ1`` held): ``s0 = s1 / cos φ1``, ``u = (s0, s0 sin φ1 / d1)``."""
    phi1 = float(q[2] - q[3])
    s0 = s1 / math.cos(phi1)
    return (s0, s0 * math.sin(phi1) / geometry.hitches[0])


def _margin(checker: Checker, *qs: np.ndarray) -> float:
    """The margin of the motion checks from states ``qs``: :data:`MARGIN`, less near an
    obstacle (0.45 of the least clearance, at least :data:`MIN_MARGIN`)."""
    clear = float(checker.measures(np.array(qs))[0].min())
    return min(MARGIN, max(MIN_MARGIN, 0.45 * clear))


def _drive_samples(q: np.ndarray, s1: float, geometry: LatticeGeometry,
                   margin: float = MARGIN) -> np.ndarray:
    s0 = abs(s1 / math.cos(float(q[2] - q[3])))
    k = max(2, math.ceil(s0 / (DRIVE_STEP * margin / MARGIN)))
    return arc_states(q, np.linspace(0.0, s1, k + 1), geometry)


@dataclass(frozen=True)
class _Motion:
    """One motion of the search: a turn at rest to ``theta0`` then a drive ``s1``."""

    theta0: float
    s1: float


def _apply(q: np.ndarray, motions: Sequence[_Motion], geometry: LatticeGeometry,
           margin: float = MARGIN) -> tuple[np.ndarray, list[np.ndarray]]:
    """The state after ``motions`` from ``q`` and the samples of each turn and drive."""
    samples = []
    for m in motions:
        samples.append(turn_states(q, m.theta0, TURN_STEP * margin / MARGIN))
        q = samples[-1][-1]
        if m.s1 != 0.0:
            samples.append(_drive_samples(q, m.s1, geometry, margin))
            q = samples[-1][-1]
    return q, samples


def _admissible(checker: Checker, samples: Sequence[np.ndarray], margin: float,
                slack: float) -> bool:
    """Every sample admissible with ``margin`` (obstacles, bodies) and the limits kept
    (``slack`` at the samples, and between them: :func:`within_limits`)."""
    rows = np.vstack(samples)
    return bool(np.all(np.isfinite(rows)) and np.all(checker.valid(rows, margin, 0.0, margin))
                and np.all(within_limits(checker, samples, slack)))


def _pose(q: np.ndarray, which: int, geometry: LatticeGeometry) -> tuple[float, float, float]:
    """The axle centre and heading of trailer ``which`` (1 or 2) at ``q``."""
    d1, d2 = geometry.hitches
    x = float(q[0] - d1 * math.cos(q[3]))
    y = float(q[1] - d1 * math.sin(q[3]))
    if which == 2:
        x, y = x - d2 * math.cos(q[4]), y - d2 * math.sin(q[4])
    return x, y, float(q[2 + which])


def _axles(q: np.ndarray, geometry: LatticeGeometry) -> np.ndarray:
    """The axle centres ``P0, P1, P2`` and the car's front ``P0 + 0.6 (cos θ0, sin θ0)``
    at states ``q (N, 5)``: ``(N, 4, 2)``."""
    d1, d2 = geometry.hitches
    p0 = q[:, :2]
    p1 = p0 - d1 * np.stack([np.cos(q[:, 3]), np.sin(q[:, 3])], axis=-1)
    p2 = p1 - d2 * np.stack([np.cos(q[:, 4]), np.sin(q[:, 4])], axis=-1)
    front = p0 + 0.6 * np.stack([np.cos(q[:, 2]), np.sin(q[:, 2])], axis=-1)
    return np.stack([p0, front, p1, p2], axis=1)


def _reduced(q: np.ndarray, geometry: LatticeGeometry) -> np.ndarray:
    """``(x1, y1, θ1, φ2)``: what the drives must bring to the goal's (``θ0`` is set at rest)."""
    x1, y1, th1 = _pose(q, 1, geometry)
    return np.array([x1, y1, th1, float(q[3] - q[4])])


def final_approach(checker: Checker, q: np.ndarray, xg: np.ndarray, geometry: LatticeGeometry,
                   space: Any = None) -> list[_Motion] | None:
    """Motions that join ``q`` to the goal ``xg`` exactly, or ``None``: drives (each a turn
    at rest to a hitch angle ``|φ1| ≤ APPROACH_PHI``, then trailer 1's arc ``s1``) whose
    parameters are solved by least squares (scipy, trust region with bounds) so that
    ``(x1, y1, θ1, φ2)`` lands on the goal's, ``|φ2|`` and the axle centres' clearance
    penalised on the way (:data:`APPROACH_SLACK`, :data:`APPROACH_ROOM`), then the turn at
    rest to the goal's ``θ0``; admissible on the samples (module doc) and within ``1e-9``.
    First guesses: :data:`APPROACH_DRIVES` equal straight drives along the goal's heading,
    then the legs of trailer 1's Reeds–Shepp curve (OMPL ``space``; ``φ1 = atan(d1 κ)``)."""
    from scipy.optimize import least_squares

    target = _reduced(xg, geometry)
    # |φ2| kept below phi_max - APPROACH_SLACK, or below the ends' own (near the limit)
    soft = min(geometry.phi_max, max(geometry.phi_max - APPROACH_SLACK, abs(float(
        q[3] - q[4])), abs(float(xg[3] - xg[4]))))
    world = checker.world
    probe = np.linspace(0.0, 1.0, APPROACH_PROBES + 1)[1:]

    def residual(p: np.ndarray) -> np.ndarray:
        # the goal's (x1, y1, θ1, φ2), and how far φ2 leaves |φ2| <= soft on the way
        x = np.asarray(q, dtype=float)
        runs = []
        for i in range(len(p) // 2):
            x = x.copy()
            x[2] = x[3] + p[2 * i]
            runs.append(arc_states(x, p[2 * i + 1] * probe, geometry))
            x = runs[-1][-1]
        run = np.vstack(runs)
        over = [np.maximum(np.abs(run[:, 3] - run[:, 4]) - soft, 0.0)]
        if world is not None:
            ok = np.all(np.isfinite(run), axis=1)
            room = np.full((len(run), 4), APPROACH_ROOM)
            room[ok] = world.point_clearance(_axles(run[ok], geometry))
            over.append(np.maximum(APPROACH_ROOM - room, 0.0).ravel())
        r = np.concatenate([_reduced(x, geometry) - target, *over])
        return np.nan_to_num(r, nan=10.0)

    diff = target - _reduced(q, geometry)
    along = float(diff[0] * math.cos(target[2]) + diff[1] * math.sin(target[2]))
    k = APPROACH_DRIVES
    starts = [np.array([0.0, along / k] * k)]
    if space is not None:
        starts += _reeds_shepp_guess(space, _reduced(q, geometry), target, geometry)
    for p0 in starts:
        lo = np.tile([-APPROACH_PHI, -APPROACH_LENGTH], len(p0) // 2)
        fit = least_squares(residual, np.clip(p0, lo + 1e-9, -lo - 1e-9), bounds=(lo, -lo),
                            xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=APPROACH_EVALS)
        if not (float(np.abs(fit.fun[:4]).max()) < 1e-10 and float(fit.fun.max()) < 1e-6):
            continue  # the goal missed, or the penalties not met (the check decides)
        p = fit.x
        out, x = [], np.asarray(q, dtype=float)
        for i in range(len(p) // 2):
            out.append(_Motion(float(x[3] + p[2 * i]), float(p[2 * i + 1])))
            x, _ = _apply(x, out[-1:], geometry)
        out.append(_Motion(float(xg[2]), 0.0))
        margin = min(APPROACH_MARGIN, _margin(checker, np.asarray(q, dtype=float),
                                              np.asarray(xg, dtype=float)))
        end, samples = _apply(np.asarray(q, dtype=float), out, geometry, margin)
        slack = limit_slack(checker, margin, np.asarray(q, dtype=float), xg)
        if _admissible(checker, samples, margin, slack) and float(
                np.abs(end - xg).max()) < 1e-9:
            return out
    return None


def _reeds_shepp_guess(space: Any, a: np.ndarray, b: np.ndarray,
                       geometry: LatticeGeometry) -> list[np.ndarray]:
    """Drives ``(φ1, s1)`` (flattened) on the legs of the Reeds–Shepp curve from trailer 1's
    pose ``a[:3]`` to ``b[:3]`` (:func:`~nilpotent.planning.guide.edge_legs`; at least two)."""
    from nilpotent.planning.guide import edge_legs, edge_poses

    sa, sb = space.allocState(), space.allocState()
    for st, v in ((sa, a), (sb, b)):
        st.setX(float(v[0]))
        st.setY(float(v[1]))
        st.setYaw(float(v[2]))
    d1, d2 = geometry.hitches
    radius = HEURISTIC_RADIUS * d2  # the radius of ``space`` (lattice_path)
    try:
        legs = edge_legs(edge_poses(space, sa, sb), radius, float(space.distance(sa, sb)))
    except PlanningError:
        return []
    drives = [[math.atan(d1 * leg.kappa), leg.length] for leg in legs if leg.length != 0.0]
    while 0 < len(drives) < 2:
        longest = max(range(len(drives)), key=lambda i: abs(drives[i][1]))
        phi, s = drives[longest]
        drives[longest:longest + 1] = [[phi, s / 2], [phi, s / 2]]
    return [np.ravel(drives)] if drives else []


def _children(checker: Checker, q: np.ndarray, sign: float, geometry: LatticeGeometry,
              margin: float) -> list[tuple[_Motion, np.ndarray, float]]:
    """The admissible motions from ``q`` (each hitch angle of :data:`HITCH_ANGLES`, forwards
    and backwards), their end states and costs (module doc); one batch of samples checked."""
    rows: list[np.ndarray] = []
    spans: list[tuple[_Motion, int, int]] = []  # the motion, its turn's and drive's rows
    held = float(q[2] - q[3])  # the hitch angle as it is: no turn (e.g. none has room)
    angles = HITCH_ANGLES if min(abs(held - a) for a in HITCH_ANGLES) < 1e-9 or \
        abs(held) > max(HITCH_ANGLES) else (*HITCH_ANGLES, held)
    for phi1 in angles:
        th0 = float(q[3] + phi1)
        rows.append(turn_states(q, th0, TURN_STEP * margin / MARGIN))
        turned = len(rows) - 1
        for s1 in (FORWARD_STEP, -REVERSE_STEP):
            rows.append(_drive_samples(rows[turned][-1], s1, geometry, margin))
            spans.append((_Motion(th0, s1), turned, len(rows) - 1))
    flat = np.vstack(rows)
    ok = np.all(np.isfinite(flat), axis=1)
    ok[ok] = checker.valid(flat[ok], margin, 0.0, margin)
    # the hitch limits: as near as q is at most, and between the samples (trailer_hitch)
    row_ok = within_limits(checker, rows, limit_slack(checker, margin, q))
    for k, part in enumerate(np.split(ok, np.cumsum([len(r) for r in rows])[:-1])):
        row_ok[k] &= bool(part.all())
    out = []
    for m, turned, driven in spans:
        if not (row_ok[turned] and row_ok[driven]):
            continue
        step = abs(m.s1) * (1.0 if m.s1 > 0 else REVERSE_COST)
        step += TURN_COST * abs(m.theta0 - float(q[2]))
        if sign and sign != math.copysign(1.0, m.s1):
            step += SWITCH_COST
        out.append((m, rows[driven][-1], step))
    return out


def _heuristic(checker: Checker, space: Any, geometry: LatticeGeometry,
               xg: np.ndarray) -> Any:
    """The largest of the Reeds–Shepp distances (OMPL, radius ``d1 / tan max(HITCH_ANGLES)``)
    of trailer 1's and trailer 2's poses to theirs at the goal, and of their axle centres'
    grid distances among the obstacles
    (:func:`~nilpotent.planning.grid_distance.grid_distance`)."""
    a = space.allocState()
    goals, grids = [], []
    for which in (1, 2):
        g = space.allocState()
        x, y, th = _pose(xg, which, geometry)
        g.setX(x)
        g.setY(y)
        g.setYaw(th)
        goals.append(g)
        grids.append(grid_distance(checker.world, (x, y), GRID_RADIUS, GRID))

    def h(q: np.ndarray) -> float:
        best = 0.0
        for which, g, grid in zip((1, 2), goals, grids, strict=True):
            x, y, th = _pose(q, which, geometry)
            a.setX(x)
            a.setY(y)
            a.setYaw(th)
            best = max(best, float(space.distance(a, g)))
            if grid is not None:
                best = max(best, grid(x, y))
        return best

    return h


def lattice_path(checker: Checker, x0: np.ndarray, xg: np.ndarray, seconds: float,
                 seed: int | None = None, *args: Any, **kwargs: Any) -> LatticePath:
    """The lattice search for a path from ``x0`` to ``xg`` (module doc: grown from ``xg``,
    joined exactly to ``x0``) within ``seconds``.

    Extra arguments (those of :func:`~nilpotent.planning.holonomic_path.ompl_path`) are
    ignored: the search is deterministic and uses the checker's own validity.

    Raises
    ------
    OptionError
        The model is not a car with two trailers (:func:`lattice_geometry`).
    PlanningError
        Every reachable bin was expanded without joining the start exactly (one: no motion
        of the lattice leaves the goal, what constrains it there named).
    ComputationLimitError
        ``seconds`` ran out.
    """
    from ompl import base as ob

    del seed, args, kwargs
    t0 = time.perf_counter()
    geometry = lattice_geometry(checker.system, checker)
    x0, xg = np.asarray(x0, dtype=float), np.asarray(xg, dtype=float)
    # the search grows from the goal (in the parking slot, where room is scarce) and is
    # joined exactly to the start; the motions are reversible (a drive of -s1, a turn back)
    root, end = xg, x0
    space = ob.ReedsSheppStateSpace(HEURISTIC_RADIUS * geometry.hitches[1])
    h = _heuristic(checker, space, geometry, end)
    target = _reduced(end, geometry)
    # nodes: state, cost, parent, motion from the parent, direction of its drive
    states: list[np.ndarray] = [root]
    cost = [0.0]
    parent = [-1]
    via: list[_Motion | None] = [None]
    sign = [0.0]
    heap = [(HEURISTIC_WEIGHT * h(root), 0)]
    closed: set[tuple[int, ...]] = set()
    expanded = 0
    tried = 0
    approached: set[tuple[int, ...]] = set()
    while heap:
        if time.perf_counter() - t0 > seconds:
            raise ComputationLimitError(
                f"no path found within the budget: the lattice search for the car with two "
                f"trailers expanded {expanded} nodes in {seconds:.3g} s without joining the "
                "start; raise --time-limit (whether the goal can be reached was not decided)")
        budget.check("searching the lattice of exact motions")
        _, i = heapq.heappop(heap)
        q = states[i]
        r = _reduced(q, geometry)
        key = (round(r[0] / BIN_XY), round(r[1] / BIN_XY),
               round(math.remainder(r[2], 2 * math.pi) / BIN_ANGLE), round(r[3] / BIN_ANGLE))
        if key in closed:
            continue
        closed.add(key)
        expanded += 1
        if expanded % 200 == 0:
            report_progress(ProgressEvent("lattice nodes expanded", expanded, None,
                                          f"cost {cost[i]:.2f}, to go {h(q):.2f}"))
        clear = float(checker.measures(q[None, :])[0][0])
        margin = min(MARGIN, max(MIN_MARGIN, 0.45 * clear))
        gap = np.abs(r - target)
        gap[2] = abs(math.remainder(r[2] - target[2], 2 * math.pi))
        coarse = (round(r[0] / APPROACH_BIN), round(r[1] / APPROACH_BIN),
                  round(math.remainder(r[2], 2 * math.pi) / APPROACH_BIN),
                  round(r[3] / APPROACH_BIN))
        if float(gap.max()) <= GOAL_REGION or (
                clear >= APPROACH_CLEARANCE and coarse not in approached
                and gap[2] <= APPROACH_HEADING and abs(r[3]) <= APPROACH_HITCH):
            approached.add(coarse)
            tried += 1
            # from the start to the node (forward drives, better conditioned), else back
            for forward in (True, False):
                a, b = (end, q) if forward else (q, end)
                found = final_approach(checker, a, b, geometry, space)
                if found is not None:
                    return _result(i, found, forward, states, parent, via, geometry,
                                   expanded, t0, x0)
        for m, child, step in _children(checker, q, sign[i], geometry, margin):
            states.append(child)
            cost.append(cost[i] + step)
            parent.append(i)
            via.append(m)
            sign.append(math.copysign(1.0, m.s1))
            heapq.heappush(heap, (cost[-1] + HEURISTIC_WEIGHT * h(child), len(states) - 1))
    if expanded == 1:  # not "every reachable bin": no motion of the lattice leaves the goal
        raise PlanningError(
            f"no motion of the lattice search for the car with two trailers leaves the goal "
            f"(turns at rest to theta0 - theta1 in {list(HITCH_ANGLES)}, then drives of "
            f"+-{FORWARD_STEP:g} of trailer 1, margin {_margin(checker, root):.3g} from the "
            f"obstacles and bodies): at the goal {checker.constraints_near(root, 0.1)}")
    raise PlanningError(f"the lattice search for the car with two trailers expanded every "
                        f"reachable bin ({expanded}) without joining the start exactly "
                        f"({tried} tried)")


def _result(i: int, approach: list[_Motion], forward: bool, states: list[np.ndarray],
            parent: list[int], via: list[_Motion | None], geometry: LatticeGeometry,
            expanded: int, t0: float, x0: np.ndarray) -> LatticePath:
    """The path from ``x0``: the motions from the root (the goal) to node ``i`` run
    backwards (waypoints reversed, controls negated), after ``approach`` from ``x0`` to the
    node (``forward``) or before it, run backwards too (``approach`` from the node to
    ``x0``)."""
    search: list[_Motion] = []
    while parent[i] >= 0:
        m = via[i]
        assert m is not None
        search.append(m)
        i = parent[i]
    if forward:
        head, head_controls, head_length = _waypoints(x0, approach, geometry)
        back, controls, length = _waypoints(states[i], search[::-1], geometry)
    else:
        head, head_controls, head_length = [tuple(map(float, x0))], [], 0.0
        back, controls, length = _waypoints(states[i], search[::-1] + approach, geometry)
    back.reverse()
    head[0] = tuple(map(float, x0))
    points = head[:-1] + back  # the approach ends at the node within 1e-9
    controls = head_controls + [(-u[0], -u[1]) for u in reversed(controls)]
    length += head_length
    seconds = time.perf_counter() - t0
    return LatticePath(tuple(points), tuple(controls), length, expanded, seconds,
                       ((seconds, length),))


def _waypoints(q: np.ndarray, motions: Sequence[_Motion], geometry: LatticeGeometry) -> tuple[
        list[tuple[float, ...]], list[tuple[float, float]], float]:
    """Waypoints of ``motions`` from ``q`` (module doc), the controls between them, and
    trailer 1's arc length."""
    points = [tuple(map(float, q))]
    controls: list[tuple[float, float]] = []
    length = 0.0
    for m in motions:
        if abs(m.theta0 - float(q[2])) > 0:
            k = max(1, math.ceil(abs(m.theta0 - float(q[2])) / TURN_WAYPOINT_STEP))
            for th in np.linspace(float(q[2]), m.theta0, k + 1)[1:]:
                nxt = np.array(q, dtype=float)
                nxt[2] = th
                controls.append((0.0, float(th - q[2])))
                points.append(tuple(map(float, nxt)))
                q = nxt
        if m.s1 != 0.0:
            k = max(1, math.ceil(abs(m.s1) / WAYPOINT_STEP))
            ends = arc_states(q, np.linspace(0.0, m.s1, k + 1)[1:], geometry)
            for e in ends:
                controls.append(drive_controls(q, m.s1 / k, geometry))
                points.append(tuple(map(float, e)))
            q = ends[-1]
            length += abs(m.s1)
    return points, controls, length


def lattice_exact_piece(checker: Checker, x: np.ndarray, prev: np.ndarray, w: np.ndarray,
                        tol: float, points: int, path: LatticePath) -> Any:
    """The exact motion of ``path`` from waypoint ``prev`` to ``w`` (a turn at rest or a
    drive with ``φ1`` held) driven from the state ``x`` reached, if it lands within ``tol``
    of ``w`` and is admissible; else ``None`` (the piece is then steered).  A piece that only
    turns the car (``θ0``) is a turn at rest wherever it comes from (a halved turn).  Returns
    a :class:`~nilpotent.planning.iterative.Plan` of the piece."""
    from nilpotent.errors import IntegrationError
    from nilpotent.planning.controls import constant_segment
    from nilpotent.planning.iterative import Plan
    from nilpotent.planning.simulation import simulate_path
    from nilpotent.simulation.trajectory import Trajectory

    delta = np.asarray(w, dtype=float) - np.asarray(prev, dtype=float)
    if float(np.abs(np.delete(delta, 2)).max()) <= AT_REST:
        u = (0.0, float(w[2] - x[2]))
        points = max(points, math.ceil(abs(u[1]) / EXACT_STEP) + 1)
    else:
        key = tuple(map(float, prev)), tuple(map(float, w))
        pieces = dict(zip(zip(path.points[:-1], path.points[1:], strict=True), path.controls,
                          strict=True))
        found = pieces.get(key)
        if found is None:
            return None
        u = found
        points = max(points, math.ceil(abs(u[0]) / EXACT_STEP) + 1)
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
                initial_error=float(np.linalg.norm(np.asarray(w) - x)))
