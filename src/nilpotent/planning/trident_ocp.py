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
the world's bounds at every node, and its obstacles by separating lines: on each interval
the :data:`SLOTS` obstacles nearest the reference motion (a straight drive's roll-out),
each as a convex stand-in (:meth:`BodyPathSteering.separations`), lie beyond a line
``a · p = b`` (``|a| ≤ 1``, variables of the problem, one per interval and obstacle) that
every vertex and wheel keeps :data:`WORLD_MARGIN` from at every RK4 sub-step (the robot
lies in their convex hull; the separating-hyperplane form of the distance between convex
sets, Boyd & Vandenberghe, *Convex Optimization*, §8.2; TrajOpt, Schulman et al. 2014,
imposes collision avoidance per time step the same way).  Those constraints are
sufficient, not necessary, and hold at the sub-steps and nodes only (the first solver,
one line per obstacle and piece at the nodes, made pieces round a wall's end infeasible or
let a leg graze it between nodes: slalom 1 of 4 pairs); no leg balanced ahead of its
joint: a perturbation of a joint grows by at most ``e^``:data:`LEG_GROWTH` from any time of
the piece to its end (:meth:`BodyPathSteering._leg_rates`; without it the optimum drove a
corridor with a leg straight ahead, an unstable equilibrium whose end moved 5·10⁷ times a
change of that joint, beyond what any integrator certifies).  IPOPT starts from the line
of states from ``x`` to ``w`` (:meth:`BodyPathSteering.line`), then, if it finds no
solution, from a straight drive's roll-out.  The motion is checked afterwards
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
from nilpotent.planning.casadi_tree import casadi_module, to_casadi
from nilpotent.planning.controls import Segment, constant_segment
from nilpotent.planning.iterative import Plan
from nilpotent.planning.ocp_smooth import correct_endpoint, rk4_interval
from nilpotent.planning.simulation import PLANNING_SETTINGS, simulate_path
from nilpotent.planning.verify import Checker
from nilpotent.simulation.trajectory import Trajectory

__all__ = [
    "END_ROOM", "EPSILON", "FAR", "LEG_GAP", "MODELS", "PIECE", "REACH", "SHAPE_WEIGHT",
    "SLOTS", "TURN_WEIGHT", "VERTICES", "WORLD_MARGIN", "BodyPathSteering", "body_path_piece",
]

#: Models the steering applies to (body-velocity inputs: ``(u_1, u_2)`` is the body's velocity).
MODELS = ("trident-snake",)
#: Default longest piece (configuration-space length) of the holonomic path.
PIECE = 3.0
#: Shooting intervals of every piece (one IPOPT problem, built once per process).
INTERVALS = 24
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
#: Obstacles imposed on each interval of a piece (the nearest to the reference motion).
SLOTS = 3
#: Most vertices of an obstacle's convex stand-in (more: its least rotated rectangle).
VERTICES = 8
#: An unused slot's point lies this far away (model length).
FAR = 1e3
#: Distance the hull of the robot's vertices and wheels keeps from the obstacles.
WORLD_MARGIN = 0.05
#: Intervals next to a fixed end (the start; the last piece's goal) that keep only half
#: that end's clearance when it has less than :data:`WORLD_MARGIN`.
END_INTERVALS = 3
#: Obstacles further than this from an interval's reference motion are not imposed.
REACH = 3.0
#: Least distance from a wheel to another leg in the problem (model length).
LEG_GAP = 0.1
#: The limits are imposed tightened by this (rad).
LIMIT_MARGIN = 0.03
#: Most growth ``∫_t^T ∂φ̇_i/∂φ_i`` of a perturbation of a joint, from any time of a piece to
#: its end (:meth:`BodyPathSteering._leg_rates`): without it IPOPT balances a leg straight
#: ahead of its joint, an unstable equilibrium (a corridor plan whose end moved 5·10⁷ times
#: a change of φ₂ at the start, so that integrators at rtol 1e-12 disagreed by 1e-6 at the
#: end).
LEG_GROWTH = 2.0
#: Largest body displacement / turn per interval (RK4 accuracy).
STEP_BOUND = 0.25
#: Most seconds of one IPOPT solve under a time limit (less when less time is left: half
#: of it); without a time limit, :data:`NO_LIMIT` (the iterations bound it).
SOLVE_SECONDS = 20.0
NO_LIMIT = 1e6
#: The shorter wall times of a solve, when less than ``2 × SOLVE_SECONDS`` is left.
WALLS = (4.0, 1.0, 0.25)
#: Most IPOPT iterations per solve, and most Gauss–Newton corrections of the last piece.
IPOPT_ITERATIONS = 400
#: IPOPT's tolerance (the end is met to its constraint tolerance, then corrected).
IPOPT_TOL = 1e-3
#: IPOPT's options (besides its iterations and wall time).
IPOPT_OPTIONS = {"print_level": 0, "sb": "yes", "tol": IPOPT_TOL, "acceptable_tol": 1e-2,
                 "acceptable_iter": 5}
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
        self._obstacles: list[tuple[np.ndarray, float, Any]] | None = None
        q = self.ca.SX.sym("q", 6)
        self._gap = self.ca.Function("gaps", [q], [self.ca.vertcat(*self._gaps(q))])
        self._points = self.ca.Function("points", [q], [self.ca.vertcat(*self._corners(q))])
        self.solves = 0
        self.seconds = 0.0
        #: Why the last piece was handed back (``""`` when it was driven).
        self.reason = ""

    def _separation(self, n_int: int) -> Any:
        """``(points (12, SUBSTEPS), a, b, stand-in (2V + 1), margin) ↦`` the slacks
        ``a · p − b − margin`` of every vertex and wheel ``p`` of an interval's sub-step
        states, and ``b − a · v − ρ`` of the stand-in's vertices (all ``≥ 0``)."""
        ca = self.ca
        pts, a, b = ca.SX.sym("p", 12, SUBSTEPS), ca.SX.sym("a", 2), ca.SX.sym("b")
        o, m = ca.SX.sym("o", 2 * VERTICES + 1), ca.SX.sym("m")
        robot = a[0] * pts[:6, :] + a[1] * pts[6:, :] - b - m
        stand = b - a[0] * o[:VERTICES] - a[1] * o[VERTICES:2 * VERTICES] - o[-1]
        return ca.Function("separation", [pts, a, b, o, m], [ca.vertcat(ca.vec(robot), stand)])

    def _leg_rates(self) -> Any:
        """``(q, u) ↦ (∂φ̇_i/∂φ_i)_{i=1..3}``: the growth rate of a perturbation of each
        joint.  Given the body velocities, each ``φ_i`` obeys a scalar equation
        ``φ̇_i = g_i(φ_i, θ, u)`` and the pose does not depend on the joints, so a change
        ``δ`` of ``φ_i`` at ``t`` reaches the end as ``δ exp(∫_t^T ∂g_i/∂φ_i)``: a leg
        pushed ahead of its joint (a leading caster) grows it like ``e^{|v| t / l}``."""
        ca, system = self.ca, self.checker.system
        q, v = ca.SX.sym("q", system.n), ca.SX.sym("v", system.m)
        symbols = {c: q[i] for i, c in enumerate(system.coordinates)}
        cols = [ca.vertcat(*[to_casadi(e, symbols) for e in fld])
                for fld in system.specialized_fields]
        f: Any = sum((cols[i] * v[i] for i in range(1, system.m)), cols[0] * v[0])
        return ca.Function("leg_rates", [q, v],
                           [ca.vertcat(*[ca.jacobian(f[3 + i], q[3 + i]) for i in range(3)])])

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

    def _stand_ins(self) -> list[tuple[np.ndarray, float, Any]]:
        """The world's obstacles as convex stand-ins ``(vertices (V, 2), radius, shapely
        shape)``: a polygon's convex hull (its least rotated rectangle when the hull has more
        than :data:`VERTICES` vertices), a disc's centre repeated with its radius; a
        superset of the obstacle, so that keeping clear of it is sufficient."""
        if self._obstacles is not None:
            return self._obstacles
        out: list[tuple[np.ndarray, float, Any]] = []
        world = self.checker.world
        for poly in () if world is None else world.polygons:
            hull: Any = shapely.Polygon(poly).convex_hull
            if len(hull.exterior.coords) - 1 > VERTICES:
                hull = hull.minimum_rotated_rectangle
            v = np.array(hull.exterior.coords)[:-1]
            v = np.vstack([v, np.repeat(v[-1:], VERTICES - len(v), axis=0)])
            out.append((v, 0.0, hull))
        for c, r in () if world is None else world.discs:
            out.append((np.tile(np.asarray(c, float), (VERTICES, 1)), float(r),
                        shapely.Point(c).buffer(r, 64)))
        self._obstacles = out
        return out

    def separations(self, x: np.ndarray, w: np.ndarray, states: np.ndarray,
                    final: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                          np.ndarray, int]:
        """The obstacles imposed on each interval and a first guess of the lines that
        separate them from the robot, along the reference ``states`` (6, N + 1).

        For interval ``k``, the :data:`SLOTS` stand-ins (:meth:`_stand_ins`) nearest the
        convex hull of the robot's vertices and wheels at the reference's nodes ``k`` and
        ``k + 1``, within :data:`REACH`; each is kept at least the margin away from the
        hull of the robot at every RK4 sub-step of the interval by a line ``a · p = b``
        (``|a| ≤ 1``) of the problem's variables: every vertex and wheel ``a · p ≥ b +
        margin``, the stand-in ``a · v + ρ ≤ b`` (the separating-hyperplane form of the
        distance between convex sets, Boyd & Vandenberghe, *Convex Optimization*, §8.2).
        An unused slot is a point :data:`FAR` away.

        Returns ``(obstacles (2V + 1, S·N), a₀ (2, S·N), b₀ (1, S·N), box (4,), margins
        (1, S·N), S)``, column ``s·N + k`` for slot ``s`` of interval ``k`` (one unused
        column when ``S = 0``: no obstacle within reach); ``box``: the bounds less
        :data:`WORLD_MARGIN`, widened to hold the fixed ends (``±FAR`` without bounds);
        ``margins``: :data:`WORLD_MARGIN`, or, on the :data:`END_INTERVALS` intervals next
        to a fixed end (``x``; ``w`` when ``final``), half that end's clearance when less.
        """
        n_int = states.shape[1] - 1
        shapes = self._stand_ins()

        def hull(q: np.ndarray) -> Any:
            p = np.asarray(self._corners(q, np))
            return shapely.MultiPoint(np.column_stack([p[:6], p[6:]])).convex_hull

        hulls = [hull(q) for q in states.T]
        # the fixed ends (the start; the goal of the last piece, whose shape is fixed too)
        # keep half their clearance near them when they have less than the margin
        ends = [WORLD_MARGIN, WORLD_MARGIN]
        for e, h in enumerate((hulls[0], hull(w)) if final else (hulls[0],)):
            for _, _, g in shapes:
                ends[e] = min(ends[e], 0.5 * float(h.distance(g)))
        steps = np.arange(n_int)
        margins = np.where(steps < END_INTERVALS, ends[0], WORLD_MARGIN)
        margins = np.where(steps >= n_int - END_INTERVALS, np.minimum(margins, ends[1]), margins)
        segs, chosen = [], []
        for k in range(n_int):
            seg = shapely.union_all([hulls[k], hulls[k + 1]]).convex_hull
            near = sorted((float(seg.distance(g)), i) for i, (_, _, g) in enumerate(shapes))
            segs.append(seg)
            chosen.append([i for d, i in near if d <= REACH][:SLOTS])
        slots = max(len(c) for c in chosen)
        cols = max(1, slots * n_int)
        obs = np.zeros((2 * VERTICES + 1, cols))
        a0, b0 = np.zeros((2, cols)), np.zeros((1, cols))
        for k, seg in enumerate(segs):
            centre = np.array(seg.centroid.coords[0])
            for s in range(slots):
                col = s * n_int + k
                if s >= len(chosen[k]):
                    obs[:VERTICES, col] = centre[0] + FAR
                    obs[VERTICES:2 * VERTICES, col] = centre[1]
                    a0[:, col] = (-1.0, 0.0)
                    b0[0, col] = -(centre[0] + FAR / 2)
                    continue
                v, rho, g = shapes[chosen[k][s]]
                obs[:VERTICES, col], obs[VERTICES:2 * VERTICES, col] = v[:, 0], v[:, 1]
                obs[-1, col] = rho
                dist = float(seg.distance(g))
                if dist > 0:
                    p_near, o_near = shapely.ops.nearest_points(seg, g)
                    n = np.array([p_near.x - o_near.x, p_near.y - o_near.y]) / dist
                    o = np.array([o_near.x, o_near.y])
                else:  # the reference meets it: away from its centre
                    o = np.array(g.centroid.coords[0])
                    n = centre - o
                    n = n / (np.linalg.norm(n) or 1.0)
                    o = o + n * float(np.max((v - o) @ n) + rho)
                a0[:, col] = n
                b0[0, col] = float(n @ o) + 0.5 * dist
        box = np.array([-FAR, FAR, -FAR, FAR])
        world = self.checker.world
        if world is not None and world.bounds is not None:
            (xlo, xhi), (ylo, yhi) = world.bounds
            ext = np.array([self._corners(q, np) for q in ((x, w) if final else (x,))])
            m = WORLD_MARGIN
            box = np.array([min(xlo + m, ext[:, :6].min()), max(xhi - m, ext[:, :6].max()),
                            min(ylo + m, ext[:, 6:].min()), max(yhi - m, ext[:, 6:].max())])
        margins = np.tile(margins, slots)[None, :] if slots else np.zeros((1, 1))
        return obs, a0, b0, box, margins, slots

    def line(self, x: np.ndarray, w: np.ndarray, n_int: int) -> tuple[np.ndarray, np.ndarray]:
        """The states on the segment from ``x`` to ``w`` (the shape too) at the nodes and the
        body velocities that move the pose along it: ``(controls (3, N), states (6, N + 1))``
        (not a motion of the robot: a start for IPOPT, which pieces that fail from the
        roll-out of :meth:`_guess` mostly solve from)."""
        states = x[:, None] + (w - x)[:, None] * np.linspace(0.0, 1.0, n_int + 1)[None, :]
        v = np.diff(states[:3], axis=1) * n_int  # world velocity and turning rate
        th = states[2, :-1]
        u = np.vstack([np.cos(th) * v[0] + np.sin(th) * v[1],
                       -np.sin(th) * v[0] + np.cos(th) * v[1], v[2]])
        return u, states

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
            states = self.line(x, w, n_int)[1]
        return u, states

    def _solver(self, n_int: int, final: bool, wall: float, slots: int) -> Any:
        """IPOPT on the problem of the module doc with ``N = n_int`` and ``slots`` obstacles
        per interval, as a CasADi function ``(x, w, lower limits, upper limits, least gap²,
        stand-ins, box, margins, U₀, X₀, a₀, b₀) ↦ (U, X)`` (:meth:`casadi.Opti.to_function`;
        the arrays of :meth:`separations`), built once per ``(N, final, wall, slots)``."""
        key = (self.r, self.l, tuple(self.bounds), n_int, final, wall, slots)
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
        cols = max(1, slots * n_int)  # (one unused column without obstacles)
        obs, box, margin = opti.parameter(2 * VERTICES + 1, cols), opti.parameter(4), \
            opti.parameter(1, cols)
        sep_a, sep_b = opti.variable(2, cols), opti.variable(1, cols)
        if not slots:
            opti.subject_to(ca.vec(sep_a) == 0)
            opti.subject_to(sep_b == 0)
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
        # the world: the sub-step states' vertices and wheels inside the bounds, and each
        # interval's stand-ins beyond its separating lines (:meth:`separations`)
        nodes = self._points.map(n_int)(xs[:, 1:])  # (12, N)
        opti.subject_to(opti.bounded(box[0], ca.vec(nodes[:6, :]), box[1]))
        opti.subject_to(opti.bounded(box[2], ca.vec(nodes[6:, :]), box[3]))
        if slots:
            pts = self._points.map(n_int * SUBSTEPS)(subs)  # (12, N·SUBSTEPS)
            opti.subject_to(ca.vec(self._separation(n_int).map(cols)(
                ca.repmat(pts, 1, slots), sep_a, sep_b, obs, margin)) >= 0)
            opti.subject_to(ca.vec(sep_a[0, :] ** 2 + sep_a[1, :] ** 2) <= 1)
        # every leg's perturbation grows by at most e^LEG_GROWTH from any time to the end
        # (trapezoid rule on the nodes; suffix sums by an upper-triangular matrix of ones)
        rates = self._leg_rates().map(n_int)
        lam = 0.5 * h * (rates(xs[:, :n_int], us) + rates(xs[:, 1:], us))  # (3, N)
        suffix = ca.DM(np.tril(np.ones((n_int, n_int))))  # [j, k] = 1 for j >= k
        opti.subject_to(ca.vec(ca.mtimes(lam, suffix)) <= LEG_GROWTH)
        bound = STEP_BOUND * n_int
        opti.subject_to(opti.bounded(-bound, us, bound))
        opti.solver("ipopt", {"print_time": False, "expand": True, "error_on_fail": False},
                    {**IPOPT_OPTIONS, "max_iter": IPOPT_ITERATIONS, "max_wall_time": wall})
        solver = opti.to_function(
            "trident_piece", [x, w, lo, hi, least, obs, box, margin, us, xs, sep_a, sep_b],
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
        # no time limit: IPOPT_ITERATIONS bounds the solve; else at most SOLVE_SECONDS, or
        # the largest of WALLS within half the time left (each wall time is a solver of
        # its own, built once: few of them)
        wall = (NO_LIMIT if not math.isfinite(left) else
                next((t for t in (SOLVE_SECONDS, *WALLS) if t <= 0.5 * left), WALLS[-1]))
        # the limits tightened, but not past the fixed ends (the start; the last piece's goal)
        ends = (x, w) if final else (x,)
        lo = [min(lo + LIMIT_MARGIN, *(float(q[j]) for q in ends)) for j, lo, _ in self.bounds]
        hi = [max(hi - LIMIT_MARGIN, *(float(q[j]) for q in ends)) for j, _, hi in self.bounds]
        start_gap = float(np.sqrt(np.min(np.array(self._gap(x)))))
        if final:  # the goal's own legs' gap too
            start_gap = min(start_gap, float(np.sqrt(np.min(np.array(self._gap(w))))))
        least = min(LEG_GAP, 0.5 * start_gap) ** 2
        u0, s0 = self._guess(x, w, n_int) if warm is None else warm
        obs, a0, b0, box, margin, slots = self.separations(x, w, s0, final)
        solver = self._solver(n_int, final, wall, slots)
        t0 = time.perf_counter()
        self.solves += 1
        try:
            u_out, _ = solver(x, w, lo, hi, least, obs, box, margin, u0, s0, a0, b0)
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
    # from the line of states first, then (where IPOPT did not run out of time) from the
    # roll-out of a straight drive: each solves pieces that the other finds infeasible
    u, status = steering.solve(x, w, final, n_int, steering.line(x, w, n_int))
    if u is None and "Time" not in status:
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
