r"""The one rank engine: certified decisions "is this vector new?" and "is this value zero?".

Every rank decision of the core (growth vectors at a point and at random points,
the brackets of a nilpotent approximation, the rank checks of planning and of the
audit) goes through :class:`Span`.  A decision is one of three answers
(:class:`Decision`):

*independent*
    proved: the Gram determinant of the *normalised* vectors (each divided by
    its Euclidean norm, so that the decision does not depend on the scale of
    the fields) is enclosed in a ball of python-flint's ``arb`` that excludes
    0, or exact arithmetic says so;
*dependent*
    proved by exact arithmetic: rational values (decimals are read as the exact
    rationals they denote, ``0.7`` is ``7/10``) by fraction-free elimination in
    python-flint's ``fmpq_mat``; algebraic values (``sqrt(3)/2``) by sympy's
    elimination over a number field, within :data:`ALGEBRAIC_BUDGET` characters;
*undetermined*
    neither could be proved: the balls still contain 0 at
    :data:`MAX_PRECISION_BITS` bits and the values are not exact algebraic
    numbers (``cos(1)`` at a singular point), or exact arithmetic is over its
    budget.  The caller reports it; it never turns it into a verdict.

Ball evaluation starts at :data:`START_PRECISION_BITS` bits and doubles.  No
absolute threshold is used anywhere: a system scaled by $10^{300}$ or
$10^{-300}$ gets the same decisions (arb's exponents are unbounded).

Values are given as exact constant expressions (sympy or symengine), Python or
flint numbers, or as a :class:`Vector` that computes its balls and its exact
values on demand (e.g. a bracket's value from directional derivatives).

A :class:`Span` built with ``probabilistic=True`` (the analysis at a random
point) also calls *dependent* a vector whose normalised Gram determinant is
still enclosed in a ball of radius below $2^{-3P/4}$ at the last precision
$P$ tried: a nonzero value that small at a pseudo-random point has probability
zero, like every other statement about random points.  Before raising the
precision it tries the vectors' polynomial forms (:meth:`Vector.free`): when
they are exactly dependent (``fmpq_mat``) at a pseudo-random integer point of
$[2^{61}, 2^{62})^N$, the dependence is a polynomial identity with probability
at least $1 - D/2^{61}$ ($D$ the degree of a minor, Schwartz-Zippel), hence
holds at the random point too; else the balls go on as before.
"""

from __future__ import annotations

import abc
import enum
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import sympy as sp
from flint import arb, arb_mat, fmpq, fmpq_mat

from nilpotent.core.decide.evaluation import (
    FLOAT_RELATIVE_TOLERANCE,
    START_PRECISION_BITS,
    Evaluator,
    Inaccurate,
    NotEvaluable,
    NotRational,
    SymbolicEvaluator,
    ball,
    exact_value,
    negligible,
    precision,
    to_double,
)
from nilpotent.core.model.expressions import exact_decimals

__all__ = [
    "ALGEBRAIC_BUDGET",
    "FLOAT_RELATIVE_TOLERANCE",
    "MAX_PRECISION_BITS",
    "START_PRECISION_BITS",
    "Decision",
    "Evaluator",
    "ExprVector",
    "Inaccurate",
    "MeasuredSpan",
    "NotEvaluable",
    "NotRational",
    "Span",
    "SymbolicEvaluator",
    "Vector",
    "ball",
    "exact_decimals",
    "exact_value",
    "is_zero",
    "negligible",
    "numeric_rank",
    "rank",
    "to_double",
]

MAX_PRECISION_BITS = 1024
"""Highest working precision tried before a decision is *undetermined* (bits)."""

ALGEBRAIC_BUDGET = 20_000
"""Most characters of exact algebraic entries given to sympy's number-field elimination."""


class Decision(enum.Enum):
    """The answer to "is this vector independent of the span?"."""

    INDEPENDENT = "independent"
    DEPENDENT = "dependent"
    UNDETERMINED = "undetermined"


# --- vectors --------------------------------------------------------------------------------

Key = object


class Vector(abc.ABC):
    """A vector whose entries are computed on demand; sparse (a mapping key → value).

    Subclasses give :meth:`rational` (all entries as ``fmpq`` or ``None``),
    :meth:`balls` (entries at a precision) and :meth:`symbolic` (exact sympy
    entries, or ``None`` when not available within a budget).
    """

    @abc.abstractmethod
    def rational(self) -> dict[Key, fmpq] | None:
        """All entries as exact rationals, or None when some entry is not rational."""

    @abc.abstractmethod
    def balls(self, prec: int) -> dict[Key, arb]:
        """All entries as arb balls at ``prec`` bits."""

    def symbolic(self) -> dict[Key, sp.Expr] | None:
        return None

    def free(self) -> dict[Key, fmpq] | None:
        """Exact values of the vector's polynomial form at a random free point, or None.

        A vector given by polynomials in variables (coordinates and atoms,
        :mod:`nilpotent.core.lie.polynomial_fields`) evaluated at a pseudo-random
        integer point where the variables are treated as independent: a
        dependence found there is a polynomial identity (Schwartz-Zippel),
        true at every point.  Used only by a probabilistic :class:`Span`.
        """
        return None


class ExprVector(Vector):
    """A vector of exact constant expressions (sympy, symengine, ints, fractions, decimals)."""

    def __init__(self, entries: Sequence[object] | Mapping[Key, object]) -> None:
        items = entries.items() if isinstance(entries, Mapping) else enumerate(entries)
        self.entries: dict[Key, object] = {k: v for k, v in items if not _is_literal_zero(v)}
        self._rational: dict[Key, fmpq] | bool | None = False
        self._balls: dict[int, dict[Key, arb]] = {}

    def rational(self) -> dict[Key, fmpq] | None:
        if self._rational is False:
            out: dict[Key, fmpq] | None = {}
            for k, v in self.entries.items():
                q = exact_value(v)
                if q is None:
                    out = None
                    break
                if q != 0:
                    out[k] = q
            self._rational = out
        return self._rational  # type: ignore[return-value]

    def balls(self, prec: int) -> dict[Key, arb]:
        hit = self._balls.get(prec)
        if hit is None:
            hit = {k: ball(v, prec) for k, v in self.entries.items()}
            self._balls[prec] = hit
        return hit

    def symbolic(self) -> dict[Key, sp.Expr] | None:
        out = {}
        for k, v in self.entries.items():
            if isinstance(v, arb):
                return None
            out[k] = exact_decimals(v if not isinstance(v, fmpq) else sp.Rational(
                int(v.p), int(v.q)))
        return out


def _is_literal_zero(v: object) -> bool:
    if isinstance(v, arb):
        return v.is_zero()
    try:
        return v == 0
    except TypeError:  # pragma: no cover
        return False


def _as_vector(v: Vector | Sequence[object] | Mapping[Key, object]) -> Vector:
    return v if isinstance(v, Vector) else ExprVector(v)


# --- the span ---------------------------------------------------------------------------------


@dataclass
class Span:
    """An incremental span of real vectors with certified decisions.

    Parameters
    ----------
    probabilistic:
        Vectors are values at a pseudo-random point: a Gram determinant still
        enclosed in a ball of radius below $2^{-3P/4}$ at the last precision
        $P$ counts as dependent (see the module docstring).
    max_precision:
        Highest working precision (bits) before *undetermined*.

    Attributes
    ----------
    vectors:
        The kept vectors (certified independent).
    precision_reached:
        The highest precision used so far (bits).
    exact:
        Whether every *dependent* answer so far was proved by exact arithmetic.
    """

    probabilistic: bool = False
    max_precision: int = MAX_PRECISION_BITS
    vectors: list[Vector] = field(default_factory=list)
    precision_reached: int = 0
    exact: bool = True
    _undetermined: int = 0

    @property
    def rank(self) -> int:
        return len(self.vectors)

    def add(self, vec: Vector | Sequence[object] | Mapping[Key, object]) -> Decision:
        """Decide whether ``vec`` is independent of the span; keep it if it is."""
        v = _as_vector(vec)
        decision = self.decide(v)
        if decision is Decision.INDEPENDENT:
            self.vectors.append(v)
        elif decision is Decision.UNDETERMINED:
            self._undetermined += 1
        return decision

    def try_add(self, vec: Vector | Sequence[object] | Mapping[Key, object]) -> bool:
        """:meth:`add`, True only when the vector was proved independent (and kept)."""
        return self.add(vec) is Decision.INDEPENDENT

    def decide(self, v: Vector) -> Decision:
        """The decision for ``v`` (without keeping it)."""
        rows = [*self.vectors, v]
        exact_rows = [r.rational() for r in rows]
        if all(r is not None for r in exact_rows):
            return _exact_decision(exact_rows)  # type: ignore[arg-type]
        prec = START_PRECISION_BITS
        tried_algebraic = False
        tried_free = False
        floor = None
        while True:
            self.precision_reached = max(self.precision_reached, prec)
            balls = [r.balls(prec) for r in rows]
            if not balls[-1]:
                return Decision.DEPENDENT  # every entry is an exact 0
            with precision(prec):
                gram = _gram_det(balls)
            if gram is not None and gram > 0:
                return Decision.INDEPENDENT
            if self.probabilistic:
                if not tried_free:
                    tried_free = True
                    free = [r.free() for r in rows]
                    if all(f is not None for f in free) and (
                        _exact_decision(free) is Decision.DEPENDENT  # type: ignore[arg-type]
                    ):
                        self.exact = False
                        return Decision.DEPENDENT
                if floor is None:
                    floor = _probabilistic_floor(balls, len(rows))
                tiny = arb(2) ** (-(3 * prec) // 4)
                if gram is not None and prec >= floor and gram.rad() < tiny:
                    self.exact = False
                    return Decision.DEPENDENT
            elif not tried_algebraic and prec >= 2 * START_PRECISION_BITS:
                tried_algebraic = True
                answer = _algebraic_decision(rows)
                if answer is not None:
                    return answer
            limit = max(self.max_precision, floor or 0)
            if prec >= limit:
                return Decision.UNDETERMINED
            prec *= 2


PROBABILISTIC_MAX_PRECISION_BITS = 1 << 15
"""Highest precision of a decision at a random point (bits)."""


def _probabilistic_floor(balls: Sequence[Mapping[Key, arb]], k: int) -> int:
    """The least precision at which a random-point Gram determinant near 0 counts as 0.

    $256 + 2kR$ bits, $R$ the spread (in bits) of the magnitudes of the
    entries: a determinant of $k$ rows of entries spread over $2^R$ can be as
    small as about $2^{-2kR}$ without being 0.
    """
    exps = []
    for r in balls:
        for x in r.values():
            m = x.mid()
            if m != 0 and m.is_finite():
                man, ex = m.man_exp()
                exps.append(int(ex) + int(man).bit_length())
    spread = (max(exps) - min(exps)) if exps else 0
    need = 256 + 2 * k * spread
    bits = START_PRECISION_BITS
    while bits < need:
        bits *= 2
    return min(bits, PROBABILISTIC_MAX_PRECISION_BITS)


def _exact_decision(rows: Sequence[Mapping[Key, fmpq]]) -> Decision:
    last = rows[-1]
    if not last:
        return Decision.DEPENDENT
    keys = sorted({k for r in rows for k in r}, key=repr)
    mat = fmpq_mat(len(rows), len(keys), [r.get(k, fmpq(0)) for r in rows for k in keys])
    return Decision.INDEPENDENT if mat.rank() == len(rows) else Decision.DEPENDENT


def _gram_det(rows: Sequence[Mapping[Key, arb]]) -> arb | None:
    """Determinant of the Gram matrix of the equilibrated rows (None if a norm is not positive).

    Each column (coordinate) with a certified nonzero entry is first divided by
    the largest magnitude in it, and then each row by its norm: neither scaling
    changes the rank (the enclosures contain the matrix scaled by the midpoints
    of the factors), and together they make the decision independent of the
    units of the coordinates and of the size of the fields.  The columns of
    certified nonzero entries are tried alone first (a nonzero minor there is a
    nonzero minor of the whole matrix); then all columns, those whose entries
    all enclose 0 left unscaled.
    """
    certain: dict[Key, arb] = {}
    for r in rows:
        for k, x in r.items():
            if not x.contains(0):
                up = x.abs_upper()
                if k not in certain or up > certain[k]:
                    certain[k] = up
    inv = {k: 1 / arb(v) for k, v in certain.items()}
    first = _unit_gram([{k: x * inv[k] for k, x in r.items() if k in inv} for r in rows])
    if first is not None and first > 0:
        return first
    return _unit_gram([{k: x * inv.get(k, 1) for k, x in r.items()} for r in rows])


def _unit_gram(rows: Sequence[Mapping[Key, arb]]) -> arb | None:
    units = []
    for r in rows:
        norm2 = sum((x * x for x in r.values()), arb(0))
        if not norm2 > 0:
            if norm2.is_zero():
                return arb(0)
            return None
        inv = 1 / norm2.sqrt()
        units.append({k: x * inv for k, x in r.items()})
    k = len(units)
    g = arb_mat(k, k)
    for i in range(k):
        for j in range(i, k):
            a, b = units[i], units[j]
            if len(b) < len(a):
                a, b = b, a
            s = sum((x * b[key] for key, x in a.items() if key in b), arb(0))
            g[i, j] = s
            g[j, i] = s
    d = g.det()
    return d if d.is_finite() else None


def _algebraic_decision(rows: Sequence[Vector]) -> Decision | None:
    """Exact rank over a number field (sympy), within :data:`ALGEBRAIC_BUDGET` characters."""
    from sympy.polys.matrices import DomainMatrix

    sym = [r.symbolic() for r in rows]
    if any(s is None for s in sym):
        return None
    if not sym[-1]:
        return Decision.DEPENDENT
    rational = [{k: exact_value(e) for k, e in s.items()} for s in sym]  # type: ignore[union-attr]
    if all(q is not None for r in rational for q in r.values()):
        return _exact_decision([{k: q for k, q in r.items() if q != 0} for r in rational])  # type: ignore[misc]
    entries = [e for s in sym for e in s.values()]  # type: ignore[union-attr]
    if sum(len(str(e)) for e in entries) > ALGEBRAIC_BUDGET:
        return None
    if not all(e.is_Rational or e.is_algebraic for e in entries):
        return None
    keys = sorted({k for s in sym for k in s}, key=repr)  # type: ignore[union-attr]
    try:
        dm = DomainMatrix.from_list_sympy(
            len(rows), len(keys), [[s.get(k, sp.S(0)) for k in keys] for s in sym],  # type: ignore[union-attr]
            extension=True,
        )
        if not dm.domain.is_Field:
            dm = dm.to_field()
        r = dm.rank()
    except (NotImplementedError, sp.polys.polyerrors.PolificationFailed, ValueError):
        return None
    return Decision.INDEPENDENT if r == len(rows) else Decision.DEPENDENT


# --- one-call helpers -------------------------------------------------------------------------


def is_zero(e: object, max_precision: int = MAX_PRECISION_BITS) -> bool | None:
    """Whether a real constant is zero: True / False when proved, ``None`` when undetermined.

    Exact for rationals (decimals read exactly) and, within the budget, for
    algebraic numbers; else a ball at rising precision proves a nonzero.
    """
    d = Span(max_precision=max_precision).add([e])
    if d is Decision.UNDETERMINED:
        return None
    return d is Decision.DEPENDENT


def rank(vectors: Sequence[Sequence[object]], *, probabilistic: bool = False) -> tuple[int, int]:
    """Certified bounds ``(lo, hi)`` of the rank of exact vectors (``lo == hi`` when decided).

    ``probabilistic``: the values are taken at a pseudo-random point (see :class:`Span`).
    """
    span = Span(probabilistic=probabilistic)
    undetermined = 0
    for v in vectors:
        if span.add(v) is Decision.UNDETERMINED:
            undetermined += 1
    return span.rank, span.rank + undetermined


class MeasuredSpan:
    """Incremental span of vectors of floating-point *measurements* (not exact values).

    For values known only to rounding (coefficients computed in floating point
    at a transcendental point, numerical Jacobians) no decision can be
    certified; this span is scale-invariant (each vector normalised to unit
    length) and calls a vector new when its distance to the span exceeds
    ``rel_tol``.  :attr:`rank` counts the kept vectors.
    """

    def __init__(self, rel_tol: float = FLOAT_RELATIVE_TOLERANCE) -> None:
        self.rel_tol = rel_tol
        self.keys: dict[Key, int] = {}
        self.basis: list[dict[Key, float]] = []

    @property
    def rank(self) -> int:
        return len(self.basis)

    def try_add(self, vec: Mapping[Key, object]) -> bool:
        v = {k: to_double(x) for k, x in vec.items()}
        big = max((abs(x) for x in v.values()), default=0.0)
        if big == 0.0 or big != big or big == float("inf"):
            return False
        v = {k: x / big for k, x in v.items()}  # no underflow in the norm
        norm = sum(x * x for x in v.values()) ** 0.5
        u = {k: x / norm for k, x in v.items()}
        for _ in range(2):
            for b in self.basis:
                c = sum(x * b.get(k, 0.0) for k, x in u.items())
                for k, bx in b.items():
                    u[k] = u.get(k, 0.0) - c * bx
        dist = sum(x * x for x in u.values()) ** 0.5
        if dist <= self.rel_tol:
            return False
        self.basis.append({k: x / dist for k, x in u.items()})
        return True


def numeric_rank(
    rows: Sequence[Sequence[float]], rel_tol: float = FLOAT_RELATIVE_TOLERANCE
) -> int:
    """Rank of a matrix of floating-point *measurements* (not exact values).

    Scale-invariant: each row is normalised to unit norm, then a vector counts
    as new when its distance to the span of the previous ones exceeds
    ``rel_tol``.  For values known only to rounding (numerical Jacobians,
    simulated flows) no certification is possible; exact inputs should use
    :class:`Span`.
    """
    import numpy as np

    kept: list[np.ndarray] = []
    for row in rows:
        v = np.asarray(row, dtype=float)
        big = float(np.max(np.abs(v))) if v.size else 0.0
        if not np.isfinite(big) or big == 0.0:
            continue
        v = v / big  # no underflow in the norm
        u = v / float(np.linalg.norm(v))
        for _ in range(2):
            for b in kept:
                u = u - (u @ b) * b
        dist = float(np.linalg.norm(u))
        if dist > rel_tol:
            kept.append(u / dist)
    return len(kept)
