"""The filtration $\\Delta^1 \\subset \\Delta^2 \\subset \\cdots$ of a system at a point.

$\\Delta^1 = \\mathrm{span}\\{X_i\\}$, $\\Delta^{s+1} = \\Delta^s + [\\Delta^1, \\Delta^s]$;
$n_s(p) = \\dim \\Delta^s(p)$ is spanned by the values at $p$ of the bracket words
of length $\\le s$ (of the Hall basis, :func:`nilpotent.core.brackets.hall_basis`).
:func:`analyze` gives the growth vector, the weights, the step, an adapted frame
made of Hall words, whether $p$ is regular and whether the system is
bracket-generating there.  Bracket convention $[X,Y] = DY\\cdot X - DX\\cdot Y$.

How it is computed
------------------
1. *Generic growth vector*, at a pseudo-random point $q$ near $p$ (fixed seed),
   confirmed at a second one.  A random point is regular with probability
   one, so near $q$ the words chosen up to length $s$ span $\\Delta^s$ as a
   module and $\\Delta^{s+1}(q)$ is spanned by them and the brackets $[X_i, Y]$
   with $Y$ a word chosen at length $s$: only $m\\,(n_s - n_{s-1})$ new
   brackets per length.  At a regular point the span grows at every length
   until it stops for ever, so this ends after at most $n$ lengths.  Values
   are doubles; a new word $[u, v]$ is evaluated from the fields of $u$ and
   $v$ by complex-step directional derivatives, so the longest fields are never
   expanded.  Each value is normalised and its distance to the span decides
   (independent above :data:`DOUBLE_INDEPENDENT`, dependent below
   :data:`DOUBLE_DEPENDENT`); in between, 212-bit values and :data:`GENERIC_TOL`
   decide.
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

import math
import random
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import mpmath
import symengine as se
import sympy as sp
from sympy.polys.matrices import DomainMatrix

from nilpotent.core.brackets import (
    Word,
    format_word,
    hall_basis,
    is_built,
    se_coordinates,
    to_symengine,
    to_sympy,
    word_field_symengine,
    word_length,
    word_values_at,
)
from nilpotent.core.system import ControlSystem
from nilpotent.errors import (
    ComputationLimitError,
    ModelError,
    NotBracketGeneratingError,
    PointError,
)

GENERIC_TOL = 1e-30
"""Relative tolerance of the 212-bit rank decisions at random points."""

GENERIC_ZERO = 1e-40
"""Norm below which a 212-bit value of a word at a random point is zero."""

DOUBLE_INDEPENDENT = 1e-6
DOUBLE_DEPENDENT = 1e-10
DOUBLE_ZERO = 1e-9
"""Double-precision thresholds at random points; between them, 212-bit values decide."""

COMPLEX_STEP = 1e-4
"""Relative step of the complex-step derivatives at random points."""

POINT_TOL = 1e-25
"""Relative tolerance of numerical rank decisions at ``p`` (50-digit evaluation)."""

POINT_ZERO = 1e-35
"""Norm below which a 50-digit value at ``p`` is zero."""

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
    max_length:
        The longest bracket length examined at ``p``.  When the system is
        bracket-generating at nearby points but not within this length at
        ``p`` (only possible at a singular point), ``bracket_generating`` is
        false *up to this length*: a longer bracket could still add a direction.
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
    max_length: int = 0

    @property
    def frame_names(self) -> tuple[str, ...]:
        """The frame words as users write them (``"[X1,X2]"``)."""
        return tuple(format_word(w) for w in self.frame)


# --- rank trackers ------------------------------------------------------------


def _residual(basis: list[list], vec: list, fsum) -> tuple[float, list]:
    """Distance of the unit vector ``vec`` to the span of the orthonormal ``basis``.

    Gram–Schmidt applied twice (stable); returns the distance and the residual.
    """
    res = list(vec)
    for _ in range(2):
        for b in basis:
            c = fsum(x * y for x, y in zip(res, b, strict=True))
            res = [x - c * y for x, y in zip(res, b, strict=True)]
    return fsum(x * x for x in res) ** 0.5, res


class _MpSpan:
    """Incremental span of real vectors at ``dps`` digits.

    A vector is independent when its distance to the span, after normalising it
    to unit length, exceeds ``tol``; a vector of norm below ``zero`` is zero
    (trigonometric identities leave such rounding residues).
    """

    def __init__(self, tol: float, zero: float, dps: int) -> None:
        self.tol, self.zero, self.dps = tol, zero, dps
        self.basis: list[list[mpmath.mpf]] = []

    def try_add(self, vec: Sequence[mpmath.mpf]) -> bool:
        with mpmath.workdps(self.dps):
            norm = mpmath.sqrt(mpmath.fsum(v * v for v in vec))
            if norm <= self.zero:
                return False
            dist, res = _residual(self.basis, [v / norm for v in vec], mpmath.fsum)
            if dist <= self.tol:
                return False
            self.basis.append([x / dist for x in res])
        return True


class _ExactSpan:
    """Incremental span of exact vectors (rational or algebraic entries).

    Ranks by fraction-free elimination over $\\mathbb{Q}$ or a number field; falls
    back to 50-digit numerics (tolerance :data:`POINT_TOL`) for entries that are
    not algebraic numbers (e.g. ``cos(1)``) and records it in :attr:`exact`.
    """

    def __init__(self, n: int) -> None:
        self.n = n
        self.rows: list[tuple[sp.Expr, ...]] = []
        self.exact = True
        self._numeric = _MpSpan(POINT_TOL, POINT_ZERO, 50)

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
                self._numeric.try_add(_mp_vector(row, 50))
        if self.exact:
            rows = [*self.rows, vec]
            dm = DomainMatrix.from_list_sympy(
                len(rows), self.n, [list(r) for r in rows], extension=True
            )
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


# --- generic growth vector ----------------------------------------------------


class _Undefined(Exception):
    """A field cannot be evaluated (pole, complex value) at a random point."""


def _random_points(point: Sequence[sp.Expr], count: int) -> list[list[sp.Expr]]:
    """Pseudo-random exact points near ``point``: ``p + δ`` with rational ``δ``.

    Exact, so that they can be evaluated at any precision (symengine rounds
    rational coefficients to double precision when floats are substituted).
    Floats in ``point`` are replaced by their exact binary value.
    """
    rng = random.Random(_SEED)
    den = 2**20
    half = int(GENERIC_PERTURBATION * den)
    out = []
    for _ in range(count):
        vals = []
        for v in point:
            centre = v.replace(lambda e: e.is_Float, lambda e: sp.Rational(e))
            vals.append(centre + sp.Rational(rng.randint(-half, half), den))
        out.append(vals)
    return out


def _as_float(v: se.Basic) -> float:
    """A real double from a symengine number (``atan2`` of doubles needs ``n()``)."""
    try:
        c = complex(v)
    except (TypeError, RuntimeError, ValueError):
        try:
            c = complex(v.n(53, real=True))
        except (TypeError, RuntimeError, ValueError) as exc:
            raise _Undefined from exc
    if not math.isfinite(c.real) or c.imag != 0:
        raise _Undefined
    return c.real


class _GenericPoint:
    """Values of words at one random point ``q``: doubles, and 212-bit when needed.

    Words whose field is not built yet, $[u, v]$, are evaluated as
    $Dv(q)u(q) - Du(q)v(q)$ from directional derivatives of the fields of ``u``
    and ``v``, so the longest fields are never expanded.
    """

    def __init__(self, sys: ControlSystem, exact_point: Sequence[sp.Expr]) -> None:
        self.sys = sys
        coords = se_coordinates(sys)
        self.exact = dict(zip(coords, (to_symengine(v) for v in exact_point), strict=True))
        self.q = {x: float(sp.N(v, 20)) for x, v in zip(coords, exact_point, strict=True)}
        self.doubles = {x: se.RealDouble(v) for x, v in self.q.items()}
        self._dcache: dict[Word, list[float]] = {}
        self._hcache: dict[Word, list[mpmath.mpf]] = {}

    def double(self, word: Word) -> list[float]:
        """Values in double precision."""
        hit = self._dcache.get(word)
        if hit is not None:
            return hit
        if is_built(self.sys, word):
            vals = [
                _as_float(e.subs(self.doubles) if e.free_symbols else e)
                for e in word_field_symengine(self.sys, word)
            ]
        else:
            u, v = word
            fu, fv = word_field_symengine(self.sys, u), word_field_symengine(self.sys, v)
            uq, vq = self.double(u), self.double(v)
            try:
                vals = [
                    b - a
                    for a, b in zip(self._step(fu, vq), self._step(fv, uq), strict=True)
                ]
            except _Undefined:
                word_field_symengine(self.sys, word)
                vals = self.double(word)
        self._dcache[word] = vals
        return vals

    def _step(self, field: Sequence[se.Basic], direction: Sequence[float]) -> list[float]:
        """Directional derivative $\\frac{d}{dt} Z(q + t d)|_{t=0}$ of ``field``, in doubles.

        Complex step $\\operatorname{Im} Z(q + i h d)/h$ (no cancellation), with
        Richardson extrapolation over $h$ and $2h$ (error $O(h^4)$), $h = 10^{-4}/|d|_\\infty$.
        Raises :class:`_Undefined` where the field has no complex extension in
        symengine (``atan2``); the caller then builds the bracket instead.
        """
        scale = max(abs(d) for d in direction)
        if scale == 0:
            return [0.0] * len(field)
        h = COMPLEX_STEP / scale
        steps = []
        for hh in (h, 2 * h):
            subs = {
                x: se.S(complex(self.q[x], hh * d)) if d != 0 else self.doubles[x]
                for x, d in zip(self.q, direction, strict=True)
            }
            row = []
            for e in field:
                if not e.free_symbols:
                    row.append(0.0)
                    continue
                try:
                    c = complex(e.subs(subs))
                except (TypeError, RuntimeError, ValueError) as exc:
                    raise _Undefined from exc
                if not (math.isfinite(c.real) and math.isfinite(c.imag)):
                    raise _Undefined
                row.append(c.imag / hh)
            steps.append(row)
        return [(4 * a - b) / 3 for a, b in zip(*steps, strict=True)]

    def precise(self, word: Word) -> list[mpmath.mpf]:
        """Values at 212 bits (the word's field is built for it)."""
        hit = self._hcache.get(word)
        if hit is not None:
            return hit
        vals = []
        for e in word_field_symengine(self.sys, word):
            v = e.subs(self.exact) if e.free_symbols else e
            try:
                text = str(v.n(GENERIC_PREC_BITS, real=True))
            except (TypeError, RuntimeError, ValueError) as exc:
                raise _Undefined from exc
            if not _FINITE.fullmatch(text):
                raise _Undefined
            with mpmath.workdps(_GENERIC_DPS + 10):
                vals.append(mpmath.mpf(text))
        self._hcache[word] = vals
        return vals


class _GenericSpan:
    """Span of word values at a random point: double precision, 212 bits when unclear.

    After normalising, a distance to the span above :data:`DOUBLE_INDEPENDENT` is
    independent and one below :data:`DOUBLE_DEPENDENT` dependent; in between (or
    for a vector of norm below :data:`DOUBLE_ZERO`) the decision is redone from
    212-bit values with :data:`GENERIC_TOL`.
    """

    def __init__(self, at: _GenericPoint) -> None:
        self.at = at
        self.words: list[Word] = []
        self.basis: list[list[float]] = []

    @property
    def rank(self) -> int:
        return len(self.words)

    def try_add(self, word: Word) -> bool:
        vec = self.at.double(word)
        norm = math.fsum(v * v for v in vec) ** 0.5
        dist, res = (0.0, vec) if norm == 0 else _residual(
            self.basis, [v / norm for v in vec], math.fsum
        )
        if norm == 0 or (dist < DOUBLE_DEPENDENT and norm > DOUBLE_ZERO):
            return False
        if not (dist > DOUBLE_INDEPENDENT and norm > DOUBLE_ZERO) and not self._precise(word):
            return False
        self.words.append(word)
        if dist > 0:
            self.basis.append([x / dist for x in res])
        return True

    def _precise(self, word: Word) -> bool:
        span = _MpSpan(GENERIC_TOL, GENERIC_ZERO, _GENERIC_DPS)
        for w in self.words:
            span.try_add(self.at.precise(w))
        return span.try_add(self.at.precise(word))


def _generic_growth_at(
    at: _GenericPoint, n: int, m: int, frame: Sequence[Word] | None = None
) -> tuple[tuple[int, ...], tuple[Word, ...]]:
    """Growth vector at a (random, assumed regular) point, and the words that realise it.

    With ``frame`` given, only those words are evaluated (a cheap confirmation at
    a second point); else new words are the brackets ``[X_i, Y]`` of the chosen
    generators with the words chosen at the previous length.
    """
    span = _GenericSpan(at)
    growth: list[int] = []
    if frame is not None:
        by_length: dict[int, list[Word]] = {}
        for w in frame:
            by_length.setdefault(word_length(w), []).append(w)
        for s in range(1, max(by_length, default=0) + 1):
            for w in by_length.get(s, []):
                span.try_add(w)
            growth.append(span.rank)
        return tuple(growth), tuple(span.words)
    newest: list[Word] = [i for i in range(1, m + 1) if span.try_add(i)]
    generators = list(newest)
    growth.append(span.rank)
    while span.rank < n:
        candidates = [(g, w) for w in newest for g in generators]
        newest = []
        for w in candidates:
            if span.try_add(w):
                newest.append(w)
                if span.rank == n:
                    break
        if not newest:
            break
        growth.append(span.rank)
    return tuple(growth), tuple(span.words)


def generic_growth_vector(
    sys: ControlSystem, point: Sequence[sp.Expr] | None = None
) -> tuple[int, ...]:
    """The growth vector at random points near ``point`` (the origin by default).

    A pseudo-random exact point (fixed seed) in the box of half-width
    :data:`GENERIC_PERTURBATION` around ``point`` is regular with probability one;
    there the words chosen at length $s$ span $\\Delta^s$ as a module, so only
    the brackets $[X_i, Y]$ with the words $Y$ chosen at the previous length are
    needed.  The growth of the same words is confirmed at a second random point
    and the componentwise maximum returned (each is a lower bound of the
    generic value); if the two differ, the second point is analysed in full.
    """
    p = _normalise_point(sys, point)
    results: list[tuple[int, ...]] = []
    frame: tuple[Word, ...] | None = None
    for values in _random_points(p, 8):
        try:
            at = _GenericPoint(sys, values)
            growth, words = _generic_growth_at(at, sys.n, sys.m, frame)
            if frame is not None and growth != results[0]:
                growth, words = _generic_growth_at(at, sys.n, sys.m)
        except _Undefined:
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


# --- analysis at p ------------------------------------------------------------


def _normalise_point(
    sys: ControlSystem, point: Sequence[object] | Mapping[str, object] | None
) -> tuple[sp.Expr, ...]:
    """The point as sympy numbers; checks its length, that it is real, and the fields."""
    extra = set().union(*(sp.S(e).free_symbols for f in sys.specialized_fields for e in f))
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
    values = tuple(sp.S(v) for v in point)
    for name, v in zip(sys.coordinate_names, values, strict=True):
        if not (v.is_number and v.is_real is not False and v.is_finite is not False):
            raise PointError(f"coordinate {name} of the point must be a real number, got {v}")
    return values


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
        Longest bracket length examined at ``p`` (default
        :func:`default_max_length`).  Only singular points can need lengths
        beyond the generic step; if the brackets up to this length do not span
        at ``p`` while they do nearby, the result says ``bracket_generating``
        false and records the length examined in ``Filtration.max_length``.

    Returns
    -------
    Filtration
        See its attributes.  For a system that is not bracket-generating the
        growth vector ends at the dimension reached (``bracket_generating``
        false); this is a result, not an error.

    Raises
    ------
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
    if max_length is not None:
        check_hall_budget(m, max_length)
    limit = max_length if max_length is not None else default_max_length(n, m)
    limit = max(limit, len(generic))
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
        max_length=limit,
    )


HALL_WORD_BUDGET = 5000
"""Most Hall words the default ``max_length`` lets :func:`analyze` examine at ``p``."""


def default_max_length(n: int, m: int) -> int:
    r"""The default longest bracket length examined at a point.

    $\max(2n + 2, 12)$, lowered so that at most :data:`HALL_WORD_BUDGET` Hall
    words (Witt's formula) of length $\le$ it exist for $m$ generators; it only
    matters at singular points, where the span can stall and grow again later.
    """
    total = 0
    length = 0
    wanted = max(2 * n + 2, 12)
    while length < wanted:
        count = _witt(m, length + 1)
        if total + count > HALL_WORD_BUDGET and length >= 2:
            break
        total += count
        length += 1
    return length


def check_hall_budget(m: int, max_length: int) -> None:
    """Refuse an explicit ``max_length`` whose Hall words exceed :data:`HALL_WORD_BUDGET`.

    Raises
    ------
    ComputationLimitError
        Naming the number of Hall words, the budget and the option (``--max-length``).
    """
    total = 0
    for length in range(1, max_length + 1):
        total += _witt(m, length)
        if total > HALL_WORD_BUDGET:
            raise ComputationLimitError(
                f"--max-length {max_length} with {m} fields means more than "
                f"{HALL_WORD_BUDGET:,} Hall words (the budget HALL_WORD_BUDGET; already "
                f"{total:,} up to length {length}); give a --max-length of at most "
                f"{default_max_length_for_budget(m)}"
            )


def default_max_length_for_budget(m: int) -> int:
    """The longest bracket length whose Hall words fit in :data:`HALL_WORD_BUDGET`."""
    total = length = 0
    while True:
        count = _witt(m, length + 1)
        if total + count > HALL_WORD_BUDGET:
            return max(length, 1)
        total += count
        length += 1


def _witt(m: int, k: int) -> int:
    """Dimension of the degree-k part of the free Lie algebra on m generators."""
    return sum(_mobius(d) * m ** (k // d) for d in range(1, k + 1) if k % d == 0) // k


def _mobius(k: int) -> int:
    result, q = 1, 2
    while q * q <= k:
        if k % q == 0:
            k //= q
            if k % q == 0:
                return 0
            result = -result
        q += 1
    return -result if k > 1 else result


def singular_locus(sys: ControlSystem, filtration: Filtration | None = None) -> sp.Expr:
    """The determinant of the adapted frame's fields, as an expression in the coordinates.

    Where this determinant is non-zero the frame words of ``filtration`` (by
    default ``analyze(sys)`` at the origin) are a basis adapted to the generic
    filtration, so the point is regular; its zero set therefore *contains* the
    singular points (it may also contain regular points where another frame
    would be needed).  Needs a square frame, i.e. a bracket-generating system.

    Raises
    ------
    ComputationLimitError
        If a frame field is longer than :data:`SINGULAR_LOCUS_MAX_CHARS`
        characters (the expanded determinant would be unmanageable).
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
    sizes = [sum(len(str(e)) for e in col) for col in cols]
    if max(sizes) > SINGULAR_LOCUS_MAX_CHARS:
        worst = max(range(len(sizes)), key=sizes.__getitem__)
        raise ComputationLimitError(
            f"the singular locus of {sys.name!r} is not expanded: the frame field "
            f"{format_word(f.frame[worst])} alone has {sizes[worst]:,} characters (limit "
            f"{SINGULAR_LOCUS_MAX_CHARS:,}), so the {sys.n}x{sys.n} determinant would be far "
            "larger; analyze points instead (the regular/singular verdict at a point needs "
            "no determinant)"
        )
    mat = se.DenseMatrix(sys.n, sys.n, [cols[k][j] for j in range(sys.n) for k in range(sys.n)])
    return to_sympy(sys, se.expand(mat.det()))


SINGULAR_LOCUS_MAX_CHARS = 20_000
"""Largest frame column (characters of its components) whose determinant is expanded."""
