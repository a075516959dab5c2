"""A robot's outline evaluated at configurations: shapely geometries, limits, singular margin.

:class:`Robot` compiles a system's :class:`~nilpotent.core.model.outline.Outline`
(parameters substituted) once with :func:`nilpotent.numeric.compile.compile_map`
(the expressions came from the safe grammar or the built-ins) and turns arrays of configurations
``(N, n)`` into shapely 2 geometries, vectorised (``shapely.polygons``,
``shapely.linestrings``, ``shapely.points``): one row of ``P`` parts per
configuration.  Discs are kept as their centre points plus a radius (the
exact distance to a disc is the distance to its centre minus the radius).

It also evaluates the limits (:meth:`Robot.limit_margin`: the signed
distance to the nearest bound of the box limits and of the relative limits
``lo ≤ g(q) ≤ hi``, negative outside), self-collision
(:meth:`Robot.self_collides`, :meth:`Robot.self_clearance`: the outline's pairs
of bodies that must not touch, one vectorised shapely call per pair of parts)
and, for models that have
one, the singular margin (:func:`singular_margin_function`:
``|det M(q)|`` of ``trident-snake-joints``, the matrix of the no-slip
constraints solved for the body velocity; 0 on the singular set).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypedDict

import numpy as np
import shapely
import sympy as sp

from nilpotent.core.model.expressions import as_expr
from nilpotent.core.model.outline import Limits, Outline
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ModelError, OptionError
from nilpotent.numeric.compile import CompiledMap, compile_map

__all__ = ["OutlinePoints", "Robot", "singular_margin_function"]


def singular_margin_function(system: ControlSystem) -> Callable[[np.ndarray], np.ndarray] | None:
    """``q (N, n) ↦ margin (N,)`` from the singular set, or ``None`` if the model has none.

    ``trident-snake-joints``: ``|det M(q)|`` (:func:`nilpotent.models.trident.joint_determinant`
    with the model's ``r`` and ``l``).
    """
    if system.name != "trident-snake-joints":
        return None
    from nilpotent.models.trident import TridentGeometry, joint_determinant

    geom = TridentGeometry.from_system(system)

    def margin(q: np.ndarray) -> np.ndarray:
        return np.abs(joint_determinant(np.asarray(q, dtype=float), geom))

    return margin


def _compile_outline(system: ControlSystem, exprs: tuple[sp.Expr, ...]) -> CompiledMap:
    return compile_map(system.coordinates, exprs, dict(system.parameters),
                       name=f"{system.name}-outline", outputs=len(exprs))


def _real_or_nan(value: Any) -> Any:
    """``value`` where it is real, NaN where its imaginary part is not 0."""
    if not np.iscomplexobj(value):
        return value
    arr = np.asarray(value, dtype=np.complex128)
    return np.where(np.imag(arr) == 0, np.real(arr), np.nan)


class OutlinePoints(TypedDict):
    """Raw outline coordinates of ``N`` configurations (:meth:`Robot.points`)."""

    polygons: list[np.ndarray]  # one (N, k, 2) array per polygon
    segments: np.ndarray  # (N, S, 2, 2)
    discs: np.ndarray  # (N, D, 2) centres
    radii: np.ndarray  # (N, D)


@dataclass(frozen=True, eq=False)
class Robot:
    """The outline, limits and singular margin of a system, evaluated numerically.

    Parameters
    ----------
    system:
        The model (its ``geometry`` may be ``None``: then the robot has no
        outline and only limits/margins are checked).
    limits:
        The limits to check (default: the system's own).
    """

    system: ControlSystem
    limits: Limits | None = None
    _fn: CompiledMap | None = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if self.limits is None:
            object.__setattr__(self, "limits", self.system.limits)
        outline = self.system.geometry
        fn = None if outline is None else _compile_outline(self.system, outline.expressions())
        object.__setattr__(self, "_fn", fn)
        # the limited coordinates' indices and bounds, once (limit_margin is called for
        # single configurations thousands of times by OMPL's validity checks)
        names = self.system.coordinate_names
        assert self.limits is not None
        bounds = self.limits.bounds
        object.__setattr__(self, "_limit_index", np.array([names.index(k) for k, _, _ in bounds],
                                                          dtype=int))
        object.__setattr__(self, "_limit_lo", np.array([lo for _, lo, _ in bounds], dtype=float))
        object.__setattr__(self, "_limit_hi", np.array([hi for _, _, hi in bounds], dtype=float))
        rel = self.limits.relative
        object.__setattr__(self, "_rel_fn", sp.lambdify(
            [self.system.coordinates], [as_expr(e) for _, e, _, _ in rel], "numpy")
            if rel else None)
        object.__setattr__(self, "_rel_lo", np.array([lo for _, _, lo, _ in rel], dtype=float))
        object.__setattr__(self, "_rel_hi", np.array([hi for _, _, _, hi in rel], dtype=float))
        pairs = outline.self_collision_parts() if outline is not None else ()
        object.__setattr__(self, "_pairs", np.array(pairs, dtype=int).reshape(-1, 2))

    @property
    def outline(self) -> Outline | None:
        return self.system.geometry

    @property
    def has_self_collision(self) -> bool:
        """The outline names pairs of bodies that must not touch."""
        return bool(self._pairs.size)  # type: ignore[attr-defined]

    def relative_values(self, q: np.ndarray) -> np.ndarray:
        """The relative-limit expressions at ``q (N, n)``: shape ``(N, R)``."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        fn = self._rel_fn  # type: ignore[attr-defined]
        if fn is None:
            return np.zeros((q.shape[0], 0))
        with np.errstate(all="ignore"):
            vals = fn(q.T)
        out = np.empty((q.shape[0], len(vals)))
        for i, v in enumerate(vals):
            out[:, i] = v
        return out

    def self_clearance(self, q: np.ndarray, parts: tuple[np.ndarray, np.ndarray] | None = None
                       ) -> np.ndarray:
        """Smallest distance between two parts that must not touch, minus their radii, ``(N,)``
        (``≤ 0``: self-collision); ``+inf`` where the outline names no such pair."""
        pairs = self._pairs  # type: ignore[attr-defined]
        q = np.atleast_2d(np.asarray(q, dtype=float))
        if not pairs.size:
            return np.full(q.shape[0], np.inf)
        geoms, radii = self.parts(q) if parts is None else parts
        a, b = pairs[:, 0], pairs[:, 1]
        d = shapely.distance(geoms[:, a], geoms[:, b]) - radii[:, a] - radii[:, b]
        return d.min(axis=1)

    def self_collides(self, q: np.ndarray, parts: tuple[np.ndarray, np.ndarray] | None = None,
                      margin: float | np.ndarray = 0.0) -> np.ndarray:
        """Boolean ``(N,)``: two parts that must not touch are closer than ``margin`` (or touch,
        or overlap): :meth:`self_clearance` ``≤ margin``, by shapely's predicates
        (``intersects`` where the distance allowed is 0, ``dwithin`` elsewhere).  ``margin``
        may be an ``(N, 1)`` array, one value per configuration."""
        pairs = self._pairs  # type: ignore[attr-defined]
        q = np.atleast_2d(np.asarray(q, dtype=float))
        if not pairs.size:
            return np.zeros(q.shape[0], dtype=bool)
        geoms, radii = self.parts(q) if parts is None else parts
        a, b = pairs[:, 0], pairs[:, 1]
        ga, gb = geoms[:, a], geoms[:, b]
        reach = radii[:, a] + radii[:, b] + margin
        hit = np.zeros(ga.shape, dtype=bool)
        flat = reach <= 0
        hit[flat] = shapely.intersects(ga[flat], gb[flat])
        # shapely's stubs take a scalar distance; dwithin is vectorised over it
        hit[~flat] = shapely.dwithin(  # pyright: ignore[reportCallIssue]
            ga[~flat], gb[~flat], reach[~flat])  # pyright: ignore[reportArgumentType]
        return np.asarray(hit.any(axis=1), dtype=bool)

    @property
    def has_outline(self) -> bool:
        return self._fn is not None

    def _values(self, q: np.ndarray) -> np.ndarray:
        """All outline expressions at ``q (N, n)``: shape ``(N, E)``.

        Raises
        ------
        ModelError
            An expression that is not finite at one of the configurations (``1/x`` at
            ``x = 0``, ``log(x)`` at ``x <= 0``), or a disc radius below 0: the message
            names the expression and the configuration.
        """
        assert self._fn is not None
        with np.errstate(all="ignore"):
            try:
                vals = self._fn(q).T
            except (ZeroDivisionError, OverflowError, ValueError, TypeError) as exc:
                raise ModelError(f"model {self.system.name}: the outline [geometry] cannot be "
                                 f"evaluated ({type(exc).__name__}: {exc})") from None
            out = np.empty((q.shape[0], len(vals)))
            if isinstance(vals, np.ndarray) and vals.dtype.kind == "f":
                out[:] = vals.T  # one real array (the common case: no per-column work)
            else:
                for i, v in enumerate(vals):
                    # constants (a disc's radius) broadcast; a value with an imaginary part
                    # (``sqrt(p)`` with a parameter p < 0) is no real coordinate: NaN, not
                    # its real part
                    out[:, i] = _real_or_nan(v)
        bad = ~np.isfinite(out)
        if bad.any():
            row, col = (int(k[0]) for k in np.nonzero(bad))
            self._refuse(q[row], col, f"is not finite ({out[row, col]})")
        outline = self.outline
        assert outline is not None
        if outline.discs:
            radius_cols = np.arange(out.shape[1] - 3 * len(outline.discs) + 2, out.shape[1], 3)
            negative = out[:, radius_cols] < 0
            if negative.any():
                row, k = (int(v[0]) for v in np.nonzero(negative))
                col = int(radius_cols[k])
                self._refuse(q[row], col, f"is negative ({out[row, col]:.6g}); a radius is >= 0")
        return out

    def _refuse(self, q: np.ndarray, col: int, why: str) -> None:
        outline = self.outline
        assert outline is not None
        label = outline.labels()[col]
        expr = as_expr(outline.expressions()[col])
        at = ", ".join(f"{n}={float(v):.6g}" for n, v in zip(self.system.coordinate_names, q,
                                                             strict=True))
        raise ModelError(f"model {self.system.name}: the outline expression {label} = {expr} "
                         f"{why} at {at}; give an outline defined at every configuration "
                         "the robot may take")

    def parts(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Shapely geometries ``(N, P)`` of the outline's parts and their radii ``(N, P)``.

        ``P`` = polygons + segments + discs, in that order.  Polygons and
        segments have radius 0; a disc is its centre point with its radius
        (evaluated per configuration: it may depend on the parameters).

        Raises
        ------
        OptionError
            Wrong number of coordinates, or a model without outline.
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        if q.shape[1] != self.system.n:
            raise OptionError(
                f"configurations of {self.system.name} need {self.system.n} coordinates, "
                f"got shape {q.shape}"
            )
        outline = self.outline
        if outline is None:
            raise OptionError(f"model {self.system.name} has no [geometry] (robot outline)")
        v = self._values(q)
        n = q.shape[0]
        geoms, radii = [], []
        k = 0
        for poly in outline.polygons:
            m = len(poly)
            coords = v[:, k: k + 2 * m].reshape(n, m, 2)
            k += 2 * m
            geoms.append(shapely.polygons(coords))
            radii.append(np.zeros(n))
        for _ in outline.segments:
            coords = v[:, k: k + 4].reshape(n, 2, 2)
            k += 4
            geoms.append(shapely.linestrings(coords))
            radii.append(np.zeros(n))
        for _ in outline.discs:
            geoms.append(shapely.points(v[:, k: k + 2]))
            radii.append(v[:, k + 2])
            k += 3
        return np.stack(geoms, axis=1), np.stack(radii, axis=1)

    def points(self, q: np.ndarray) -> OutlinePoints:
        """Raw outline coordinates: ``polygons`` list of ``(N, k, 2)``, ``segments``
        ``(N, S, 2, 2)``, ``discs`` ``(N, D, 2)`` and ``radii`` ``(N, D)`` (for drawing)."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        outline = self.outline
        if outline is None:
            return {"polygons": [], "segments": np.zeros((len(q), 0, 2, 2)),
                    "discs": np.zeros((len(q), 0, 2)), "radii": np.zeros((len(q), 0))}
        v = self._values(q)
        n = q.shape[0]
        k = 0
        polys: list[np.ndarray] = []
        for poly in outline.polygons:
            polys.append(v[:, k: k + 2 * len(poly)].reshape(n, len(poly), 2))
            k += 2 * len(poly)
        s = len(outline.segments)
        segs = v[:, k: k + 4 * s].reshape(n, s, 2, 2)
        k += 4 * s
        d = len(outline.discs)
        disc = v[:, k: k + 3 * d].reshape(n, d, 3)
        return {"polygons": polys, "segments": segs, "discs": disc[..., :2],
                "radii": disc[..., 2]}

    def limit_margin(self, q: np.ndarray) -> np.ndarray:
        """``min_j min(x_j − lo_j, hi_j − x_j)`` over the limited coordinates and the
        relative limits (``x_j`` then the expression's value), ``(N,)``.

        Non-negative iff every limit holds; ``+inf`` where there are no limits; NaN (an
        expression not defined there) counts as outside (``-inf``).
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        out = np.full(q.shape[0], np.inf)
        idx = self._limit_index  # type: ignore[attr-defined]
        if idx.size:
            x = q[:, idx]
            out = np.minimum(x - self._limit_lo, self._limit_hi - x).min(axis=1)  # type: ignore[attr-defined]
        if self._rel_fn is not None:  # type: ignore[attr-defined]
            g = self.relative_values(q)
            m = np.minimum(g - self._rel_lo, self._rel_hi - g).min(axis=1)  # type: ignore[attr-defined]
            out = np.minimum(out, np.where(np.isnan(m), -np.inf, m))
        return out
