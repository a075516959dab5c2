"""The holonomic stage of global planning: a path of the configuration space between two
configurations, found by OMPL (RRTConnect in a box around them, every configuration checked
by the planner's validity check), before it is cut into pieces and steered
(:func:`nilpotent.planning.global_planner.plan_global`)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from nilpotent.errors import PlanningError
from nilpotent.planning import budget
from nilpotent.planning.verify import Checker

__all__ = ["SIMPLIFY_SECONDS", "SLICE_SECONDS", "ConfigurationSpace", "anytime_solve", "box",
           "configuration_space", "ompl_path"]

#: Longest time OMPL's path simplification (shortcutting) may take.
SIMPLIFY_SECONDS = 0.5
#: Length of one RRT* slice between two records of the best cost (seconds).
SLICE_SECONDS = 0.25


def box(
    checker: Checker, x0: np.ndarray, xg: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The configuration-space box OMPL samples in: the limits, the world's bounds for ``x``
    and ``y``; else around the two configurations, by half the chord (at least π) for ``x``
    and ``y`` and by half the coordinate's own change (at least π) for the others.

    An unlimited heading gets ``[min − π, max + π]`` (every direction between, the full
    turn on either side), not half the chord: a trident crossing a 14 wide world once
    searched a heading range 23 rad wide, mostly turns it never needed (issue 20).
    """
    names = checker.system.coordinate_names
    lo = np.minimum(x0, xg)
    hi = np.maximum(x0, xg)
    pad = np.maximum(math.pi, 0.5 * np.abs(xg - x0))
    for name in ("x", "y"):
        if name in names:
            pad[names.index(name)] = max(math.pi, 0.5 * float(np.linalg.norm(xg - x0)))
    lo, hi = lo - pad, hi + pad
    world = checker.world
    if world is not None and world.bounds is not None:
        for axis, name in enumerate(("x", "y")):
            if name in names:
                j = names.index(name)
                lo[j], hi[j] = world.bounds[axis]
    assert checker.limits is not None
    for name, a, b in checker.limits.bounds:
        j = names.index(name)
        lo[j], hi[j] = a, b
    return lo, hi


@dataclass(frozen=True)
class ConfigurationSpace:
    """OMPL's real-vector space of the sampled coordinates, with its validity check.

    ``info`` is the set-up ``ompl.base.SpaceInformation`` (validity checker: the
    checker's, or ``valid``; checking resolution from ``resolution``); ``free`` the
    indices of the coordinates OMPL samples, the others held at ``x0``'s values.
    """

    space: Any
    info: Any
    free: np.ndarray
    x0: np.ndarray

    def embed(self, state: Any) -> np.ndarray:
        """The configuration (model coordinates) of an OMPL state."""
        q = self.x0.astype(float).copy()
        q[self.free] = [state[j] for j in range(len(self.free))]
        return q

    def endpoints(self, xg: np.ndarray) -> tuple[Any, Any]:
        """OMPL states of ``x0`` and ``xg``."""
        start, goal = self.space.allocState(), self.space.allocState()
        for j, k in enumerate(self.free):
            start[j], goal[j] = float(self.x0[k]), float(xg[k])
        return start, goal


def configuration_space(
    checker: Checker,
    x0: np.ndarray,
    xg: np.ndarray,
    resolution: float,
    valid: Callable[[np.ndarray], np.ndarray] | None,
    held: Sequence[int],
    seed: int | None,
) -> ConfigurationSpace:
    """The OMPL space both planners search (:func:`ompl_path`'s parameters).

    Raises
    ------
    ValueError
        Held coordinates that differ between ``x0`` and ``xg``.
    """
    from ompl import base as ob
    from ompl import util as ou

    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    if seed is not None:
        ou.RNG.setSeed(int(seed) + 1)  # OMPL refuses seed 0
    held_set = {int(j) for j in held}
    if any(x0[j] != xg[j] for j in held_set):
        raise ValueError("held coordinates must agree at the start and the goal")
    free = np.array([j for j in range(len(x0)) if j not in held_set], dtype=int)
    lo, hi = box(checker, x0, xg)
    lo, hi = lo[free], hi[free]
    n = len(free)
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for j in range(n):
        bounds.setLow(j, float(lo[j]))
        bounds.setHigh(j, float(hi[j]))
    space.setBounds(bounds)
    info = ob.SpaceInformation(space)
    is_valid = checker.valid if valid is None else valid
    cs = ConfigurationSpace(space, info, free, np.asarray(x0, dtype=float))
    info.setStateValidityChecker(lambda st: bool(is_valid(cs.embed(st)[None, :])[0]))
    extent = float(np.linalg.norm(hi - lo))
    info.setStateValidityCheckingResolution(min(0.05, resolution / max(extent, 1e-12)))
    info.setup()
    return cs


def ompl_path(
    checker: Checker,
    x0: np.ndarray,
    xg: np.ndarray,
    seconds: float,
    seed: int | None = None,
    resolution: float = 0.05,
    valid: Callable[[np.ndarray], np.ndarray] | None = None,
    held: Sequence[int] = (),
) -> list[np.ndarray]:
    """A collision-free configuration-space path from OMPL RRTConnect, simplified.

    ``resolution``: largest step (configuration-space units) at which OMPL checks
    straight motions between states.  ``valid``: the validity of a batch of
    configurations (default ``checker.valid``; ``checker`` also gives the box).
    ``held``: indices of coordinates kept at ``x0``'s values all along (OMPL
    samples only the others; ``xg`` must agree with ``x0`` there).

    Raises
    ------
    PlanningError
        No exact solution within ``seconds``.
    """
    from ompl import geometric as og

    cs = configuration_space(checker, x0, xg, resolution, valid, held, seed)
    setup = og.SimpleSetup(cs.info)
    start, goal = cs.endpoints(xg)
    setup.setStartAndGoalStates(start, goal)
    setup.setPlanner(og.RRTConnect(setup.getSpaceInformation()))
    status = setup.solve(float(seconds))
    if not (status and setup.haveExactSolutionPath()):
        raise PlanningError(
            f"no collision-free path from OMPL RRTConnect within {seconds:.3g} s "
            f"(status: {status.asString() if hasattr(status, 'asString') else status}); "
            "raise --time-limit, or check that start and goal are connected in the free space"
        )
    # shortcutting until it converges can take seconds of validity checks: bounded
    setup.simplifySolution(float(min(SIMPLIFY_SECONDS, seconds)))
    path = setup.getSolutionPath()
    states = [path.getState(i) for i in range(path.getStateCount())]
    pts = [cs.embed(st) for st in states]
    pts[0], pts[-1] = x0.copy(), xg.copy()
    return pts


def anytime_solve(planner: Any, pdef: Any, seconds: float, improve: float,
                  what: str, restart: float | None = None,
                  improve_by: float | None = None) -> list[tuple[float, float]]:
    """Run an OMPL optimising planner in slices of :data:`SLICE_SECONDS` until ``seconds``,
    or ``improve`` seconds after its first exact solution, or (when given) ``improve_by``
    seconds after the start once it has one (the improvement never eats the time that the
    stages after the search need); ``[(seconds, best cost)]`` after each slice with a
    solution (the budget is checked before each slice).  ``restart``:
    the tree is cleared (``planner.clear()``: a new tree, from the RNG's next numbers) after
    each ``restart`` seconds without an exact solution (a tree can stall at a narrow goal,
    retrying the same failing edges from the same nearest vertices).

    Raises
    ------
    PlanningError
        No exact solution within ``seconds`` (``what`` names the path sought).
    """
    t0 = time.perf_counter()
    history: list[tuple[float, float]] = []
    first: float | None = None
    tree = t0  # when the current tree was started
    while True:
        now = time.perf_counter()
        spent = now - t0
        left = seconds - spent
        if first is not None:
            left = min(left, first + improve - spent)
            if improve_by is not None:
                left = min(left, improve_by - spent)
        elif restart is not None and now - tree >= restart and left >= SLICE_SECONDS:
            planner.clear()
            pdef.clearSolutionPaths()
            tree = now
        if left <= 0:
            break
        budget.check(f"looking for {what} with OMPL RRT*")
        planner.solve(float(min(SLICE_SECONDS, left)))
        if pdef.hasExactSolution():
            now = time.perf_counter() - t0
            first = now if first is None else first
            history.append((now, float(planner.bestCost().value())))
    if first is None:
        raise PlanningError(
            f"no collision-free {what.removeprefix('a ')} from OMPL RRT* within {seconds:.3g} "
            "s; raise --time-limit, or check that start and goal are connected in the free "
            "space")
    return history
