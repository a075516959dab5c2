r"""Asymptotically optimal holonomic stage: OMPL RRT* under a sub-Riemannian cost (ball–box).

:func:`nilpotent.planning.global_planner.plan_global` with ``planner="rrtstar"``
finds its configuration-space path with OMPL's RRT* (Karaman & Frazzoli,
"Sampling-based algorithms for optimal motion planning", IJRR 30(7), 2011)
instead of RRTConnect, under a cost that measures what the path will cost
the steering, not its Euclidean length:

**Ball–box cost** (:class:`BallBoxMetric`).  At a regular point ``p`` with an
adapted frame ``Y_1..Y_n`` of weights ``w_j`` (fields, then brackets:
:func:`nilpotent.core.analysis.filtration.analyze`), write a displacement
``q − p = Σ_j z_j Y_j(c)`` in the frame at the midpoint ``c = (p + q)/2``
(symmetric in ``p``, ``q``).  The ball–box theorem (Bellaïche 1996, Thm 7.34;
Jean, *Control of Nonholonomic Systems*, 2014, Thm 2.4) gives
``d(p, q) ≍ Σ_j |z_j|^{1/w_j}`` with constants depending on ``p``; the
estimate used is

.. math::

    \hat d(p, q) = \Big(\sum_{w_j = 1} z_j^2\Big)^{1/2}
                   + \sum_{w_j \ge 2} 2\sqrt{\pi}\,|z_j|^{1/w_j},

exact for a horizontal straight motion, and for a pure weight-2 displacement
of the Heisenberg group (a circle of area ``|z|``: length ``2√(π|z|)``).  A
sideways step of a car (weight 3) costs ``~|z|^{1/3}``, a step along its
heading ``|z|``: RRT* prefers paths along which the steered pieces are short.
It is a cost, not a metric of the configuration space (no triangle inequality
is claimed); RRT*'s guarantee of convergence to the optimum holds for this
additive cost over the straight-edge graph it builds.

**Anytime** (:func:`optimal_path`): RRT* runs until its first solution, then
keeps improving it for ``improve_seconds`` (the cost of the best path after
each slice is recorded: ``cost_history``, non-increasing since RRT* only
replaces its solution by a cheaper one).  Its edges are straight chords checked
by the validity check every ``resolution`` (as RRTConnect's).  The path is then
cut into pieces and every piece steered and verified on the true system by the
global planner (nothing here is returned unverified).

"""

from __future__ import annotations

import contextlib
import importlib.util
import itertools
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import OptionError, PlanningError
from nilpotent.planning import budget
from nilpotent.planning.holonomic_path import anytime_solve, configuration_space, ompl_path
from nilpotent.planning.verify import Checker

__all__ = [
    "IMPROVE_FRACTION", "PLANNERS", "BallBoxMetric", "HolonomicStage", "OptimalPath",
    "ball_box_metric", "optimal_path", "planner_json", "shortcut",
]

#: Global planners of :func:`~nilpotent.planning.global_planner.plan_global`: the holonomic
#: stage's OMPL planner; ``"auto"`` (the default) stands for the one that plans best for the
#: model (:meth:`HolonomicStage.__init__`).
PLANNERS = ("auto", "rrtconnect", "rrtstar", "reeds-shepp", "trident-ocp")
#: Share of the time left that the Reeds–Shepp guide may take (the others: half).
GUIDE_SHARE = 0.8
#: The share of its time that RRT* spends improving its first path (:class:`HolonomicStage`).
IMPROVE_FRACTION = 0.5
#: Constant of the weight ≥ 2 terms of the ball–box cost (module doc).
BOX_CONSTANT = 2.0 * math.sqrt(math.pi)
#: Cost of a motion through a point where the frame is singular (not infinite: OMPL adds it).
SINGULAR_COST = 1e9


@dataclass(frozen=True, eq=False)
class BallBoxMetric:
    """The ball–box cost estimate of a system (module doc).

    Attributes
    ----------
    weights:
        ``w_j`` of the adapted frame.
    frame:
        ``q (N, n) ↦`` the frame values ``(N, n·n)``, column ``j`` of frame field ``Y_{j+1}``
        in entries ``j·n .. j·n + n − 1``.
    """

    weights: tuple[int, ...]
    frame: Callable[[np.ndarray], np.ndarray]

    def __post_init__(self) -> None:
        w = np.asarray(self.weights)
        object.__setattr__(self, "_horizontal", w == 1)
        object.__setattr__(self, "_higher", w > 1)
        object.__setattr__(self, "_powers", 1.0 / w[w > 1])

    def coordinates(self, p: np.ndarray, q: np.ndarray) -> np.ndarray:
        """``z (N, n)`` with ``q − p = Σ_j z_j Y_j((p+q)/2)``; rows ``NaN`` where the frame is
        singular."""
        n = len(self.weights)
        p = np.asarray(p, dtype=float).reshape(-1, n)
        q = np.asarray(q, dtype=float).reshape(-1, n)
        f = self.frame(0.5 * (p + q)).reshape(-1, n, n).transpose(0, 2, 1)
        d = (q - p)[..., None]
        with np.errstate(all="ignore"):
            try:
                z = np.linalg.solve(f, d)[..., 0]
            except np.linalg.LinAlgError:  # an exactly singular frame: row by row
                z = np.full(p.shape, np.nan)
                for i in range(len(p)):
                    with contextlib.suppress(np.linalg.LinAlgError):
                        z[i] = np.linalg.solve(f[i], d[i])[:, 0]
        z[~np.isfinite(z).all(axis=1)] = np.nan
        return z

    def cost(self, p: np.ndarray, q: np.ndarray) -> np.ndarray:
        """``d̂(p, q)`` for rows of ``p``, ``q`` ``(N, n)`` (:data:`SINGULAR_COST` where the
        frame is singular)."""
        z = self.coordinates(p, q)
        horizontal = np.sqrt((z[:, self._horizontal] ** 2).sum(axis=1))  # type: ignore[attr-defined]
        higher = (BOX_CONSTANT * np.abs(z[:, self._higher])  # type: ignore[attr-defined]
                  ** self._powers).sum(axis=1)  # type: ignore[attr-defined]
        out = horizontal + higher
        return np.where(np.isfinite(out), out, SINGULAR_COST)

    def edge_cost(self, p: np.ndarray, q: np.ndarray, piece: float) -> float:
        """The cost of the chord ``p → q`` cut into ``k = ⌈‖q − p‖ / piece⌉`` equal pieces
        (as the global planner steers it): the sum of their :meth:`cost`."""
        k = max(1, math.ceil(math.dist(p, q) / piece))
        t = np.arange(k + 1, dtype=float)[:, None] / k
        pts = p + t * (q - p)
        return float(np.sum(self.cost(pts[:-1], pts[1:])))


@lru_cache(maxsize=16)
def _metric(system: ControlSystem, point: tuple[sp.Expr, ...]) -> BallBoxMetric:
    from nilpotent.core.analysis.filtration import analyze
    from nilpotent.core.lie.brackets import word_field
    from nilpotent.numeric.compile import compile_map

    filt = analyze(system, point)
    if not filt.bracket_generating or len(filt.frame) != system.n:
        raise PlanningError(
            f"{system.name} is not bracket generating at the start: no sub-Riemannian cost "
            "for --planner rrtstar")
    exprs = [e for word in filt.frame for e in word_field(system, word)]
    params: dict[str | sp.Symbol, Any] = {sp.Symbol(k): v for k, v in system.parameters}
    frame = compile_map(system.coordinates, exprs, params, name=f"{system.name}-frame",
                        outputs=len(exprs))
    return BallBoxMetric(tuple(int(w) for w in filt.weights), frame)


def ball_box_metric(system: ControlSystem, point: Sequence[float] | np.ndarray) -> BallBoxMetric:
    """The ball–box cost of ``system`` with the adapted frame chosen at ``point`` (cached).

    Raises
    ------
    PlanningError
        The system is not bracket generating at ``point``.
    """
    exact = tuple(sp.Rational(repr(float(v))) for v in point)
    return _metric(system, exact)


@dataclass(frozen=True)
class OptimalPath:
    """RRT*'s path and how its cost went down.

    Attributes
    ----------
    points:
        The path's vertices (model coordinates), start and goal included.
    cost:
        Its ball–box cost (sum over the edges).
    cost_history:
        ``(seconds since RRT* started, best cost)`` after each slice with a solution.
    """

    points: tuple[tuple[float, ...], ...]
    cost: float
    cost_history: tuple[tuple[float, float], ...]


def optimal_path(
    checker: Checker,
    x0: np.ndarray,
    xg: np.ndarray,
    seconds: float,
    seed: int | None = None,
    resolution: float = 0.05,
    valid: Callable[[np.ndarray], np.ndarray] | None = None,
    held: Sequence[int] = (),
    improve_seconds: float | None = None,
    piece: float = 1.0,
) -> OptimalPath:
    """A collision-free path from OMPL RRT* under the ball–box cost (module doc).

    Parameters as :func:`~nilpotent.planning.holonomic_path.ompl_path`; ``seconds``
    bounds the search for a first solution and its improvement together, and
    ``improve_seconds`` (default: all of ``seconds``) the improvement after the first;
    ``piece``: an edge costs the sum of the ball–box costs of the pieces of at most this
    length it will be cut into (:meth:`BallBoxMetric.edge_cost`; the ball–box estimate
    holds for short displacements only: one long edge would under-cost a sideways motion).

    Raises
    ------
    PlanningError
        No exact solution within ``seconds``.
    """
    from ompl import base as ob
    from ompl import geometric as og

    metric = ball_box_metric(checker.system, x0)
    cs = configuration_space(checker, x0, xg, resolution, valid, held, seed)
    si, embed = cs.info, cs.embed
    is_valid = checker.valid if valid is None else valid

    class Objective(ob.OptimizationObjective):
        def __init__(self, info: Any) -> None:
            super().__init__(info)

        def stateCost(self, s: Any) -> Any:
            return ob.Cost(0.0)

        def motionCost(self, s1: Any, s2: Any) -> Any:
            return ob.Cost(metric.edge_cost(embed(s1), embed(s2), piece))

    objective = Objective(si)
    pdef = ob.ProblemDefinition(si)
    start, goal = cs.endpoints(xg)
    pdef.setStartAndGoalStates(start, goal)
    pdef.setOptimizationObjective(objective)
    planner = og.RRTstar(si)
    planner.setProblemDefinition(pdef)
    planner.setup()
    t0 = time.perf_counter()
    improve = seconds if improve_seconds is None else improve_seconds
    try:
        history = anytime_solve(planner, pdef, seconds, improve, "a path")
        path: Any = pdef.getSolutionPath()  # a geometric path (the stubs say Path)
        pts = [embed(path.getState(i)) for i in range(path.getStateCount())]
    finally:
        # break the references between Python objects and OMPL's (no leak at exit)
        planner.clear()
        pdef.clearSolutionPaths()
        del planner, pdef, objective
    pts[0], pts[-1] = x0.copy(), xg.copy()
    pts = shortcut(pts, metric, piece, is_valid, resolution)
    cost = float(sum(metric.edge_cost(a, b, piece) for a, b in itertools.pairwise(pts)))
    if history and cost < history[-1][1]:
        history.append((time.perf_counter() - t0, cost))
    return OptimalPath(tuple(tuple(float(c) for c in p) for p in pts), cost, tuple(history))


def shortcut(
    points: Sequence[np.ndarray], metric: BallBoxMetric, piece: float,
    valid: Callable[[np.ndarray], np.ndarray], resolution: float,
) -> list[np.ndarray]:
    """The cheapest path through a subsequence of ``points`` whose chords are valid (ball–box
    cost of :meth:`BallBoxMetric.edge_cost`): dynamic programming over the ``O(n²)`` chords,
    a chord checked only when it would improve the best cost to its end; the path's own
    edges are kept as they are (valid already)."""
    pts = [np.asarray(p, dtype=float) for p in points]
    n = len(pts)
    best = [0.0] + [math.inf] * (n - 1)
    back = [0] * n
    for j in range(1, n):
        budget.check("shortcutting the path of OMPL RRT*")
        best[j] = best[j - 1] + metric.edge_cost(pts[j - 1], pts[j], piece)
        back[j] = j - 1
        for i in range(j - 1):
            c = best[i] + metric.edge_cost(pts[i], pts[j], piece)
            if c < best[j] and _chord(valid, pts[i], pts[j], resolution):
                best[j], back[j] = c, i
    out, j = [pts[-1]], n - 1
    while j > 0:
        j = back[j]
        out.append(pts[j])
    return out[::-1]


def _chord(valid: Callable[[np.ndarray], np.ndarray], a: np.ndarray, b: np.ndarray,
           step: float) -> bool:
    k = max(2, math.ceil(float(np.linalg.norm(b - a)) / step) + 1)
    t = np.linspace(0.0, 1.0, k)[:, None]
    return bool(np.all(valid(a + t * (b - a))))


def refuse_full_turn(names: Sequence[str], x0: np.ndarray, xg: np.ndarray) -> None:
    """Refuse a goal whose headings (the coordinates ``theta…``: real numbers, not angles
    modulo ``2π``) turn by a full turn or more from the start's: the Reeds–Shepp planners
    do not plan such a turn (their curves join poses modulo ``2π``, the lattice bins its
    headings so, and a path turning by another multiple than the goal's was searched for
    the whole time limit); the message names the headings and the same pose less than a
    full turn away.

    Raises
    ------
    PlanningError
        A heading of ``xg`` is ``2π`` or more from ``x0``'s.
    """
    at = [k for k, name in enumerate(names) if name.startswith("theta")]
    turns = [float(xg[k] - x0[k]) for k in at]
    if not turns or max(abs(t) for t in turns) < 2 * math.pi:
        return
    shift = 2 * math.pi * round(sum(turns) / len(turns) / (2 * math.pi))
    listed = ", ".join(f"{names[k]} by {t:.4g}" for k, t in zip(at, turns, strict=True))
    same = ",".join(f"{names[k]}={float(xg[k]) - shift:.6g}" for k in at)
    raise PlanningError(
        f"the goal's headings turn from the start's by a full turn or more ({listed} rad), "
        "which --planner reeds-shepp does not plan (headings are real numbers, not angles "
        f"modulo 2 pi; --to ...,{same} is the same pose less than a full turn away)")


def _car(checker: Checker) -> Any:
    """The Reeds–Shepp guide's geometry of the model (OptionError: not car-like)."""
    from nilpotent.planning.guide import car_geometry
    from nilpotent.planning.trailer_guide import TRAILER_COORDINATES, trailer_geometry
    from nilpotent.planning.trailer_lattice import is_lattice_model, lattice_geometry

    # the trailer as a car (trailer_guide); a model with a trailer's coordinates that is not
    # one is refused with the trailer's reason, not the car's; two trailers: the lattice
    # search over exact motions (trailer_lattice)
    if is_lattice_model(checker.system):
        return lattice_geometry(checker.system, checker)
    if checker.system.coordinate_names == TRAILER_COORDINATES:
        return trailer_geometry(checker.system, checker)
    return car_geometry(checker.system, checker)


def _not_car_like(checker: Checker) -> str:
    """What ``"auto"`` stands for where the model is not car-like (:class:`HolonomicStage`)."""
    from nilpotent.planning.trident_ocp import MODELS

    if checker.system.name in MODELS and importlib.util.find_spec("casadi") is not None:
        return "trident-ocp"
    return "rrtconnect"


class HolonomicStage:
    """The holonomic stage of :func:`~nilpotent.planning.global_planner.plan_global` for a
    planner of :data:`PLANNERS`: :meth:`path` has the signature of
    :func:`~nilpotent.planning.holonomic_path.ompl_path` (``seconds`` its 4th argument);
    for ``"rrtstar"`` it runs :func:`optimal_path` (improving for :data:`IMPROVE_FRACTION`
    of its time, edges cut into pieces of ``piece``), for ``"reeds-shepp"``
    :func:`~nilpotent.planning.guide.guide_path` (car-like models only, checked here when
    ``checker`` is given), and keeps each result in ``found``.

    ``"auto"`` chooses (``planner`` then names the choice): ``"reeds-shepp"`` where the
    model is car-like (``car``, ``car-trailers:1`` and ``:2``: every piece driven exactly,
    lengths 0.87–1.09× OMPL's Reeds–Shepp RRT* on the benchmark), ``"trident-ocp"`` for
    ``trident-snake`` when CasADi is installed (body path 1.4–2× the holonomic path where
    the nilpotent steering of pieces drives 19–26×), else ``"rrtconnect"`` (every other
    model: the nilpotent steering of straight pieces), benchmarks/RESULTS.md.

    Raises
    ------
    OptionError
        An unknown planner, ``"reeds-shepp"`` for a model that is not car-like,
        ``"trident-ocp"`` for another model than ``trident-snake``.
    MissingExtraError
        ``"trident-ocp"`` without CasADi (the ``ocp`` extra).
    """

    def __init__(self, planner: str, piece: float, checker: Checker | None = None) -> None:
        if planner not in PLANNERS:
            raise OptionError(f"unknown planner {planner!r} (choose from {', '.join(PLANNERS)})")
        auto = planner == "auto"
        if auto:
            planner = "reeds-shepp" if checker is not None else "rrtconnect"
        self.car: Any = None  # the guide's CarGeometry, once (refuses a model not car-like)
        if planner == "reeds-shepp" and checker is not None:
            try:
                self.car = _car(checker)
            except OptionError:
                if not auto:
                    raise
                planner = _not_car_like(checker)
        self.steering: Any = None  # trident-ocp: the plan's CasADi functions, once
        if planner == "trident-ocp" and checker is not None:
            from nilpotent.planning.trident_ocp import PIECE, BodyPathSteering

            self.steering = BodyPathSteering(checker)
            piece = max(piece, PIECE)
        self.planner, self.piece = planner, piece
        self.found: list[Any] = []
        #: Share of the time left that the stage may take: the guide's legs are driven
        #: exactly (little steering left to do), the other stages' paths are steered.
        self.share = GUIDE_SHARE if planner == "reeds-shepp" else 0.5

    def path(self, *args: Any, **kwargs: Any) -> list[np.ndarray]:
        """The path from OMPL (RRTConnect, RRT* under the ball–box cost, or the lifted
        Reeds–Shepp guide)."""
        if self.planner in ("rrtconnect", "trident-ocp"):
            return ompl_path(*args, **kwargs)
        if self.planner == "reeds-shepp":
            from nilpotent.planning.guide import guide_path
            from nilpotent.planning.trailer_guide import TrailerGeometry, trailer_guide_path
            from nilpotent.planning.trailer_lattice import LatticeGeometry, lattice_path

            checker, x0, xg = args[:3]
            refuse_full_turn(checker.system.coordinate_names, x0, xg)
            if isinstance(self.car, LatticeGeometry):
                found = lattice_path(*args, **kwargs)
                self.found.append(found)
                return [np.array(p) for p in found.points]
            find = trailer_guide_path if isinstance(self.car, TrailerGeometry) else guide_path
            # the plain validity, not plan_global's extra clearance (room for steered
            # pieces): the guide's legs are driven exactly, and the clearance kept the
            # paths out of the parking slot's corners (1.3-1.5x Reeds-Shepp RRT*)
            guide = find(*args, **{**kwargs, "valid": None})
            self.found.append(guide)
            return [np.array(p) for p in guide.points]
        best = optimal_path(*args, **kwargs, improve_seconds=IMPROVE_FRACTION * args[3],
                            piece=self.piece)
        self.found.append(best)
        return [np.array(p) for p in best.points]

    def exact(self, checker: Checker, x: np.ndarray, prev: np.ndarray, w: np.ndarray,
              tol: float, points: int, final: bool = False) -> Any:
        """The piece from ``x`` to waypoint ``w`` (after ``prev``) driven exactly, or
        ``None`` (then steered): the lifted Reeds–Shepp guide's legs and turns at rest
        (:func:`~nilpotent.planning.guide.exact_piece`), the lattice's motions for two
        trailers (:func:`~nilpotent.planning.trailer_lattice.lattice_exact_piece`), the
        trident's optimal control of its body path
        (:func:`~nilpotent.planning.trident_ocp.body_path_piece`; ``final``: the last piece,
        whose end is all of ``w``, not only its pose, as is that of a piece back onto the
        path, ``w = prev``); ``None`` for the other stages."""
        if self.steering is not None:
            from nilpotent.planning.trident_ocp import body_path_piece

            # back onto the path (``w`` the previous waypoint): all of ``w``, shape included
            whole = final or not np.any(w != prev)
            return body_path_piece(self.steering, x, w, tol, points, whole)
        if self.car is None:
            return None
        from nilpotent.planning.guide import exact_piece
        from nilpotent.planning.trailer_guide import TrailerGeometry, trailer_exact_piece
        from nilpotent.planning.trailer_lattice import LatticeGeometry, lattice_exact_piece

        if isinstance(self.car, LatticeGeometry):
            return lattice_exact_piece(checker, x, prev, w, tol, points, self.found[-1])
        if isinstance(self.car, TrailerGeometry):
            return trailer_exact_piece(checker, x, prev, w, tol, points, self.car)
        return exact_piece(checker, x, prev, w, tol, points, self.car.wheelbase)

    def fields(self) -> dict[str, Any]:
        """``planner``, ``path_cost``, ``cost_history`` of the last path (for ``GlobalPlan``):
        the ball–box cost (``"rrtstar"``) or the Reeds–Shepp length (``"reeds-shepp"``)."""
        last = self.found[-1] if self.found else None
        if last is None:
            return {"planner": self.planner, "path_cost": None, "cost_history": ()}
        if self.planner == "reeds-shepp":
            return {"planner": self.planner, "path_cost": last.length,
                    "cost_history": last.length_history}
        return {"planner": self.planner, "path_cost": last.cost,
                "cost_history": last.cost_history}


def planner_json(planner: str, path_cost: float | None,
                 cost_history: Sequence[tuple[float, float]],
                 reasons: dict[str, str]) -> dict[str, Any]:
    """The plan JSON's ``planner``, ``path_cost``, ``cost_history`` (the reason of a ``null``
    ``path_cost`` added to ``reasons``)."""
    if path_cost is None:
        reasons["path_cost"] = "the holonomic stage (rrtconnect, trident-ocp, or none) has no cost"
    return {"planner": planner, "path_cost": path_cost,
            "cost_history": [list(c) for c in cost_history]}
