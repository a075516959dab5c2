r"""The trident snake's pieces steered by direct optimal control of its body path.

:func:`~nilpotent.planning.global_planner.plan_global` with ``planner="trident-ocp"``
(``trident-snake`` only) finds its holonomic path as ``"rrtconnect"`` does (the legs held
straight, the body's pose searched), cuts it into pieces of at most :data:`PIECE` (or
``--max-piece``, if longer), and drives every piece by :func:`body_path_piece`: the
multiple-shooting problem

.. math::

    \min_u \sum_{k<N} h\sqrt{v_{1,k}^2 + v_{2,k}^2 + \varepsilon^2}
    + \mu\, h \sum_{k<N} v_{3,k}^2 + \lambda\,|\varphi(1)|^2
    \quad\text{s.t.}\quad \dot q = \sum_i u_i X_i(q),\ q(0) = x,

on ``N`` equal intervals of ``[0, 1]`` (``h = 1/N``, controls constant on each, flow by
RK4 sub-steps), ``v = (u_1, u_2)`` the body's velocity (its speed is the speed of the
body centre: the cost is the centre's path length, smoothed by :data:`EPSILON`),
``μ`` (:data:`TURN_WEIGHT`) a small price on turning, which alone moves no body path;
the end: the waypoint's pose ``(x, y, θ)`` with the shape free (``λ``
(:data:`SHAPE_WEIGHT`) pulls it towards the star ``φ = 0``, inside the limits by
:data:`END_ROOM`), the whole goal for the last piece; the joint limits at every RK4
sub-step (tightened by :data:`LIMIT_MARGIN`); no leg touching another
(``dist(W_i, leg_j) ≥`` :data:`LEG_GAP` for every ordered pair at every node: a leg's only
free end is its wheel, a vertex is ``√3 r − l``-far from another leg when ``l < √3 r``);
the world's obstacles and bounds as at most :data:`MAX_PLANES` half-planes
(:meth:`BodyPathSteering.planes`) that every vertex and wheel keeps to at every node (the
robot is inside their convex hull).  Those constraints are sufficient, not necessary, and
hold at the nodes only: the motion is checked afterwards
(:meth:`~nilpotent.planning.verify.Checker.valid_motion`, 20 samples per interval) and a
piece that fails, or that IPOPT does not solve within :data:`SOLVE_SECONDS`
(:data:`IPOPT_ITERATIONS` without a time limit), is handed back (``None``, the reason in
:attr:`BodyPathSteering.reason`), to be steered by the nilpotent steering and halved as
usual.  The whole plan is re-simulated and verified as every plan is.

Why (measured, ``benchmarks/trident_free_ocp.py``, benchmarks/RESULTS.md): between two
star shapes in free space the least body path found is 1.02–1.15 × the distance for
distances 3–10 (80 intervals; 1.08–1.4 at distance 1), while the nilpotent steering of
pieces pays about 20× (each piece corrects the shape by loops whose body path grows like
their size).  The optimum drives nearly straight, the
legs trailing, and restores the shape by turning the body in place (``u = (0, 0, v_3)``:
``φ̇_i = −(r cos φ_i + l) v_3 / l``, no body path) and by short moves where the legs are
folded.

The endpoint of the last piece is corrected by Gauss–Newton on the product's own
re-simulation (:func:`~nilpotent.planning.ocp_smooth.correct_endpoint`), so the plan
meets any ``tol`` that the RK4 model's Jacobian can reach.  CasADi is the optional extra
``ocp``.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import shapely
import shapely.ops

from nilpotent.errors import ComputationLimitError, IntegrationError, OptionError
from nilpotent.planning import budget
from nilpotent.planning.casadi_tree import casadi_module
from nilpotent.planning.controls import Segment, constant_segment
from nilpotent.planning.iterative import Plan
from nilpotent.planning.ocp_smooth import correct_endpoint, rk4_interval
from nilpotent.planning.simulation import PLANNING_SETTINGS, simulate_path
from nilpotent.planning.verify import Checker
from nilpotent.simulation.trajectory import Trajectory

__all__ = [
    "END_ROOM", "EPSILON", "LEG_GAP", "MAX_PLANES", "MODELS", "PIECE", "REACH", "SHAPE_WEIGHT",
    "TURN_WEIGHT", "WORLD_MARGIN", "BodyPathSteering", "body_path_piece",
]

#: Models the steering applies to (body-velocity inputs: ``(u_1, u_2)`` is the body's velocity).
MODELS = ("trident-snake",)
#: Default longest piece (configuration-space length) of the holonomic path.
PIECE = 3.0
#: Shooting intervals of every piece (one IPOPT problem, built once per process).
INTERVALS = 36
#: RK4 steps per interval.
SUBSTEPS = 3
#: Smoothing of the speed ``√(|v|² + ε²)`` (model length per unit time of the horizon).
EPSILON = 0.1
#: Price of turning ``μ ∫ v_3² dt`` (turning alone moves no body path).
TURN_WEIGHT = 1e-4
#: Pull of an intermediate end's shape towards the star, ``λ |φ(1)|²``.
SHAPE_WEIGHT = 0.3
#: An intermediate end's joints stay this far inside their limits (rad): room for the next.
END_ROOM = 1.0
#: Most half-planes of the world imposed on a piece (the nearest obstacles and bounds).
MAX_PLANES = 6
#: Distance the robot's vertices and wheels keep from those half-planes' obstacles.
WORLD_MARGIN = 0.05
#: Obstacles further than this from a piece's chord (body centre) are not imposed.
REACH = 4.0
#: Least distance from a wheel to another leg in the problem (model length).
LEG_GAP = 0.1
#: The limits are imposed tightened by this (rad).
LIMIT_MARGIN = 0.03
#: Largest body displacement / turn per interval (RK4 accuracy).
STEP_BOUND = 0.25
#: Most seconds of one IPOPT solve under a time limit (less when less time is left: half
#: of it); without a time limit, :data:`NO_LIMIT` (the iterations bound it).
SOLVE_SECONDS = 20.0
NO_LIMIT = 1e6
#: Most IPOPT iterations per solve, and most Gauss–Newton corrections of the last piece.
IPOPT_ITERATIONS = 400
#: IPOPT's tolerance (the end is met to its constraint tolerance, then corrected).
IPOPT_TOL = 1e-4
CORRECTIONS = 8


#: The IPOPT problems built so far, by model lengths, limits, ``N``, ``final`` and wall time.
_SOLVERS: dict[tuple[Any, ...], Any] = {}


def _check_model(checker: Checker) -> None:
    system = checker.system
    if system.name not in MODELS:
        raise OptionError(f"--planner trident-ocp applies to {', '.join(MODELS)}, not "
                          f"{system.name}")


class BodyPathSteering:
    """The CasADi flow and constraints of the trident snake, built once per plan.

    Parameters
    ----------
    checker : Checker
        The model (``trident-snake``: coordinates ``x, y, theta, phi1..phi3``, parameters
        ``r``, ``l``) with its limits and world.

    Raises
    ------
    OptionError
        Another model.
    MissingExtraError
        CasADi is not installed (the ``ocp`` extra).
    """

    def __init__(self, checker: Checker) -> None:
        _check_model(checker)
        self.ca = casadi_module()
        self.checker = checker
        values = checker.system.parameter_values
        self.r, self.l = float(values.get("r", 1)), float(values.get("l", 1))
        assert checker.limits is not None
        names = checker.system.coordinate_names
        self.bounds = [(names.index(k), lo, hi) for k, lo, hi in checker.limits.bounds]
        self._flows: dict[int, Any] = {}
        q = self.ca.SX.sym("q", 6)
        self._gap = self.ca.Function("gaps", [q], [self.ca.vertcat(*self._gaps(q))])
        self._points = self.ca.Function("points", [q], [self.ca.vertcat(*self._corners(q))])
        self.solves = 0
        self.seconds = 0.0
        #: Why the last piece was handed back (``""`` when it was driven).
        self.reason = ""

    def _flow(self, n_int: int) -> Any:
        if n_int not in self._flows:
            ca = self.ca
            system = self.checker.system
            x = ca.SX.sym("x", system.n)
            u = ca.SX.sym("u", system.m)
            z, subs = rk4_interval(ca, system, x, lambda t: u, 0.0, 1.0 / (n_int * SUBSTEPS),
                                   SUBSTEPS)
            self._flows[n_int] = ca.Function("step", [x, u], [z, ca.horzcat(*subs)])
        return self._flows[n_int]

    def _gaps(self, q: Any) -> list[Any]:
        """Squared distances wheel ``i`` – leg ``j`` (``i ≠ j``) of the CasADi state ``q``."""
        ca, r, l = self.ca, self.r, self.l
        legs = []
        for i in range(3):
            a = q[2] + 2 * math.pi * i / 3
            vx, vy = q[0] + r * ca.cos(a), q[1] + r * ca.sin(a)
            legs.append(((vx, vy), (vx + l * ca.cos(a + q[3 + i]), vy + l * ca.sin(a + q[3 + i]))))
        out = []
        for i in range(3):
            for j in range(3):
                if i == j:
                    continue
                (px, py), ((ax, ay), (bx, by)) = legs[i][1], legs[j]
                dx, dy = bx - ax, by - ay
                t = ca.fmin(1.0, ca.fmax(0.0, ((px - ax) * dx + (py - ay) * dy) / (l * l)))
                ex, ey = px - ax - t * dx, py - ay - t * dy
                out.append(ex * ex + ey * ey)
        return out

    def _corners(self, q: Any, lib: Any = None) -> list[Any]:
        """The x then the y coordinates of the 3 vertices and 3 wheels of state ``q``
        (CasADi, or numpy with ``lib=np``): the robot is inside their convex hull."""
        lib = self.ca if lib is None else lib
        xs_, ys_ = [], []
        for i in range(3):
            a = q[2] + 2 * math.pi * i / 3
            xs_.append(q[0] + self.r * lib.cos(a))
            ys_.append(q[1] + self.r * lib.sin(a))
        for i in range(3):
            a = q[2] + 2 * math.pi * i / 3
            xs_.append(xs_[i] + self.l * lib.cos(a + q[3 + i]))
            ys_.append(ys_[i] + self.l * lib.sin(a + q[3 + i]))
        return xs_ + ys_

    def planes(self, x: np.ndarray, w: np.ndarray) -> np.ndarray:
        """Half-planes ``a · p ≥ b`` (rows ``(a_x, a_y, b)``, :data:`MAX_PLANES` of them) that
        keep the robot's vertices and wheels, hence the robot, off the world's obstacles
        and inside its bounds near the piece from ``x`` to ``w``: for each obstacle within
        :data:`REACH` of the chord of the body centre, the line through its point nearest
        the chord, normal to that direction, moved :data:`WORLD_MARGIN` off it (less where
        the robot at ``x`` or at ``w`` is nearer: the piece's ends must satisfy them); for
        the bounds, their sides.  A sufficient condition (the obstacle lies beyond its
        line), not a necessary one; unused rows are ``(0, 0, −1)``."""
        out = np.tile([0.0, 0.0, -1.0], (MAX_PLANES, 1))
        world = self.checker.world
        if world is None:
            return out
        chord = shapely.LineString([x[:2], w[:2]]) if np.any(x[:2] != w[:2]) else \
            shapely.Point(x[:2])
        cands: list[tuple[float, np.ndarray, float]] = []
        shapes = [shapely.Polygon(p) for p in world.polygons]
        shapes += [shapely.Point(c).buffer(r, 64) for c, r in world.discs]
        for g in shapes:
            dist = float(chord.distance(g))
            if 0 < dist <= REACH:
                near_c, near_o = shapely.ops.nearest_points(chord, g)
                n = np.array([near_c.x - near_o.x, near_c.y - near_o.y]) / dist
                cands.append((dist, n, float(n @ [near_o.x, near_o.y]) + WORLD_MARGIN))
        if world.bounds is not None:
            (xlo, xhi), (ylo, yhi) = world.bounds
            for n, b in (((1.0, 0.0), xlo), ((-1.0, 0.0), -xhi), ((0.0, 1.0), ylo),
                         ((0.0, -1.0), -yhi)):
                nn = np.array(n)
                dist = float(min(nn @ x[:2], nn @ w[:2]) - b)
                if dist <= REACH:
                    cands.append((dist, nn, b + WORLD_MARGIN))
        ends = np.array([self._corners(q, np) for q in (x, w)])  # (2, 12)
        for k, (_, n, b) in enumerate(sorted(cands, key=lambda c: c[0])[:MAX_PLANES]):
            least = float(np.min(n[0] * ends[:, :6] + n[1] * ends[:, 6:]))
            out[k] = (n[0], n[1], min(b, least - 1e-6))
        return out

    def _guess(self, x: np.ndarray, w: np.ndarray, n_int: int) -> tuple[np.ndarray, np.ndarray]:
        """A straight drive at a constant world direction and turning rate, its RK4
        roll-out (the legs trail): ``(controls (3, N), states (6, N + 1))``."""
        d = w[:2] - x[:2]
        heading = math.atan2(float(d[1]), float(d[0]))
        t = (np.arange(n_int) + 0.5) / n_int
        th = x[2] + (w[2] - x[2]) * t
        dist = float(np.hypot(*d))
        u = np.vstack([dist * np.cos(heading - th), dist * np.sin(heading - th),
                       np.full(n_int, float(w[2] - x[2]))])
        roll = self._flow(n_int).mapaccum(n_int)(x, u)[0]
        states = np.hstack([x[:, None], np.array(roll)])
        if not np.all(np.isfinite(states)):
            states = x[:, None] + (w - x)[:, None] * np.linspace(0, 1, n_int + 1)[None, :]
        return u, states

    def _solver(self, n_int: int, final: bool, wall: float) -> Any:
        """IPOPT on the problem of the module doc with ``N = n_int``, as a CasADi function
        ``(x, w, lower limits, upper limits, least gap², U₀, X₀) ↦ (U, X, success)``
        (:meth:`casadi.Opti.to_function`), built once per ``(N, final)`` (or for a shorter
        ``wall``)."""
        key = (self.r, self.l, tuple(self.bounds), n_int, final, wall)
        if key in _SOLVERS:
            return _SOLVERS[key]
        ca = self.ca
        step = self._flow(n_int)
        opti = ca.Opti()
        xs = opti.variable(6, n_int + 1)
        us = opti.variable(3, n_int)
        x, w = opti.parameter(6), opti.parameter(6)
        nb = len(self.bounds)
        lo, hi, least = opti.parameter(nb), opti.parameter(nb), opti.parameter()
        planes = opti.parameter(MAX_PLANES, 3)
        h = 1.0 / n_int
        cost = h * ca.sum2(ca.sqrt(us[0, :] ** 2 + us[1, :] ** 2 + EPSILON ** 2))
        cost += TURN_WEIGHT * h * ca.sumsqr(us[2, :])
        if not final:
            cost += SHAPE_WEIGHT * ca.sumsqr(xs[3:, n_int])
        opti.minimize(cost)
        nxt, subs = step.map(n_int)(xs[:, :n_int], us)
        opti.subject_to(xs[:, 0] == x)
        opti.subject_to(xs[:, 1:] == nxt)
        opti.subject_to((xs[:, n_int] if final else xs[:3, n_int]) == (w if final else w[:3]))
        for k, (j, lo_k, hi_k) in enumerate(self.bounds):
            opti.subject_to(opti.bounded(lo[k], subs[j, :], hi[k]))
            if not final:
                opti.subject_to(opti.bounded(lo_k + END_ROOM, xs[j, n_int], hi_k - END_ROOM))
        opti.subject_to(ca.vec(self._gap.map(n_int)(xs[:, 1:])) >= least)
        pts = self._points.map(n_int)(xs[:, 1:])  # (12, N): x then y of 3 vertices, 3 wheels
        for k in range(MAX_PLANES):
            side = planes[k, 0] * pts[:6, :] + planes[k, 1] * pts[6:, :] - planes[k, 2]
            opti.subject_to(ca.vec(side) >= 0)
        bound = STEP_BOUND * n_int
        opti.subject_to(opti.bounded(-bound, us, bound))
        opti.solver("ipopt", {"print_time": False, "expand": True, "error_on_fail": False},
                    {"print_level": 0, "max_iter": IPOPT_ITERATIONS, "tol": IPOPT_TOL, "sb": "yes",
                     "acceptable_tol": 1e-3, "acceptable_iter": 5,
                     "max_wall_time": wall})
        solver = opti.to_function("trident_piece", [x, w, lo, hi, least, planes, us, xs],
                                  [us, xs])
        _SOLVERS[key] = solver
        return solver

    def solve(self, x: np.ndarray, w: np.ndarray, final: bool, n_int: int,
              warm: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray | None, str]:
        """IPOPT on the problem of the module doc from ``x`` to ``w``: ``(controls (3, N) or
        None, IPOPT's status)``; ``final``: the end is all of ``w`` (else its pose);
        ``warm``: the start ``(controls (3, N), states (6, N + 1))`` (default: a straight
        drive's roll-out)."""
        left = budget.seconds_left()
        # no time limit: IPOPT_ITERATIONS bounds the solve; else at most SOLVE_SECONDS
        # (a power of 2 below that: each wall time is a solver of its own, built once)
        wall = (NO_LIMIT if not math.isfinite(left) else SOLVE_SECONDS
                if 0.5 * left >= SOLVE_SECONDS else 2.0 ** math.floor(math.log2(
                    max(0.125, 0.5 * left))))
        solver = self._solver(n_int, final, wall)
        lo = [min(lo + LIMIT_MARGIN, float(x[j])) for j, lo, _ in self.bounds]
        hi = [max(hi - LIMIT_MARGIN, float(x[j])) for j, _, hi in self.bounds]
        start_gap = float(np.sqrt(np.min(np.array(self._gap(x)))))
        least = min(LEG_GAP, 0.5 * start_gap) ** 2
        u0, s0 = self._guess(x, w, n_int) if warm is None else warm
        t0 = time.perf_counter()
        self.solves += 1
        try:
            u_out, _ = solver(x, w, lo, hi, least, self.planes(x, w), u0, s0)
            stats = solver.stats()
        except RuntimeError as exc:
            self.seconds += time.perf_counter() - t0
            return None, f"failed: {exc}"[:120]
        self.seconds += time.perf_counter() - t0
        status = str(stats.get("return_status", ""))
        if not stats.get("success", False):
            return None, status
        return np.array(u_out, dtype=float).reshape(3, n_int), status

    def correct(self, x: np.ndarray, w: np.ndarray, u: np.ndarray, tol: float) -> tuple[
            np.ndarray, float]:
        """Gauss–Newton on the endpoint (the product's re-simulation, the RK4 Jacobian)."""
        ca = self.ca
        n_int = u.shape[1]
        sym = ca.SX.sym("u", 3, n_int)
        end = self._flow(n_int).mapaccum(n_int)(ca.DM(x), sym)[0][:, -1]
        jac = ca.Function("endpoint_jacobian", [sym], [ca.jacobian(end, ca.vec(sym))])
        return correct_endpoint(self.checker.system, x, w, u, jac, _segments, tol,
                                PLANNING_SETTINGS, CORRECTIONS,
                                "correcting the endpoint of a trident piece")


def _segments(u: np.ndarray) -> list[Segment]:
    n_int = u.shape[1]
    return [constant_segment(u[:, k], 1.0 / n_int) for k in range(n_int)]


def body_path_piece(steering: BodyPathSteering, x: np.ndarray, w: np.ndarray, tol: float,
                    points: int, final: bool) -> Plan | None:
    """The piece from state ``x`` to waypoint ``w`` by the optimal control of the module
    doc, if IPOPT solves it and the re-simulated motion is admissible; else ``None``.

    Parameters
    ----------
    steering : BodyPathSteering
        The plan's CasADi functions.
    x, w : ndarray, shape (6,)
        The state reached and the next waypoint (model coordinates).
    tol : float
        How close the end must come: to ``w`` itself when ``final``, else to its pose
        ``(x, y, θ)`` (the shape is left free; :attr:`Plan.error` is then the pose's
        error when within ``tol``, so that the piece counts as reached).
    points : int
        Samples per segment of the motion's check (``points // 2`` per interval).
    final : bool
        The last piece (the whole goal).

    Returns
    -------
    Plan or None
        The piece's controls (``N`` constant segments of duration ``1/N``), re-simulated
        by the product's integrator and checked by ``steering.checker``.
    """
    checker = steering.checker
    n_int = INTERVALS
    budget.check("steering a trident piece by optimal control")
    u, status = steering.solve(x, w, final, n_int)
    if u is None:
        steering.reason = f"IPOPT found no solution ({status})"
        return None
    try:
        if final:
            u, _err = steering.correct(x, w, u, tol)
        segs = _segments(u)
        times, states = simulate_path(checker.system, x, segs, max(4, points // 2))
    except (IntegrationError, ComputationLimitError) as exc:
        steering.reason = f"the piece's controls cannot be re-simulated: {exc}"
        return None
    reached = states[-1]
    miss = reached - w if final else np.concatenate([reached[:3] - w[:3], np.zeros(3)])
    error = float(np.linalg.norm(miss))
    if not error <= tol:
        steering.reason = f"the re-simulated piece misses its end by {error:.3g} > {tol:g}"
        return None
    if not checker.valid_motion(states):
        clear, margin, _ = checker.measures(states)
        steering.reason = (f"the piece's motion is not admissible (least clearance "
                           f"{clear.min():.3g}, limit margin {margin.min():.3g}, "
                           f"self-clearance {checker.self_clearance(states).min():.3g} at its "
                           "samples, with margins for the motion between them)")
        return None
    steering.reason = ""
    return Plan(checker.system, tuple(map(float, x)), tuple(map(float, w)), tuple(segs),
                tuple(map(float, reached)), error, (), Trajectory(times, states), tol=tol,
                initial_error=float(np.linalg.norm(w - x)))
