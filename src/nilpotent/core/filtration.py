"""The filtration $\\Delta^1 \\subset \\Delta^2 \\subset \\cdots$ of a system at a point.

$\\Delta^1 = \\mathrm{span}\\{X_i\\}$, $\\Delta^{s+1} = \\Delta^s + [\\Delta^1, \\Delta^s]$;
$n_s(p) = \\dim \\Delta^s(p)$ is spanned by the values at $p$ of the bracket words
of length $\\le s$ (of the Hall basis, :func:`nilpotent.core.brackets.hall_basis`).
:func:`analyze` gives the growth vector, the weights, the step, an adapted frame
made of Hall words, whether $p$ is regular and whether the system is
bracket-generating there.  Bracket convention $[X,Y] = DY\\cdot X - DX\\cdot Y$.

How it is computed
------------------
1. *Generic growth vector* (at two pseudo-random points $q$ near $p$, values
   evaluated with 212-bit floats, rank decided with the relative tolerance
   :data:`GENERIC_TOL` after normalising each value to unit length).  A random
   point is regular with probability one, so near $q$ the chosen words of length
   $\\le s$ span $\\Delta^s$ as a module and $\\Delta^{s+1}(q)$ is spanned by them
   and the brackets $[X_i, Y]$ with $Y$ a chosen word of length $s$: only
   $m\\,(n_s - n_{s-1})$ new brackets per length.  At a regular point the span
   grows at every length until it stops for ever, so the generic growth vector
   ends after at most $n$ lengths.
2. *At p* the Hall words of each length are scanned in order and kept when
   their value at $p$ is independent of those already kept (greedy, earliest
   first).  Since $n_s(p) \\le n_s(q)$ (rank is lower semicontinuous), the scan
   of length $s$ stops as soon as the rank reaches the generic $n_s$; otherwise
   it runs through every Hall word of that length, so $n_s(p)$ is exact also at
   singular points, where the span can stall for some lengths and grow later
   (Martinet at 0: growth $(2, 2, 3)$).
3. Ranks at $p$ are exact (fraction-free elimination over $\\mathbb{Q}$ or a
   number field such as $\\mathbb{Q}(\\sqrt3)$) when the values are rational or
   algebraic, else decided numerically with 50 digits and tolerance
   :data:`POINT_TOL` (``Filtration.exact`` is then false).
"""

from __future__ import annotations

import random
import re
from collections.abc import Sequence
from dataclasses import dataclass

import mpmath
import symengine as se
import sympy as sp
from sympy.polys.matrices import DomainMatrix

from nilpotent.core.brackets import (
    Word,
    format_word,
    hall_basis,
    to_symengine,
    word_field_symengine,
    word_length,
    word_values_at,
)
from nilpotent.core.system import ControlSystem
from nilpotent.errors import NotBracketGeneratingError, PointError

GENERIC_TOL = 1e-30
"""Relative tolerance of the rank decisions at random points (212-bit evaluation)."""

POINT_TOL = 1e-25
"""Relative tolerance of numerical rank decisions at ``p`` (50-digit evaluation)."""

GENERIC_PREC_BITS = 212
_GENERIC_DPS = 60
GENERIC_PERTURBATION = 0.25
"""Half-width of the box around ``p`` in which the random points are drawn."""

_SEED = 20240611
_FINITE = re.compile(r"[-+]?\d+(\.\d*)?([eE][-+]?\d+)?")


@dataclass(frozen=True)
class Filtration:
    """The filtration of a system at a point.

    Attributes
    ----------
    system:
        The system analysed.
    point:
        The point $p$ (sympy numbers aligned with ``system.coordinates``).
    bracket_generating:
        Whether the brackets span $\\mathbb{R}^n$ at ``p``.
    growth_vector:
        $(n_1(p), \\dots, n_r(p))$; ends where the span stops growing ($n$ when
        bracket-generating).
    weights:
        $w_1 \\le \\dots$, $w_j = s$ for $n_{s-1} < j \\le n_s$ (one per frame word).
    step:
        $r(p)$, the length of ``growth_vector``.
    frame:
        Adapted frame: Hall words $Y_1, \\dots$ with $|Y_j| = w_j$ whose values at
        ``p`` form a basis of $\\Delta^s(p)$ for every $s$.
    frame_values:
        ``frame_values[k][j]`` is the $x_{j+1}$-component of $Y_{k+1}(p)$.
    regular:
        Whether the growth vector at ``p`` equals the generic one near ``p``.
    generic_growth_vector:
        The growth vector at random points near ``p``.
    exact:
        Whether the ranks at ``p`` were decided exactly.
    """

    system: ControlSystem
    point: tuple[sp.Expr, ...]
    bracket_generating: bool
    growth_vector: tuple[int, ...]
    weights: tuple[int, ...]
    step: int
    frame: tuple[Word, ...]
    frame_values: tuple[tuple[sp.Expr, ...], ...]
    regular: bool
    generic_growth_vector: tuple[int, ...]
    exact: bool

    @property
    def frame_names(self) -> tuple[str, ...]:
        """The frame words as users write them (``"[X1,X2]"``)."""
        return tuple(format_word(w) for w in self.frame)


# --- rank trackers ------------------------------------------------------------


class _NumericSpan:
    """Incremental span of real vectors, rank decided by SVD with a relative tolerance."""

    def __init__(self, tol: float, dps: int) -> None:
        self.tol = tol
        self.dps = dps
        self.rows: list[list[mpmath.mpf]] = []

    @property
    def rank(self) -> int:
        return len(self.rows)

    def try_add(self, vec: Sequence[mpmath.mpf]) -> bool:
        with mpmath.workdps(self.dps):
            norm = mpmath.sqrt(mpmath.fsum(v * v for v in vec))
            if norm == 0:
                return False
            row = [v / norm for v in vec]
            mat = mpmath.matrix([*self.rows, row])
            sv = mpmath.svd_r(mat, compute_uv=False)
            smallest = min(sv[i] for i in range(len(self.rows) + 1))
            if smallest <= self.tol:
                return False
        self.rows.append(row)
        return True


class _ExactSpan:
    """Incremental span of exact vectors (rational or algebraic entries).

    Falls back to 50-digit numerics for entries that are not algebraic numbers
    (e.g. ``cos(1)``) and records it in :attr:`exact`.
    """

    def __init__(self, n: int) -> None:
        self.n = n
        self.rows: list[tuple[sp.Expr, ...]] = []
        self.exact = True
        self._numeric = _NumericSpan(POINT_TOL, 50)

    @property
    def rank(self) -> int:
        return len(self.rows)

    @staticmethod
    def _decidable(vec: Sequence[sp.Expr]) -> bool:
        return all(e.is_Rational or (not e.has(sp.Float) and e.is_algebraic) for e in vec)

    def try_add(self, vec: tuple[sp.Expr, ...]) -> bool:
        if all(e == 0 for e in vec):
            return False
        if self.exact and not self._decidable(vec):
            self.exact = False
            for row in self.rows:
                self._numeric.rows.append(_normalised(_mp_vector(row, 50), 50))
        if self.exact:
            rows = [*self.rows, vec]
            dm = DomainMatrix.from_list_sympy(len(rows), self.n, [list(r) for r in rows],
                                              extension=True)
            if not dm.domain.is_Field:
                dm = dm.to_field()
            if dm.rank() <= len(self.rows):
                return False
        elif not self._numeric.try_add(_mp_vector(vec, 50)):
            return False
        self.rows.append(vec)
        return True


def _mp_vector(vec: Sequence[sp.Expr], dps: int) -> list[mpmath.mpf]:
    with mpmath.workdps(dps):
        return [mpmath.mpf(str(sp.N(e, dps + 10))) for e in vec]


def _normalised(vec: list[mpmath.mpf], dps: int) -> list[mpmath.mpf]:
    with mpmath.workdps(dps):
        norm = mpmath.sqrt(mpmath.fsum(v * v for v in vec))
        return [v / norm for v in vec]


# --- generic growth vector ----------------------------------------------------


def _random_points(point: Sequence[sp.Expr], count: int) -> list[list[se.Basic]]:
    """Pseudo-random exact points near ``point``: ``p + δ`` with rational ``δ``.

    Exact, so that evaluation at 212 bits is accurate throughout (symengine
    would round rational coefficients to double precision if floats were
    substituted).  Floats in ``point`` are replaced by their exact binary value.
    """
    rng = random.Random(_SEED)
    den = 2**20
    half = int(GENERIC_PERTURBATION * den)
    out = []
    for _ in range(count):
        vals = []
        for v in point:
            centre = v.replace(lambda e: e.is_Float, lambda e: sp.Rational(e))
            delta = sp.Rational(rng.randint(-half, half), den)
            vals.append(to_symengine(centre + delta))
        out.append(vals)
    return out


def _numeric_values(sys: ControlSystem, word: Word, subs: dict) -> list[mpmath.mpf] | None:
    """Values of a word's field at an exact point, evaluated with 212-bit floats."""
    vals = []
    for e in word_field_symengine(sys, word):
        v = e.subs(subs) if e.free_symbols else e
        try:
            c = v.n(GENERIC_PREC_BITS, real=True)
        except (TypeError, RuntimeError, ValueError):
            return None
        text = str(c)
        if not _FINITE.fullmatch(text):
            return None
        with mpmath.workdps(_GENERIC_DPS + 10):
            vals.append(mpmath.mpf(text))
    return vals


def _generic_growth_at(sys: ControlSystem, values: list[se.Basic]) -> tuple[int, ...] | None:
    """Growth vector at a (random, assumed regular) point; None if a field is undefined there."""
    from nilpotent.core.brackets import _se_coords

    subs = dict(zip(_se_coords(sys), values, strict=True))
    span = _NumericSpan(GENERIC_TOL, _GENERIC_DPS)
    growth: list[int] = []
    newest: list[Word] = []
    for i in range(1, sys.m + 1):
        vec = _numeric_values(sys, i, subs)
        if vec is None:
            return None
        if span.try_add(vec):
            newest.append(i)
    generators = list(newest)
    growth.append(span.rank)
    while span.rank < sys.n:
        candidates = [(g, w) for w in newest for g in generators]
        newest = []
        for w in candidates:
            vec = _numeric_values(sys, w, subs)
            if vec is None:
                return None
            if span.try_add(vec):
                newest.append(w)
                if span.rank == sys.n:
                    break
        if not newest:
            break
        growth.append(span.rank)
    return tuple(growth)


def generic_growth_vector(
    sys: ControlSystem, point: Sequence[sp.Expr] | None = None
) -> tuple[int, ...]:
    """The growth vector at random points near ``point`` (the origin by default).

    Evaluated at two pseudo-random points (fixed seed) in the box of half-width
    :data:`GENERIC_PERTURBATION` around the point, with 212-bit floats; the
    componentwise maximum is returned (each is a lower bound of the generic value
    and equals it with probability one).
    """
    p = sys.point(point) if point is not None else sys.origin()
    results = []
    for values in _random_points(p, 6):
        g = _generic_growth_at(sys, values)
        if g is not None:
            results.append(g)
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


# --- analysis at p ------------------------------------------------------------


def _normalise_point(sys: ControlSystem, point: Sequence[object] | None) -> tuple[sp.Expr, ...]:
    if point is None:
        return sys.origin()
    if len(point) != sys.n:
        raise PointError(f"a point of {sys.name!r} has {sys.n} coordinates, got {len(point)}")
    return tuple(sp.S(v) for v in point)


def analyze(
    sys: ControlSystem, point: Sequence[object] | None = None, *, max_length: int | None = None
) -> Filtration:
    """Growth vector, weights, adapted frame and regularity of ``sys`` at ``point``.

    Parameters
    ----------
    sys:
        The system (parameters are substituted).
    point:
        The point $p$, a sequence of sympy numbers aligned with the coordinates
        (default: the origin).  Exact values give exact ranks.
    max_length:
        Longest bracket length examined at ``p`` (default $2n + 2$).  Only
        singular points can need lengths beyond the generic step.

    Returns
    -------
    Filtration
        See its attributes.  For a system that is not bracket-generating the
        growth vector ends at the dimension reached (``bracket_generating``
        false); this is a result, not an error.

    Raises
    ------
    NotBracketGeneratingError
        If brackets span $\\mathbb{R}^n$ at random points near ``p`` but those of
        length $\\le$ ``max_length`` do not span it at ``p``.
    PointError
        If the point has the wrong length or the fields are undefined there.

    Examples
    --------
    >>> x1, x2, x3 = sp.symbols("x1 x2 x3")
    >>> martinet = ControlSystem("martinet", (x1, x2, x3), ((1, 0, x2**2 / 2), (0, 1, 0)))
    >>> f = analyze(martinet)
    >>> f.growth_vector, f.weights, f.regular
    ((2, 2, 3), (1, 1, 3), False)
    >>> f.frame_names
    ('X1', 'X2', '[X2,[X1,X2]]')
    """
    p = _normalise_point(sys, point)
    n, m = sys.n, sys.m
    generic = generic_growth_vector(sys, p)
    final = generic[-1]
    limit = max_length if max_length is not None else 2 * n + 2
    span = _ExactSpan(n)
    frame: list[Word] = []
    values: list[tuple[sp.Expr, ...]] = []
    growth: list[int] = []
    for s in range(1, limit + 1):
        target = generic[s - 1] if s <= len(generic) else final
        if span.rank < target:
            for w in hall_basis(m, s):
                if word_length(w) != s:
                    continue
                (vec,) = word_values_at(sys, [w], p)
                if span.try_add(vec):
                    frame.append(w)
                    values.append(vec)
                    if span.rank == target:
                        break
        growth.append(span.rank)
        if span.rank == final:
            break
    if span.rank < final and final == n:
        raise NotBracketGeneratingError(
            f"the brackets of {sys.name!r} of length <= {limit} span only {span.rank} of "
            f"{n} dimensions at the point, while they span all {n} at nearby points; "
            f"pass a larger max_length"
        )
    while len(growth) > 1 and growth[-1] == growth[-2]:
        growth.pop()
    growth_t = tuple(growth)
    weights = tuple(
        s
        for s, (before, after) in enumerate(zip((0, *growth_t), growth_t, strict=False), start=1)
        for _ in range(after - before)
    )
    return Filtration(
        system=sys,
        point=p,
        bracket_generating=span.rank == n,
        growth_vector=growth_t,
        weights=weights,
        step=len(growth_t),
        frame=tuple(frame),
        frame_values=tuple(values),
        regular=growth_t == generic,
        generic_growth_vector=generic,
        exact=span.exact,
    )


def singular_locus(sys: ControlSystem, filtration: Filtration | None = None) -> sp.Expr:
    """The determinant of the adapted frame's fields, as an expression in the coordinates.

    Where this determinant is non-zero the frame words of ``filtration`` (by
    default ``analyze(sys)`` at the origin) are a basis adapted to the generic
    filtration, so the point is regular; its zero set therefore *contains* the
    singular points (it may also contain regular points where another frame
    would be needed).  Needs a square frame, i.e. a bracket-generating system.

    Raises
    ------
    NotBracketGeneratingError
        If the frame is not square (the system is not bracket-generating at the
        filtration's point).

    Examples
    --------
    >>> x1, x2, x3 = sp.symbols("x1 x2 x3")
    >>> martinet = ControlSystem("martinet", (x1, x2, x3), ((1, 0, x2**2 / 2), (0, 1, 0)))
    >>> singular_locus(martinet, analyze(martinet, (0, 1, 0)))
    -x2
    """
    f = filtration if filtration is not None else analyze(sys)
    if len(f.frame) != sys.n:
        raise NotBracketGeneratingError(
            f"the adapted frame of {sys.name!r} at the point has {len(f.frame)} fields for "
            f"n = {sys.n}: no determinant (the system is not bracket-generating there)"
        )
    cols = [word_field_symengine(sys, w) for w in f.frame]
    mat = se.DenseMatrix(sys.n, sys.n, [cols[k][j] for j in range(sys.n) for k in range(sys.n)])
    return sp.S(se.expand(mat.det()))
