"""Worlds: workspace bounds and obstacles (TOML world files), collision checks with shapely 2.

A world file (the interface page, "Limits and worlds"; the World files page)::

    name = "room"
    [bounds]                  # optional: the workspace, model length units
    x = [-1.0, 6.0]
    y = [-2.0, 4.0]
    [[obstacles]]
    polygon = [[1.0, 0.5], [2.0, 0.5], [2.0, 1.5], [1.0, 1.5]]
    [[obstacles]]
    disc = { center = [3.0, -0.5], radius = 0.4 }

Numbers may be constant expressions of the safe grammar (``"sqrt(2)"``).  A world
file is read like a model file (:func:`nilpotent.core.model.datafile.read_data_file`:
TOML or the same structure as JSON by its suffix, a UTF-8 byte-order mark read
past, a JSON key given twice refused, only regular files of at most 1 MB).
Every number is finite and of magnitude at most
:data:`nilpotent.core.model.points.MAX_MAGNITUDE` (1e6); a disc's radius is in
``(0, 1e6]``; a world has at most :data:`MAX_OBSTACLES` obstacles and a polygon at
most :data:`MAX_POLYGON_VERTICES` vertices (a
:class:`~nilpotent.errors.ComputationLimitError` past them, naming the file).

Collision checks are shapely 2's vectorised predicates and distances: the
polygon obstacles and, when bounds are given, the outside of the bounds (a
frame polygon around the workspace box) form one prepared geometry; disc
obstacles are kept exact (distance to the centre minus the radius).  The
clearance of a robot part (a shapely geometry with a radius, see
:class:`nilpotent.planning.robot.Robot`) is its distance to that set minus its
radius: ``≤ 0`` means contact or overlap.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from nilpotent.core.model.datafile import read_data_file
from nilpotent.core.model.expressions import parse_expression, real_value
from nilpotent.core.model.points import MAX_MAGNITUDE, check_magnitude
from nilpotent.errors import ComputationLimitError, ExpressionError, WorldError
from nilpotent.strict_json import json_object

__all__ = [
    "MAX_OBSTACLES", "MAX_POLYGON_VERTICES", "World", "builtin_worlds", "load_world",
    "world_from_dict",
]

#: Most obstacles of a world (each is checked against every part of the robot at every
#: validity check of the planner).
MAX_OBSTACLES = 1000
#: Most vertices of one obstacle polygon.
MAX_POLYGON_VERTICES = 1000
#: Longest world name, in characters (as a model's name).
MAX_NAME_LENGTH = 200

#: How far beyond the bounds the frame polygon (the outside of the workspace) reaches,
#: as a multiple of the workspace's size.
_FRAME = 100.0


@dataclass(frozen=True, eq=False)
class World:
    """A planar workspace: bounds ``((xlo, xhi), (ylo, yhi))`` or ``None``, obstacles.

    Attributes
    ----------
    name:
        The world's name.
    bounds:
        The workspace box, or ``None`` (unbounded).
    polygons:
        Obstacle polygons, each ``((x, y), ...)``.
    discs:
        Obstacle discs ``((cx, cy), radius)``.

    Raises
    ------
    WorldError
        An obstacle polygon that is not simple.
    """

    name: str
    bounds: tuple[tuple[float, float], tuple[float, float]] | None = None
    polygons: tuple[tuple[tuple[float, float], ...], ...] = ()
    discs: tuple[tuple[tuple[float, float], float], ...] = ()
    _blocked: Any = field(init=False, repr=False)
    _centres: Any = field(init=False, repr=False)
    _radii: Any = field(init=False, repr=False)
    _tree: Any = field(init=False, repr=False)

    def __post_init__(self) -> None:
        shapes: list[BaseGeometry] = [shapely.Polygon(p) for p in self.polygons]
        for i, s in enumerate(shapes):
            if not s.is_valid:
                raise WorldError(
                    f"world {self.name!r}: obstacles polygon {i} is not a simple polygon "
                    f"({shapely.is_valid_reason(s)})"
                )
        if self.bounds is not None:
            (xlo, xhi), (ylo, yhi) = self.bounds
            size = max(xhi - xlo, yhi - ylo)
            box = shapely.box(xlo, ylo, xhi, yhi)
            outer = shapely.box(xlo - _FRAME * size, ylo - _FRAME * size,
                                xhi + _FRAME * size, yhi + _FRAME * size)
            shapes.append(outer.difference(box))
        blocked = shapely.union_all(shapes) if shapes else None
        if blocked is not None:
            shapely.prepare(blocked)
        object.__setattr__(self, "_blocked", blocked)
        object.__setattr__(self, "_centres", shapely.points([c for c, _ in self.discs])
                           if self.discs else None)
        object.__setattr__(self, "_radii", np.array([r for _, r in self.discs], dtype=float))
        # discs through a spatial index: the pairs part-disc near enough, not all of them
        object.__setattr__(self, "_tree", shapely.STRtree(self._centres)
                           if self.discs else None)

    def _disc_clearance(self, flat: np.ndarray) -> np.ndarray:
        """``min_j dist(g, c_j) − r_j`` for each geometry of ``flat`` (1-D), exactly: the
        nearest centre bounds it, and only centres within that bound plus the largest
        radius can do better (:class:`shapely.STRtree` queries)."""
        radii = self._radii
        (gi, ci), dist = self._tree.query_nearest(flat, return_distance=True, all_matches=False)
        bound = np.full(flat.size, np.inf)
        np.minimum.at(bound, gi, dist - radii[ci])
        # a centre j beats the bound only if dist_j < bound + r_j <= bound + max r
        gi, ci = self._tree.query(flat, predicate="dwithin", distance=bound + radii.max())
        out = bound.copy()
        if gi.size:
            np.minimum.at(out, gi, shapely.distance(flat[gi], self._centres[ci]) - radii[ci])
        return out

    def clearance(self, geoms: np.ndarray, radii: np.ndarray | float = 0.0) -> np.ndarray:
        """Distance of each geometry to the obstacles and the outside of the bounds, minus
        its radius; same shape as ``geoms``; ``+inf`` in an empty unbounded world.

        ``≤ 0``: the part touches or overlaps an obstacle (or leaves the bounds).
        """
        geoms = np.asarray(geoms)
        out = np.full(geoms.shape, np.inf)
        if self._blocked is not None:
            out = shapely.distance(geoms, self._blocked)
        if self._centres is not None and geoms.size:
            d = self._disc_clearance(geoms.ravel()).reshape(geoms.shape)
            out = np.minimum(out, d)
        return out - radii

    def collides(
        self, geoms: np.ndarray, radii: np.ndarray | float = 0.0,
        margin: float | np.ndarray = 0.0,
    ) -> np.ndarray:
        """Boolean, same shape as ``geoms``: :meth:`clearance` ``≤ margin`` (contact, overlap,
        leaving the bounds, or closer than ``margin``), by shapely's predicates
        (``intersects`` on the prepared obstacles where the distance allowed is 0,
        ``dwithin`` elsewhere) without computing distances.  ``margin`` may be an array
        that broadcasts to ``geoms`` (``(N, 1)``: one value per configuration)."""
        geoms = np.asarray(geoms)
        reach = np.broadcast_to(np.asarray(radii, dtype=float) + margin, geoms.shape)
        out = np.zeros(geoms.shape, dtype=bool)
        if self._blocked is not None:
            flat = reach <= 0
            out[flat] = shapely.intersects(self._blocked, geoms[flat])
            # shapely's stubs take a scalar distance; dwithin is vectorised over it
            out[~flat] = shapely.dwithin(  # pyright: ignore[reportCallIssue]
                geoms[~flat], self._blocked, reach[~flat]  # pyright: ignore[reportArgumentType]
            )
        if self._centres is not None and geoms.size:
            flat, far = geoms.ravel(), np.asarray(reach, dtype=float).ravel()
            disc_r: np.ndarray = self._radii
            gi, ci = self._tree.query(flat, predicate="dwithin", distance=far + disc_r.max())
            if gi.size:
                # shapely's stubs take a scalar distance; dwithin is vectorised over it
                near = shapely.dwithin(  # pyright: ignore[reportCallIssue]
                    flat[gi], self._centres[ci],
                    far[gi] + disc_r[ci],  # pyright: ignore[reportArgumentType]
                )
                hit = np.zeros(flat.size, dtype=bool)
                hit[gi[near]] = True
                out |= hit.reshape(geoms.shape)
        return out

    def point_clearance(self, xy: np.ndarray) -> np.ndarray:
        """:meth:`clearance` of points ``(..., 2)``."""
        return self.clearance(np.asarray(shapely.points(np.asarray(xy, dtype=float))))

    def covers_boxes(self, lo: np.ndarray, hi: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """Whether no point of each closed box ``[lo, hi]`` (``(N, 2)`` corners) has a
        :meth:`clearance` above ``margin`` ``≥ 0``, ``(N,)``: the box lies within the
        obstacles and the outside of the bounds grown by ``margin`` (shapely's buffer, whose
        round corners are inscribed: less than the true growth), or within one obstacle
        disc grown by ``margin``.  Sound one way: ``True`` only where it is so (a box
        covered by several discs together, or by a disc and a polygon, reads ``False``)."""
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        out = np.zeros(len(lo), dtype=bool)
        if self._blocked is not None:
            grown = self._blocked.buffer(margin) if margin > 0 else self._blocked
            shapely.prepare(grown)
            boxes = shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1])
            out |= shapely.covers(grown, boxes)
        corners = np.stack([lo, hi, np.c_[lo[:, 0], hi[:, 1]], np.c_[hi[:, 0], lo[:, 1]]], 1)
        for (cx, cy), r in self.discs:  # a disc is convex: its corners in it, the box too
            reach = np.hypot(corners[..., 0] - cx, corners[..., 1] - cy)
            out |= np.all(reach <= r + margin, axis=1)
        return out

    def to_json(self) -> dict[str, Any]:
        """The world as a world-file structure (JSON-ready)."""
        out: dict[str, Any] = {"name": self.name}
        if self.bounds is not None:
            out["bounds"] = {"x": list(self.bounds[0]), "y": list(self.bounds[1])}
        out["obstacles"] = [{"polygon": [list(p) for p in poly]} for poly in self.polygons]
        out["obstacles"] += [{"disc": {"center": list(c), "radius": r}} for c, r in self.discs]
        return json_object(out)


def _show(value: object, limit: int = 60) -> str:
    if isinstance(value, int) and value.bit_length() > 64:
        return f"an integer of about {int(value.bit_length() * 0.30103) + 1} digits"
    text = repr(value)
    return text if len(text) <= limit else text[:limit] + "..."


def _number(value: object, where: str, low: float = -MAX_MAGNITUDE) -> float:
    """A finite number of the world file within ``[low, MAX_MAGNITUDE]``."""
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise WorldError(f"{where}: expected a number, got {_show(value)}")
    if isinstance(value, str):
        try:
            v = real_value(parse_expression(value, {}, where=where), where=where)
        except ExpressionError as exc:
            raise WorldError(str(exc)) from None
    elif isinstance(value, int) and value.bit_length() > 64:
        raise WorldError(f"{where}: {_show(value)}, outside the allowed range "
                         f"[{low:g}, {MAX_MAGNITUDE:g}]")
    else:
        v = value
    return check_magnitude(v, where, low=low, error=WorldError)


def _pair(value: object, where: str) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2:
        raise WorldError(f"{where}: expected a pair [a, b], got {_show(value)}")
    return (_number(value[0], f"{where}[0]"), _number(value[1], f"{where}[1]"))


def world_from_dict(data: Mapping[str, Any], source: str = "<world>") -> World:
    """Build a :class:`World` from the world-file structure (module doc).

    Raises
    ------
    WorldError
        Unknown keys, malformed bounds (``lo ≥ hi``), polygons with fewer than
        3 points or self-intersecting, discs with a non-positive radius, a number
        that is not finite or of magnitude above 1e6.
    ComputationLimitError
        More than :data:`MAX_OBSTACLES` obstacles or :data:`MAX_POLYGON_VERTICES`
        vertices in a polygon.
    """
    if not isinstance(data, Mapping):
        raise WorldError(f"{source}: a world is a table with name, bounds, obstacles")
    for key in data:
        if key not in ("name", "bounds", "obstacles"):
            raise WorldError(f"{source}: unknown key {key!r} (allowed: name, bounds, obstacles)")
    name = data.get("name", Path(source).stem if not source.startswith("<") else "world")
    if not isinstance(name, str) or not name:
        raise WorldError(f"{source}: name must be a non-empty string")
    if len(name) > MAX_NAME_LENGTH:
        raise WorldError(f"{source}: name has {len(name):,} characters, above the limit "
                         f"{MAX_NAME_LENGTH} of a world's name")
    bounds = None
    if "bounds" in data:
        raw = data["bounds"]
        if not isinstance(raw, Mapping) or set(raw) != {"x", "y"}:
            raise WorldError(f"{source}: bounds needs exactly x = [lo, hi] and y = [lo, hi]")
        bx, by = _pair(raw["x"], f"{source}: bounds.x"), _pair(raw["y"], f"{source}: bounds.y")
        for axis, (lo, hi) in (("x", bx), ("y", by)):
            if not lo < hi:
                raise WorldError(f"{source}: bounds.{axis} = [{lo}, {hi}] needs lo < hi")
        bounds = (bx, by)
    polygons, discs = [], []
    obstacles = data.get("obstacles", [])
    if not isinstance(obstacles, list):
        raise WorldError(f"{source}: obstacles must be a list of [[obstacles]] tables")
    if len(obstacles) > MAX_OBSTACLES:
        raise ComputationLimitError(
            f"{source}: {len(obstacles):,} obstacles, above the limit {MAX_OBSTACLES:,} of a "
            "world (nilpotent.planning.world.MAX_OBSTACLES); merge small obstacles into "
            "polygons")
    for i, ob in enumerate(obstacles):
        where = f"{source}: obstacles[{i}]"
        if not isinstance(ob, Mapping) or len(ob) != 1 or next(iter(ob)) not in ("polygon", "disc"):
            raise WorldError(f"{where}: an obstacle is either polygon = [...] or disc = {{...}}")
        if "polygon" in ob:
            pts = ob["polygon"]
            if not isinstance(pts, list) or len(pts) < 3:
                raise WorldError(f"{where}.polygon: needs at least 3 points [x, y]")
            if len(pts) > MAX_POLYGON_VERTICES:
                raise ComputationLimitError(
                    f"{where}.polygon: {len(pts):,} vertices, above the limit "
                    f"{MAX_POLYGON_VERTICES:,} (nilpotent.planning.world.MAX_POLYGON_VERTICES)")
            polygons.append(tuple(_pair(p, f"{where}.polygon[{j}]") for j, p in enumerate(pts)))
        else:
            d = ob["disc"]
            if not isinstance(d, Mapping) or set(d) != {"center", "radius"}:
                raise WorldError(f"{where}.disc: needs exactly center = [x, y] and radius")
            radius = _number(d["radius"], f"{where}.disc.radius", low=0.0)
            if radius <= 0:
                raise WorldError(f"{where}.disc.radius must be > 0, got {radius}")
            discs.append((_pair(d["center"], f"{where}.disc.center"), radius))
    try:
        return World(name, bounds, tuple(polygons), tuple(discs))
    except WorldError as exc:
        raise WorldError(f"{source}: {exc}") from None


def builtin_worlds() -> dict[str, Any]:
    """The example worlds shipped with the package, by name (``room``, ``parking``, ``corner``).

    Returns
    -------
    dict
        Name -> the world file (an :class:`importlib.resources.abc.Traversable`).
    """
    from importlib.resources import files

    folder = files("nilpotent.planning") / "worlds"
    return {
        f.name.removesuffix(".toml"): f
        for f in sorted(folder.iterdir(), key=lambda f: f.name)
        if f.name.endswith(".toml")
    }


def load_world(path: str | Path) -> World:
    """Read a world file, TOML or JSON (module doc), as model files are read, or a
    shipped example world by name.

    Parameters
    ----------
    path : str or Path
        The world file (``.toml``, or ``.json`` with the same structure), or the name
        of a world of :func:`builtin_worlds` (``"room"``): a name is looked up only
        where no file of that name exists.

    Raises
    ------
    WorldError
        Missing, unreadable or non-regular file (a FIFO, a device: refused before
        reading), unknown suffix, syntax error, a duplicate JSON key, or what
        :func:`world_from_dict` reports.
    ComputationLimitError
        A file above 1 MB, or a world past the limits of :func:`world_from_dict`.
    """
    path = Path(path)
    builtin = builtin_worlds()
    try:
        exists = path.exists()
    except (OSError, ValueError):  # a name too long, a NUL byte: read_data_file says so
        exists = True
    if not exists:
        if str(path) in builtin:
            text = builtin[str(path)].read_text("utf-8")
            return world_from_dict(tomllib.loads(text), str(path))
        names = ", ".join(builtin)
        raise WorldError(
            f"{path}: world file not found (a path to a .toml or .json file, or a built-in "
            f"world: {names})"
        )
    data = read_data_file(path, "world file", WorldError)
    return world_from_dict(data, str(path))
