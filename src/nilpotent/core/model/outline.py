"""Box limits on coordinates and a robot's outline, as data a :class:`ControlSystem` carries.

Neither changes the dynamics; they describe where the robot may go
(INTERFACE.md "Limits, geometry and worlds"):

* :class:`Limits` — closed intervals ``lo ≤ x_j ≤ hi`` on some coordinates
  (model units / radians); :meth:`Limits.tightened` intersects two sets of
  limits (``--limit`` adds or tightens, never widens);
* :class:`Outline` — the robot's shape in the plane for collision checks:
  polygons, segments and discs whose points are sympy expressions of the
  coordinates and parameters (parsed by the safe grammar from model files, or
  built in by :mod:`nilpotent.models.outlines`).  A disc of radius 0 is a
  point (the trident snake's wheels).

Numeric evaluation (arrays of configurations → shapely geometries) lives in
:mod:`nilpotent.planning.robot`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import sympy as sp

from nilpotent.core.model.expressions import as_expr
from nilpotent.errors import ModelError

__all__ = ["Limits", "Outline"]

Point2 = tuple[sp.Expr, sp.Expr]


@dataclass(frozen=True)
class Limits:
    """Closed intervals on coordinates: ``bounds`` is ``((name, lo, hi), ...)``.

    Attributes
    ----------
    bounds:
        ``(name, lo, hi)`` per limited coordinate: ``lo ≤ name ≤ hi`` (model
        units, radians for angles).

    Raises
    ------
    ModelError
        A bound that is not finite, ``lo > hi``, or a name given twice.

    Examples
    --------
    >>> Limits((("phi1", -1.0, 1.0),)).tightened({"phi1": (-2.0, 0.5)}).as_dict()
    {'phi1': (-1.0, 0.5)}
    """

    bounds: tuple[tuple[str, float, float], ...] = ()

    def __post_init__(self) -> None:
        seen: set[str] = set()
        clean = []
        for name, lo, hi in self.bounds:
            lo, hi = float(lo), float(hi)
            if not (math.isfinite(lo) and math.isfinite(hi)):
                raise ModelError(f"limit of {name}: bounds must be finite, got [{lo}, {hi}]")
            if lo > hi:
                raise ModelError(f"limit of {name}: lower bound {lo} is above upper bound {hi}")
            if name in seen:
                raise ModelError(f"limit of {name} given twice")
            seen.add(name)
            clean.append((str(name), lo, hi))
        object.__setattr__(self, "bounds", tuple(clean))

    def __bool__(self) -> bool:
        return bool(self.bounds)

    def as_dict(self) -> dict[str, tuple[float, float]]:
        """``{name: (lo, hi)}`` in the order given."""
        return {name: (lo, hi) for name, lo, hi in self.bounds}

    def tightened(self, other: Mapping[str, tuple[float, float]]) -> Limits:
        """The intersection with ``other``; an empty intersection raises :class:`ModelError`."""
        out = self.as_dict()
        for name, (lo, hi) in other.items():
            if name in out:
                lo, hi = max(lo, out[name][0]), min(hi, out[name][1])
                if lo > hi:
                    raise ModelError(
                        f"limit of {name}: [{other[name][0]}, {other[name][1]}] does not meet "
                        f"the model's [{out[name][0]}, {out[name][1]}]"
                    )
            out[name] = (lo, hi)
        return Limits(tuple((k, lo, hi) for k, (lo, hi) in out.items()))

    def check_names(self, coordinates: Iterable[str], source: str) -> None:
        """Raise :class:`ModelError` if a limit names no coordinate."""
        names = list(coordinates)
        for name, _, _ in self.bounds:
            if name not in names:
                raise ModelError(
                    f"{source}: limit on {name!r}, which is not a coordinate "
                    f"(coordinates: {', '.join(names)})"
                )


#: Largest magnitude of a constant of an outline (that of a point's coordinate,
#: :data:`nilpotent.core.model.points.MAX_MAGNITUDE`, which imports this module).
MAX_CONSTANT = 1e6


def _short(value: object, limit: int = 60) -> str:
    text = str(value)
    return text if len(text) <= limit else text[:limit] + "..."


@dataclass(frozen=True)
class Outline:
    """A robot's outline in the plane; every number is a sympy expression.

    Attributes
    ----------
    polygons:
        Each a tuple of ≥ 3 points ``(X, Y)`` (a closed polygon, solid).
    segments:
        ``((X0, Y0), (X1, Y1))`` pairs (legs, hitch bars).
    discs:
        ``((X, Y), R)``: centre and radius (``R = 0``: a point).

    The symbols are the model's coordinates and parameters (as
    ``sympy.Symbol(name)``).

    Raises
    ------
    ModelError
        A polygon with fewer than 3 points, an empty outline, a constant (a point's
        coordinate, a radius) that is not finite or of magnitude above
        :data:`MAX_CONSTANT`, or a disc whose radius
        is a constant that is negative (a radius that depends on the
        configuration is checked where it is evaluated,
        :class:`nilpotent.planning.robot.Robot`).
    """

    polygons: tuple[tuple[Point2, ...], ...] = ()
    segments: tuple[tuple[Point2, Point2], ...] = ()
    discs: tuple[tuple[Point2, sp.Expr], ...] = ()

    def __post_init__(self) -> None:
        for i, poly in enumerate(self.polygons):
            if len(poly) < 3:
                raise ModelError(f"geometry.polygons[{i}] needs at least 3 points, got {len(poly)}")
        if not (self.polygons or self.segments or self.discs):
            raise ModelError("geometry: the outline is empty (give polygons, segments or discs)")
        radii = {f"geometry.discs[{i}].radius" for i in range(len(self.discs))}
        for label, expr in zip(self.labels(), self.expressions(), strict=True):
            r = as_expr(expr)
            if r.free_symbols:
                continue
            try:
                value = float(r)
            except (TypeError, ValueError, OverflowError):
                value = math.nan
            if label in radii and not (math.isfinite(value) and value >= 0):
                raise ModelError(
                    f"{label} = {_short(r)}: a radius must be a finite number >= 0")
            if not (math.isfinite(value) and abs(value) <= MAX_CONSTANT):
                raise ModelError(
                    f"{label} = {_short(r)}: a constant of the outline must be a finite number "
                    f"of magnitude at most {MAX_CONSTANT:g}")

    def expressions(self) -> tuple[sp.Expr, ...]:
        """Every expression of the outline, in a fixed order (polygons, segments, discs)."""
        out: list[sp.Expr] = []
        for poly in self.polygons:
            for p in poly:
                out.extend(p)
        for a, b in self.segments:
            out.extend((*a, *b))
        for c, rad in self.discs:
            out.extend((*c, rad))
        return tuple(out)

    def labels(self) -> tuple[str, ...]:
        """Where each of :meth:`expressions` stands in the ``[geometry]`` table, same order
        (``geometry.discs[0].radius``, ``geometry.polygons[1].points[2][0]``, ...)."""
        out: list[str] = []
        for i, poly in enumerate(self.polygons):
            for j in range(len(poly)):
                out += [f"geometry.polygons[{i}].points[{j}][{c}]" for c in (0, 1)]
        for i in range(len(self.segments)):
            out += [f"geometry.segments[{i}].{end}[{c}]" for end in ("from", "to") for c in (0, 1)]
        for i in range(len(self.discs)):
            out += [f"geometry.discs[{i}].center[0]", f"geometry.discs[{i}].center[1]",
                    f"geometry.discs[{i}].radius"]
        return tuple(out)

    def free_names(self) -> set[str]:
        """Names of the symbols the outline uses."""
        return {str(s) for e in self.expressions() for s in as_expr(e).free_symbols}
