"""Box limits on coordinates and a robot's outline, as data a :class:`ControlSystem` carries.

Neither changes the dynamics; they describe where the robot may go
(the interface page, "Limits and worlds"):

* :class:`Limits` — closed intervals ``lo ≤ x_j ≤ hi`` on some coordinates
  (model units / radians), and *relative limits* ``lo ≤ g(q) ≤ hi`` on
  expressions of the coordinates (hitch angles ``theta0 - theta1``; the
  ``[relative_limits]`` table of model files); :meth:`Limits.tightened`
  intersects two sets of box limits (``--limit`` adds or tightens, never widens)
  and keeps the relative ones;
* :class:`Outline` — the robot's shape in the plane for collision checks:
  polygons, segments and discs whose points are sympy expressions of the
  coordinates and parameters (parsed by the safe grammar from model files, or
  built in by :mod:`nilpotent.models.outlines`).  A disc of radius 0 is a
  point (the trident snake's wheels).  Parts may belong to named *bodies*
  (``body = "car"``), and ``self_collision`` lists the pairs of bodies that must
  never touch (self-collision).

Numeric evaluation (arrays of configurations → shapely geometries) lives in
:mod:`nilpotent.planning.robot`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import sympy as sp

from nilpotent.core.model.expressions import as_expr, format_expression
from nilpotent.errors import ModelError

__all__ = ["Limits", "Outline", "linear_form"]

Point2 = tuple[sp.Expr, sp.Expr]


@dataclass(frozen=True)
class Limits:
    """Closed intervals on coordinates: ``bounds`` is ``((name, lo, hi), ...)``.

    Attributes
    ----------
    bounds:
        ``(name, lo, hi)`` per limited coordinate: ``lo ≤ name ≤ hi`` (model
        units, radians for angles).
    relative:
        ``(label, expression, lo, hi)`` per relative limit: ``lo ≤ expression(q) ≤ hi``;
        the expression a sympy expression of the coordinates only.  A linear one is
        normalised here, once, for every consumer (checker, guides, verification, output):
        ``scale · e + offset`` in ``[lo, hi]`` becomes ``e`` in the bounds divided through
        (:func:`linear_form`: ``"2*theta0 - 2*theta1" = [-1.4, 1.4]`` is
        ``theta0 - theta1`` in ``[-0.7, 0.7]``) and ``label`` the text of ``e``; any other
        keeps the text it was given as.

    Raises
    ------
    ModelError
        A bound that is not finite, ``lo > hi``, or a name (label) given twice, or two
        relative limits of the same linear quantity.

    Examples
    --------
    >>> Limits((("phi1", -1.0, 1.0),)).tightened({"phi1": (-2.0, 0.5)}).as_dict()
    {'phi1': (-1.0, 0.5)}
    """

    bounds: tuple[tuple[str, float, float], ...] = ()
    relative: tuple[tuple[str, sp.Expr, float, float], ...] = ()

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
        given: dict[str, str] = {}  # key (normalised label) -> the label as given
        rel = []
        for label, expr, lo, hi in self.relative:
            lo, hi = float(lo), float(hi)
            where = f"relative limit {label!r}"
            if not (math.isfinite(lo) and math.isfinite(hi)):
                raise ModelError(f"{where}: bounds must be finite, got [{lo}, {hi}]")
            if lo > hi:
                raise ModelError(f"{where}: lower bound {lo} is above upper bound {hi}")
            key, expr = str(label), as_expr(expr)
            form = linear_form(expr)
            if form is not None:  # one key per linear quantity, whatever its scale and offset
                expr, scale, offset = form
                lo, hi = sorted(((lo - offset) / scale, (hi - offset) / scale))
                key = format_expression(expr)
            if key in given and given[key] == label:
                raise ModelError(f"{where} given twice")
            if key in given:
                raise ModelError(f"{where}: the same quantity as relative limit {given[key]!r} "
                                 f"({key}, up to scale and offset); give it one limit")
            given[key] = str(label)
            rel.append((key, expr, lo, hi))
        object.__setattr__(self, "relative", tuple(rel))

    def __bool__(self) -> bool:
        return bool(self.bounds or self.relative)

    def as_dict(self) -> dict[str, tuple[float, float]]:
        """``{name: (lo, hi)}`` of the box limits, in the order given."""
        return {name: (lo, hi) for name, lo, hi in self.bounds}

    def relative_dict(self) -> dict[str, tuple[float, float]]:
        """``{label: (lo, hi)}`` of the relative limits, in the order given."""
        return {label: (lo, hi) for label, _, lo, hi in self.relative}

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
        return Limits(tuple((k, lo, hi) for k, (lo, hi) in out.items()), self.relative)

    def check_names(self, coordinates: Iterable[str], source: str) -> None:
        """Raise :class:`ModelError` if a limit names no coordinate, or a relative limit
        uses a name that is not a coordinate (or none at all)."""
        names = list(coordinates)
        for name, _, _ in self.bounds:
            if name not in names:
                raise ModelError(
                    f"{source}: limit on {name!r}, which is not a coordinate "
                    f"(coordinates: {', '.join(names)})"
                )
        for label, expr, _, _ in self.relative:
            used = {str(v) for v in as_expr(expr).free_symbols}
            unknown = sorted(used - set(names))
            if unknown:
                raise ModelError(
                    f"{source}: relative limit {label!r} uses {', '.join(unknown)}, which "
                    f"{'is' if len(unknown) == 1 else 'are'} not coordinates (a relative "
                    f"limit is an expression of the coordinates {', '.join(names)} only)")
            if not used:
                raise ModelError(f"{source}: relative limit {label!r} is a constant "
                                 "(it must depend on the coordinates)")


def linear_form(expr: sp.Expr) -> tuple[sp.Expr, float, float] | None:
    """``(e, scale, offset)`` with ``expr = scale · e + offset`` and ``e`` the normal form of
    a linear quantity: ``Σ c_j x_j`` over its symbols, the coefficient of the first symbol
    (by name) 1; ``None`` where ``expr`` is not affine in its symbols with real numeric
    coefficients (``sin(theta0 - theta1)``: kept as given).

    So ``2*theta0 - 2*theta1``, ``theta1 - theta0`` and ``theta0 - theta1 + 0`` all give
    ``theta0 - theta1`` (scales 2, -1, 1), as every consumer of a relative limit reads it.

    Examples
    --------
    >>> a, b = sp.symbols("theta0 theta1")
    >>> linear_form(2 * b - 2 * a + 1)
    (theta0 - theta1, -2.0, 1.0)
    """
    symbols = sorted(expr.free_symbols, key=str)
    if not symbols:
        return None
    # affine iff every partial derivative is a number (no expansion: a power of a long sum
    # is not multiplied out); one whose derivatives only cancel to numbers stays as given
    coeffs = [sp.diff(expr, s) for s in symbols]
    if any(c.free_symbols for c in coeffs):
        return None
    offset = expr.subs(dict.fromkeys(symbols, 0))
    if not all(c.is_number and c.is_real and c.is_finite for c in [*coeffs, offset]):
        return None
    scale = coeffs[0]
    if scale == 0:
        return None
    ratios = [c / scale for c in coeffs]
    ratios = [sp.Integer(int(r)) if r.is_Float and float(r).is_integer() else r for r in ratios]
    normal = sp.Add(*(r * s for r, s in zip(ratios, symbols, strict=True)))
    return normal, float(scale), float(offset)


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
    bodies:
        The body each part belongs to, in the order polygons, segments, discs (a name,
        or ``None``: in no body); empty: no bodies.
    self_collision:
        Pairs ``(A, B)`` of distinct body names that must never touch (every part of
        ``A`` against every part of ``B``).

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
        :class:`nilpotent.planning.robot.Robot`); ``bodies`` not one per part, a
        self-collision pair naming an unknown body, a body twice, or given twice.
    """

    polygons: tuple[tuple[Point2, ...], ...] = ()
    segments: tuple[tuple[Point2, Point2], ...] = ()
    discs: tuple[tuple[Point2, sp.Expr], ...] = ()
    bodies: tuple[str | None, ...] = ()
    self_collision: tuple[tuple[str, str], ...] = ()

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
        count = len(self.polygons) + len(self.segments) + len(self.discs)
        if self.bodies and len(self.bodies) != count:
            raise ModelError(f"geometry: {len(self.bodies)} body names for {count} parts "
                             "(one per part, or none)")
        known = {b for b in self.bodies if b is not None}
        pairs: set[frozenset[str]] = set()
        for i, pair in enumerate(self.self_collision):
            where = f"geometry.self_collision[{i}]"
            if len(pair) != 2:
                raise ModelError(f"{where}: a pair of two body names, got {pair!r}")
            a, b = pair
            for name in (a, b):
                if name not in known:
                    raise ModelError(
                        f"{where}: no body named {name!r} (bodies: "
                        f"{', '.join(sorted(known)) or 'none; give parts a body = NAME'})")
            if a == b:
                raise ModelError(f"{where}: [{a!r}, {b!r}] pairs a body with itself")
            key = frozenset((a, b))
            if key in pairs:
                raise ModelError(f"{where}: the pair [{a!r}, {b!r}] is given twice")
            pairs.add(key)

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

    def body_names(self) -> tuple[str, ...]:
        """The bodies' names, in the order they first appear."""
        return tuple(dict.fromkeys(b for b in self.bodies if b is not None))

    def self_collision_parts(self) -> tuple[tuple[int, int], ...]:
        """Pairs of part indices (polygons, segments, discs order) that must never touch:
        every part of ``A`` with every part of ``B`` for each pair ``(A, B)``."""
        out = []
        for a, b in self.self_collision:
            ia = [k for k, name in enumerate(self.bodies) if name == a]
            ib = [k for k, name in enumerate(self.bodies) if name == b]
            out += [(i, j) for i in ia for j in ib]
        return tuple(out)

    def free_names(self) -> set[str]:
        """Names of the symbols the outline uses."""
        return {str(s) for e in self.expressions() for s in as_expr(e).free_symbols}
