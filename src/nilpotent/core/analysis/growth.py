r"""The generic growth vector: the growth of the filtration at random points near $p$.

Near a generic point the dimensions $n_s = \dim \Delta^s$ are constant and
maximal, $(N_1, \dots, N_r)$; :func:`generic_growth_vector` finds them at
pseudo-random rational points (fixed seed) near a point, where the words chosen
at length $s$ span $\Delta^s$ as a module.  It is the first step of the analysis:
:func:`nilpotent.core.analysis.filtration.analyze` compares the growth at $p$ with
it (regularity), :mod:`nilpotent.core.analysis.singular` builds its frames from
it and :mod:`nilpotent.core.analysis.orbit` uses :func:`generic_growth_at` to
find a spanning frame at the points of an orbit.
"""

from __future__ import annotations

import random
from collections.abc import Mapping, Sequence

import sympy as sp

from nilpotent.core.decide.spans import Decision, Span, exact_value
from nilpotent.core.lie.brackets import Word, word_length
from nilpotent.core.lie.word_values import Undefined, WordValues
from nilpotent.core.model.expressions import as_expr, exact_decimals
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ModelError, PointError

__all__ = [
    "GENERIC_PERTURBATION",
    "generic_growth_at",
    "generic_growth_vector",
    "normalise_point",
]

GENERIC_PERTURBATION = 0.25
"""Half-width of the box around ``p`` in which the random points are drawn."""

_SEED = 20240611


# --- generic growth vector ----------------------------------------------------


def _random_points(point: Sequence[sp.Expr], count: int) -> list[list[sp.Expr]]:
    """Pseudo-random rational points near ``point``: ``round(p) + δ`` with rational ``δ``.

    An irrational ``p`` is first replaced by a 20-digit decimal (a random point
    only needs to be near ``p``), so that the values of rational fields are
    exact rationals.
    """
    rng = random.Random(_SEED)
    den = 2**20
    half = int(GENERIC_PERTURBATION * den)
    out = []
    for _ in range(count):
        vals = []
        for v in point:
            q = exact_value(v)
            centre = (
                sp.Rational(int(q.p), int(q.q)) if q is not None else sp.Rational(str(sp.N(v, 20)))
            )
            vals.append(centre + sp.Rational(rng.randint(-half, half), den))
        out.append(vals)
    return out


def generic_growth_at(
    sys: ControlSystem, values: Sequence[sp.Expr], frame: Sequence[Word] | None = None
) -> tuple[tuple[int, ...], tuple[Word, ...]]:
    """Growth vector at a (random, assumed regular) point, and the words that realise it.

    With ``frame`` given, only those words are evaluated (a cheap confirmation at
    a second point); else new words are the brackets ``[X_i, Y]`` of the chosen
    generators with the words chosen at the previous length.
    """
    n, m = sys.n, sys.m
    at = WordValues(sys, values, symbolic=False)
    span = Span(probabilistic=True)
    chosen: list[Word] = []

    def add(w: Word) -> bool:
        if span.add(at.vector(w)) is Decision.INDEPENDENT:
            chosen.append(w)
            return True
        return False

    growth: list[int] = []
    if frame is not None:
        by_length: dict[int, list[Word]] = {}
        for w in frame:
            by_length.setdefault(word_length(w), []).append(w)
        for s in range(1, max(by_length, default=0) + 1):
            for w in by_length.get(s, []):
                add(w)
            growth.append(span.rank)
        return tuple(growth), tuple(chosen)
    newest: list[Word] = [i for i in range(1, m + 1) if add(i)]
    generators = list(newest)
    growth.append(span.rank)
    while span.rank < n:
        candidates = []
        for w in newest:
            for g in generators:
                # [X, X] = 0 and [Y, X] = -[X, Y]: each pair once
                if g != w and (w, g) not in candidates:
                    candidates.append((g, w))
        newest = []
        for w in candidates:
            if add(w):
                newest.append(w)
                if span.rank == n:
                    break
        if not newest:
            break
        growth.append(span.rank)
    return tuple(growth), tuple(chosen)


def generic_growth_vector(
    sys: ControlSystem, point: Sequence[sp.Expr] | None = None
) -> tuple[int, ...]:
    """The growth vector at random points near ``point`` (the origin by default).

    A pseudo-random rational point (fixed seed) in the box of half-width
    :data:`GENERIC_PERTURBATION` around ``point`` is regular with probability one;
    there the words chosen at length $s$ span $\\Delta^s$ as a module, so only
    the brackets $[X_i, Y]$ with the words $Y$ chosen at the previous length are
    needed.  Decisions go through :class:`~nilpotent.core.decide.spans.Span` (exact
    for rational values, else certified balls; a Gram determinant that stays
    within $2^{-3P/4}$ of 0 at a random point counts as 0, with probability one).
    The growth of the same words is confirmed at a second random point and the
    componentwise maximum returned (each is a lower bound of the generic
    value); if the two differ, the second point is analysed in full.
    """
    p = normalise_point(sys, point)
    results: list[tuple[int, ...]] = []
    frame: tuple[Word, ...] | None = None
    for values in _random_points(p, 8):
        try:
            growth, words = generic_growth_at(sys, values, frame)
            if frame is not None and growth != results[0]:
                growth, words = generic_growth_at(sys, values)
        except Undefined:
            continue
        results.append(growth)
        frame = words
        if len(results) == 2:
            break
    if not results:
        raise PointError(
            f"the fields of {sys.name!r} could not be evaluated at random points near "
            f"({', '.join(str(v) for v in p)})"
        )
    length = max(len(g) for g in results)
    padded = [g + (g[-1],) * (length - len(g)) for g in results]
    return tuple(max(col) for col in zip(*padded, strict=True))


def normalise_point(
    sys: ControlSystem, point: Sequence[object] | Mapping[str, object] | None
) -> tuple[sp.Expr, ...]:
    """The point as exact sympy numbers (decimals read as the rationals they denote)."""
    extra = set().union(*(as_expr(e).free_symbols for f in sys.specialized_fields for e in f))
    extra -= set(sys.coordinates)
    if extra:
        raise ModelError(
            f"the fields of {sys.name!r} contain symbols that are neither coordinates nor "
            f"parameters: {', '.join(sorted(map(str, extra)))}"
        )
    if point is None:
        return sys.origin()
    if isinstance(point, Mapping):
        point = sys.point(point)
    if len(point) != sys.n:
        raise PointError(f"a point of {sys.name!r} has {sys.n} coordinates, got {len(point)}")
    values = tuple(exact_decimals(v) for v in point)
    for name, v in zip(sys.coordinate_names, values, strict=True):
        if not (v.is_number and v.is_real is not False and v.is_finite is not False):
            raise PointError(f"coordinate {name} of the point must be a real number, got {v}")
    return values


