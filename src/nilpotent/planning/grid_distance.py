"""Shortest distances among obstacles on a grid: the holonomic heuristic of a search.

Dolgov, Thrun, Montemerlo, Diebel, "Path planning for autonomous vehicles in unknown
semi-structured environments" (IJRR 29(5), 2010) take as hybrid A*'s heuristic the larger of
the nonholonomic distance without obstacles and the holonomic distance with them; this is
the latter, for a point (an axle centre) kept ``radius`` away from the obstacles
(:func:`grid_distance`; used by :mod:`nilpotent.planning.trailer_lattice`).

:func:`refuse_unreachable` decides, where it can soundly, that no motion joins a start to a
goal: a point of the robot's outline must keep its clearance along every admissible motion,
so its path lies in the free space of the plane; on a grid whose free cells over-approximate
that free space (a cell is blocked only when no point of it is free:
:meth:`~nilpotent.planning.world.World.covers_boxes`), a continuous path passes from cell to
8-neighbouring cell, so a start and a goal whose points lie in two components of the free
cells are not joined by any motion (a goal caged by obstacles).
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from nilpotent.errors import PlanningError
from nilpotent.planning.verify import Checker
from nilpotent.planning.world import World

__all__ = ["CAGE_CELLS", "grid_distance", "refuse_unreachable"]

#: About how many cells the grid of :func:`refuse_unreachable` has (its cost: milliseconds).
CAGE_CELLS = 40_000


def grid_distance(world: World | None, goal: tuple[float, float], radius: float,
                  cell: float) -> Callable[[float, float], float] | None:
    """Dijkstra's distance from ``goal`` on the 8-neighbour grid of square cells of side
    ``cell`` over the world's bounds, among the points farther than ``radius`` from every
    obstacle (length units): the holonomic heuristic "with obstacles" of Dolgov et al.
    (IJRR 2010).  Returns the distance at the cell nearest a point ``(x, y)``; unreachable
    cells get the largest finite distance plus 10.  ``None`` without a world or bounds.

    >>> from nilpotent.planning.world import world_from_dict
    >>> w = world_from_dict({"name": "box", "bounds": {"x": [0, 2], "y": [0, 1]}})
    >>> round(grid_distance(w, (0.5, 0.5), 0.1, 0.1)(1.5, 0.5), 6)
    1.0
    """
    if world is None or world.bounds is None:
        return None
    (xlo, xhi), (ylo, yhi) = world.bounds
    nx, ny = math.ceil((xhi - xlo) / cell) + 1, math.ceil((yhi - ylo) / cell) + 1
    xs, ys = np.meshgrid(xlo + cell * np.arange(nx), ylo + cell * np.arange(ny), indexing="ij")
    free = world.point_clearance(np.stack([xs, ys], axis=-1).reshape(-1, 2)) > radius
    free = free.reshape(nx, ny)
    dist = np.full((nx, ny), np.inf)
    gi = min(max(round((goal[0] - xlo) / cell), 0), nx - 1)
    gj = min(max(round((goal[1] - ylo) / cell), 0), ny - 1)
    dist[gi, gj] = 0.0
    heap = [(0.0, gi, gj)]
    steps = [(a, b, cell * math.hypot(a, b)) for a in (-1, 0, 1) for b in (-1, 0, 1) if a or b]
    while heap:
        d, i, j = heapq.heappop(heap)
        if d > dist[i, j]:
            continue
        for a, b, c in steps:
            k, m = i + a, j + b
            if 0 <= k < nx and 0 <= m < ny and free[k, m] and d + c < dist[k, m]:
                dist[k, m] = d + c
                heapq.heappush(heap, (d + c, k, m))
    far = float(np.max(dist[np.isfinite(dist)])) + 10.0
    dist[~np.isfinite(dist)] = far

    def at(x: float, y: float) -> float:
        i = min(max(round((x - xlo) / cell), 0), nx - 1)
        j = min(max(round((y - ylo) / cell), 0), ny - 1)
        return float(dist[i, j])

    return at


def refuse_unreachable(checker: Checker, x0: np.ndarray, xg: np.ndarray) -> None:
    """Refuse a goal that no admissible motion from ``x0`` reaches, where decided soundly
    (module doc): a point of the robot's outline (its first vertex, else a segment's end or
    a disc's centre) must keep more than the checker's clearance from the obstacles and the
    outside of the bounds; the grid over the bounds (without bounds, a box holding the
    obstacles and both points, whose border ring stands for the free outside) has about
    :data:`CAGE_CELLS` cells.  Nothing is decided without a world, or an outline.

    Raises
    ------
    PlanningError
        The point's cells at the start and at the goal are in two components of the free
        cells: ``"goal not reachable from start: ..."``.
    """
    world = checker.world
    if world is None or not (world.polygons or world.discs or world.bounds):
        return
    pts = checker.robot.points(np.array([x0, xg], dtype=float))  # type: ignore[attr-defined]
    arrays = [p.reshape(2, -1, 2) for p in (*pts["polygons"], pts["segments"], pts["discs"])]
    arrays = [a for a in arrays if a.shape[1]]
    if not arrays:
        return
    a, b = arrays[0][0, 0], arrays[0][1, 0]
    if world.bounds is not None:
        (xlo, xhi), (ylo, yhi) = world.bounds
    else:
        corners = [np.array(p, dtype=float) for p in world.polygons] + [
            np.array([[c[0] - r, c[1] - r], [c[0] + r, c[1] + r]]) for c, r in world.discs]
        every = np.vstack([*corners, a[None, :], b[None, :]])
        (xlo, ylo), (xhi, yhi) = every.min(axis=0), every.max(axis=0)
    cell = max(math.sqrt(max(xhi - xlo, 1e-9) * max(yhi - ylo, 1e-9) / CAGE_CELLS), 1e-6)
    if world.bounds is None:  # the border ring of cells lies beyond every obstacle: free
        grow = 2.0 * cell + checker.clearance
        xlo, ylo, xhi, yhi = xlo - grow, ylo - grow, xhi + grow, yhi + grow
    nx, ny = math.ceil((xhi - xlo) / cell), math.ceil((yhi - ylo) / cell)
    if nx * ny > 4 * CAGE_CELLS:
        return  # a degenerate box (a very thin workspace): not decided
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    lo = np.stack([xlo + cell * i.ravel(), ylo + cell * j.ravel()], axis=-1)
    free = ~world.covers_boxes(lo, lo + cell, checker.clearance)
    from scipy.ndimage import label

    labelled: Any = label(free.reshape(nx, ny), structure=np.ones((3, 3), dtype=int))
    comp = np.asarray(labelled[0])  # (labels, count); the stubs say an int too

    def at(p: np.ndarray) -> int:
        k = min(max(int((p[0] - xlo) // cell), 0), nx - 1)
        m = min(max(int((p[1] - ylo) // cell), 0), ny - 1)
        return int(comp[k, m])

    ca, cb = at(a), at(b)
    if ca and cb and ca != cb:
        raise PlanningError(
            f"goal not reachable from start: the goal is enclosed by obstacles (or the bounds) "
            f"that the start is outside of; a point of the robot's outline, at ({a[0]:.3g}, "
            f"{a[1]:.3g}) at the start and ({b[0]:.3g}, {b[1]:.3g}) at the goal, keeps clear "
            f"of them on every motion, and the free space of the plane joins none of its "
            f"points near the start to those near the goal (a grid of cells {cell:.2g} wide, "
            f"each blocked only where no point of it is free)")
