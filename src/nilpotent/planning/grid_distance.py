"""Shortest distances among obstacles on a grid: the holonomic heuristic of a search.

Dolgov, Thrun, Montemerlo, Diebel, "Path planning for autonomous vehicles in unknown
semi-structured environments" (IJRR 29(5), 2010) take as hybrid A*'s heuristic the larger of
the nonholonomic distance without obstacles and the holonomic distance with them; this is
the latter, for a point (an axle centre) kept ``radius`` away from the obstacles
(:func:`grid_distance`; used by :mod:`nilpotent.planning.trailer_lattice`).
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable

import numpy as np

from nilpotent.planning.world import World

__all__ = ["grid_distance"]


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
