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
zero, like every other statement about random points.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from fractions import Fraction

import flint
import symengine as se
import sympy as sp
from flint import arb, arb_mat, fmpq, fmpq_mat

__all__ = [
    "ALGEBRAIC_BUDGET",
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
    "numeric_rank",
    "rank",
    "to_double",
]

START_PRECISION_BITS = 64
"""Working precision of the first ball evaluation (bits)."""

MAX_PRECISION_BITS = 1024
"""Highest working precision tried before a decision is *undetermined* (bits)."""

ALGEBRAIC_BUDGET = 20_000
"""Most characters of exact algebraic entries given to sympy's number-field elimination."""


class Decision(enum.Enum):
    """The answer to "is this vector independent of the span?"."""

    INDEPENDENT = "independent"
    DEPENDENT = "dependent"
    UNDETERMINED = "undetermined"


class NotEvaluable(ValueError):
    """A constant expression cannot be evaluated (pole, complex value, unknown function)."""


class NotRational(Exception):
    """The value is not a rational number (exact rational arithmetic cannot carry it)."""


class Inaccurate(Exception):
    """A ball evaluation lost all accuracy (e.g. ``sqrt`` of a ball around 0)."""


# --- decimals ---------------------------------------------------------------------------


def _decimal_rational(f: float | sp.Float) -> sp.Rational:
    """The exact rational a decimal denotes: the shortest decimal that reads back as the float."""
    if isinstance(f, sp.Float) and f._prec != 53:
        return sp.Rational(str(f))
    return sp.Rational(repr(float(f)))


def exact_decimals(expr: object) -> sp.Expr:
    """``expr`` with every decimal (float) replaced by the exact rational it denotes.

    ``0.7`` becomes ``7/10`` (the shortest decimal that reads back as the double),
    so that decimals are decided exactly like fractions.

    Examples
    --------
    >>> exact_decimals(sp.Float(0.7) * sp.Symbol("x"))
    7*x/10
    """
    e = sp.S(expr)
    floats = e.atoms(sp.Float)
    if not floats:
        return e
    return e.xreplace({f: _decimal_rational(f) for f in floats})


# --- evaluation of constant expressions ---------------------------------------------------


def _check(value: arb) -> arb:
    if not value.is_finite():
        raise Inaccurate
    return value


_BALL_FUNCTIONS: dict[type, Callable[[arb], arb]] = {
    se.sin: arb.sin, se.cos: arb.cos, se.tan: arb.tan, se.exp: arb.exp, se.log: arb.log,
    se.atan: arb.atan, se.sinh: arb.sinh, se.cosh: arb.cosh, se.tanh: arb.tanh,
    se.asin: arb.asin, se.acos: arb.acos,
}


_CONSTANT = type(se.pi).__mro__[1]
_COMPLEX = type(se.I).__mro__[2]


def _deriv(func: type, v: arb) -> arb:
    """Derivative of a one-argument function at the ball ``v``."""
    if func is se.sin:
        return v.cos()
    if func is se.cos:
        return -v.sin()
    if func is se.tan:
        return 1 + v.tan() ** 2
    if func is se.exp:
        return v.exp()
    if func is se.log:
        return 1 / v
    if func is se.atan:
        return 1 / (1 + v * v)
    if func is se.sinh:
        return v.cosh()
    if func is se.cosh:
        return v.sinh()
    if func is se.tanh:
        return 1 - v.tanh() ** 2
    if func is se.asin:
        return 1 / (1 - v * v).sqrt()
    if func is se.acos:
        return -1 / (1 - v * v).sqrt()
    raise NotEvaluable(f"no derivative for {func}")  # pragma: no cover


class Evaluator:
    r"""Evaluate symengine expressions at a point: exactly or in balls, with derivatives.

    Parameters
    ----------
    env:
        Values of the symbols: :class:`flint.fmpq` (exact mode) or :class:`flint.arb`.
    exact:
        Exact rational arithmetic (``fmpq``); a value that is not rational
        (``pi``, ``cos(1)``, ``sqrt(2)``) raises ``NotRational``.  Else balls at
        the current ``flint.ctx.prec``.
    direction:
        If given, values of $\dot x$: :meth:`dual` returns $(f(x), \frac{d}{dt}f(x + t\dot x))$.
    """

    def __init__(
        self, env: Mapping[se.Basic, object], exact: bool, direction: Mapping | None = None
    ) -> None:
        self.env = env
        self.exact = exact
        self.direction = direction or {}
        self._memo: dict[se.Basic, tuple[object, object]] = {}

    def _num(self, e: se.Basic) -> object:
        if isinstance(e, se.Integer):
            return fmpq(int(e)) if self.exact else arb(int(e))
        if isinstance(e, se.Rational):
            p, q = e.get_num_den()
            v = fmpq(int(p), int(q))
            return v if self.exact else arb(v)
        if isinstance(e, se.RealDouble):
            fr = Fraction(repr(float(e)))
            v = fmpq(fr.numerator, fr.denominator)
            return v if self.exact else arb(v)
        if self.exact:
            raise NotRational
        if e == se.pi:
            return arb.pi()
        if e == se.E:
            return arb.const_e()
        raise NotEvaluable(f"cannot evaluate the number {e}")

    def dual(self, e: se.Basic) -> tuple[object, object]:
        """Value and directional derivative of ``e``."""
        hit = self._memo.get(e)
        if hit is not None:
            return hit
        out = self._dual(e)
        self._memo[e] = out
        return out

    def value(self, e: se.Basic) -> object:
        """Value of ``e``."""
        return self.dual(e)[0]

    def _zero(self) -> object:
        return fmpq(0) if self.exact else arb(0)

    def _dual(self, e: se.Basic) -> tuple[object, object]:
        if e.is_Symbol:
            if e not in self.env:
                raise NotEvaluable(f"no value for {e}")
            d = self.direction.get(e)
            return self.env[e], (d if d is not None else self._zero())
        if e.is_Number or isinstance(e, _CONSTANT):
            if isinstance(e, _COMPLEX):
                raise NotEvaluable(f"complex value {e}")
            return self._num(e), self._zero()
        if isinstance(e, se.Add):
            v, d = self._zero(), self._zero()
            for a in e.args:
                av, ad = self.dual(a)
                v, d = v + av, d + ad
            return v, d
        if isinstance(e, se.Mul):
            v, d = self.dual(e.args[0])
            for a in e.args[1:]:
                av, ad = self.dual(a)
                v, d = v * av, v * ad + d * av
            return v, d
        if isinstance(e, se.Pow):
            base, ex = e.args
            bv, bd = self.dual(base)
            if isinstance(ex, se.Integer):
                k = int(ex)
                if k < 0 and (bv == 0 if self.exact else bv.contains(0)):
                    if self.exact:
                        raise NotEvaluable("division by zero")
                    raise Inaccurate
                v = bv**k
                d = k * bv ** (k - 1) * bd if k != 0 else self._zero()
                return v, d
            if self.exact:
                raise NotRational
            xv, xd = self.dual(ex)
            if isinstance(ex, se.Rational) and int(ex.get_num_den()[1]) == 2:
                root = _check(bv.sqrt())
                v = root ** int(ex.get_num_den()[0])
                d = xv * v / bv * bd if bd != 0 else arb(0)
                return _check(v), _check(d) if bd != 0 else d
            if not bv > 0:
                raise Inaccurate
            v = (xv * bv.log()).exp()
            d = v * (xd * bv.log() + xv * bd / bv)
            return _check(v), _check(d)
        if self.exact:
            raise NotRational
        if isinstance(e, se.Abs):
            av, ad = self.dual(e.args[0])
            if av > 0:
                return av, ad
            if av < 0:
                return -av, -ad
            if ad == 0 and av == 0:
                return av, ad
            raise Inaccurate
        if isinstance(e, se.atan2):
            (yv, yd), (xv, xd) = self.dual(e.args[0]), self.dual(e.args[1])
            if (xv * xv + yv * yv).contains(0):
                raise Inaccurate
            return _check(arb.atan2(yv, xv)), _check((xv * yd - yv * xd) / (xv * xv + yv * yv))
        func = type(e)
        fn = _BALL_FUNCTIONS.get(func)
        if fn is None or len(e.args) != 1:
            raise NotEvaluable(f"cannot evaluate {func.__name__}")
        av, ad = self.dual(e.args[0])
        v = _check(fn(av))
        d = _check(_deriv(func, av) * ad) if ad != 0 else arb(0)
        return v, d


class SymbolicEvaluator:
    r"""Evaluate symengine expressions at an exact point with exact symengine numbers.

    Like :class:`Evaluator` (values and directional derivatives, forward mode),
    but the numbers are symengine's exact constants, expanded after every
    operation: at points such as $\theta = \pi/2$ symengine evaluates
    ``cos(pi/2)`` to ``0`` and ``sqrt(3)**2`` to ``3``, so values that are
    rational or algebraic come out in canonical form.  A value longer than
    ``max_chars`` characters raises ``NotRational`` (the exact path gives up).
    """

    def __init__(
        self,
        env: Mapping[se.Basic, se.Basic],
        direction: Mapping | None = None,
        max_chars: int = 2_000,
    ) -> None:
        self.env = env
        self.direction = direction or {}
        self.max_chars = max_chars
        self._memo: dict[se.Basic, tuple[se.Basic, se.Basic]] = {}

    def dual(self, e: se.Basic) -> tuple[se.Basic, se.Basic]:
        hit = self._memo.get(e)
        if hit is None:
            hit = self._dual(e)
            self._memo[e] = hit
        return hit

    def value(self, e: se.Basic) -> se.Basic:
        return self.dual(e)[0]

    def _small(self, v: se.Basic) -> se.Basic:
        v = se.expand(v)
        if len(str(v)) > self.max_chars:
            raise NotRational
        return v

    def _dual(self, e: se.Basic) -> tuple[se.Basic, se.Basic]:
        zero = se.Integer(0)
        if e.is_Symbol:
            if e not in self.env:
                raise NotEvaluable(f"no value for {e}")
            return self.env[e], self.direction.get(e, zero)
        if not e.free_symbols:
            if isinstance(e, _COMPLEX):
                raise NotEvaluable(f"complex value {e}")
            return e, zero
        if isinstance(e, se.Add):
            parts = [self.dual(a) for a in e.args]
            return (
                self._small(se.Add(*[v for v, _ in parts])),
                self._small(se.Add(*[d for _, d in parts])),
            )
        if isinstance(e, se.Mul):
            v, d = self.dual(e.args[0])
            for a in e.args[1:]:
                av, ad = self.dual(a)
                v, d = self._small(v * av), self._small(v * ad + d * av)
            return v, d
        if isinstance(e, se.Pow):
            base, ex = e.args
            bv, bd = self.dual(base)
            if ex.free_symbols:
                raise NotRational
            if bv == 0 and (ex.is_Number and ex < 0):
                raise NotEvaluable("division by zero")
            v = self._small(bv**ex)
            d = self._small(ex * bv ** (ex - 1) * bd) if bd != 0 else zero
            return v, d
        args = [self.dual(a) for a in e.args]
        x = [se.Symbol(f"_a{i}") for i in range(len(args))]
        f = type(e)(*x)
        v = self._small(f.subs(dict(zip(x, [a for a, _ in args], strict=True))))
        d = zero
        for xi, (_, ad) in zip(x, args, strict=True):
            if ad != 0:
                df = f.diff(xi).subs(dict(zip(x, [a for a, _ in args], strict=True)))
                d = d + df * ad
        return v, self._small(d)


def _se(e: object) -> se.Basic:
    if isinstance(e, fmpq):
        return se.Rational(int(e.p), int(e.q))
    if isinstance(e, float):
        return se.RealDouble(e)
    return se.S(e)


def exact_value(e: object) -> fmpq | None:
    """The exact rational value of a constant expression, or ``None`` if it is not rational.

    Decimals are read as the rationals they denote.
    """
    if isinstance(e, fmpq):
        return e
    if isinstance(e, int):
        return fmpq(e)
    try:
        return Evaluator({}, exact=True).value(_se(e))  # type: ignore[return-value]
    except (NotRational, NotEvaluable):
        return None


@contextmanager
def _precision(prec: int) -> Iterator[None]:
    """Run arb arithmetic at ``prec`` bits."""
    old = flint.ctx.prec
    flint.ctx.prec = prec
    try:
        yield
    finally:
        flint.ctx.prec = old


def ball(e: object, prec: int = START_PRECISION_BITS) -> arb:
    """A certified enclosure (``arb``) of a real constant expression at ``prec`` bits.

    Raises
    ------
    NotEvaluable
        For a value that is complex, undefined, or uses a function outside the grammar.
    """
    if isinstance(e, arb):
        return e
    old = flint.ctx.prec
    flint.ctx.prec = prec
    try:
        q = exact_value(e)
        if q is not None:
            return arb(q)
        try:
            return Evaluator({}, exact=False).value(_se(e))  # type: ignore[return-value]
        except Inaccurate:
            return arb("nan")
    finally:
        flint.ctx.prec = old


def to_double(e: object) -> float:
    """The double nearest to a real constant expression (from a certified 64-bit ball).

    Raises
    ------
    NotEvaluable
        If the value is complex, undefined, or cannot be enclosed.
    """
    b = ball(e, 64)
    if not b.is_finite():
        b = ball(e, 256)
    if not b.is_finite():
        raise NotEvaluable(f"cannot evaluate {e}")
    return float(b.mid())


# --- vectors --------------------------------------------------------------------------------

Key = object


class Vector:
    """A vector whose entries are computed on demand; sparse (a mapping key → value).

    Subclasses give :meth:`rational` (all entries as ``fmpq`` or ``None``),
    :meth:`balls` (entries at a precision) and :meth:`symbolic` (exact sympy
    entries, or ``None`` when not available within a budget).
    """

    def rational(self) -> dict[Key, fmpq] | None:
        raise NotImplementedError

    def balls(self, prec: int) -> dict[Key, arb]:
        raise NotImplementedError

    def symbolic(self) -> dict[Key, sp.Expr] | None:
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
            out[k] = exact_decimals(sp.S(v) if not isinstance(v, fmpq) else sp.Rational(
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
        floor = None
        while True:
            self.precision_reached = max(self.precision_reached, prec)
            balls = [r.balls(prec) for r in rows]
            if not balls[-1]:
                return Decision.DEPENDENT  # every entry is an exact 0
            with _precision(prec):
                gram = _gram_det(balls)
            if gram is not None and gram > 0:
                return Decision.INDEPENDENT
            if self.probabilistic:
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

    Each column (coordinate) is first divided by the largest magnitude in it
    and then each row by its norm: neither scaling changes the rank (the
    enclosures contain the matrix scaled by the midpoints of the factors), and
    together they make the decision independent of the units of the
    coordinates and of the size of the fields.
    """
    scale: dict[Key, arb] = {}
    for r in rows:
        for k, x in r.items():
            up = x.abs_upper()
            if k not in scale or up > scale[k]:
                scale[k] = up
    inv = {k: 1 / arb(v) for k, v in scale.items() if arb(v) > 0}
    rows = [{k: x * inv[k] for k, x in r.items() if k in inv} for r in rows]
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

    def __init__(self, rel_tol: float = 1e-9) -> None:
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


def numeric_rank(rows: Sequence[Sequence[float]], rel_tol: float = 1e-9) -> int:
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
