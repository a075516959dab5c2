r"""Evaluation of constants: exact rationals, certified arb balls, exact symengine numbers.

The numbers under every decision of :mod:`nilpotent.core.decide.spans`:

* :func:`exact_value`: the exact rational value of a constant (decimals read
  as the rationals they denote, :func:`exact_decimals`), or ``None``;
* :func:`ball`: a certified enclosure (python-flint ``arb``) at a precision;
* :class:`Evaluator`: values and directional derivatives (forward mode) of
  symengine expressions at a point, in exact rationals or in balls;
* :class:`SymbolicEvaluator`: the same with symengine's exact numbers
  (``cos(pi/2)`` is ``0``), within a size budget.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from fractions import Fraction
from typing import Any, TypeAlias

import flint
import symengine as se
from flint import arb, fmpq

from nilpotent.core.model.expressions import exact_decimals

#: A value of :class:`Evaluator`: an exact ``fmpq`` (exact mode) or an ``arb`` ball.
#: python-flint's stubs do not describe arithmetic mixing the two, hence ``Any``.
Scalar: TypeAlias = Any

__all__ = [
    "FLOAT_RELATIVE_TOLERANCE",
    "START_PRECISION_BITS",
    "Evaluator",
    "Inaccurate",
    "NotEvaluable",
    "NotRational",
    "SymbolicEvaluator",
    "ball",
    "double_inverse",
    "exact_decimals",
    "exact_value",
    "to_double",
]

START_PRECISION_BITS = 64
"""Working precision of the first ball evaluation (bits)."""


class NotEvaluable(ValueError):
    """A constant expression cannot be evaluated (pole, complex value, unknown function)."""


class NotRational(Exception):
    """The value is not a rational number (exact rational arithmetic cannot carry it)."""


class Inaccurate(Exception):
    """A ball evaluation lost all accuracy (e.g. ``sqrt`` of a ball around 0)."""


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


def _outside_domain(func: type, v: arb) -> str | None:
    """Why ``func(v)`` is certainly not real (``v`` an enclosure), or ``None``.

    The real domains of the grammar's functions: ``asin``/``acos`` on ``[-1, 1]``,
    ``acosh`` on ``[1, ∞)``, ``atanh`` on ``(-1, 1)``, ``log`` on ``(0, ∞)``; outside
    them the principal value (sympy's, symengine's) is complex.
    """
    if func in (se.asin, se.acos) and (v > 1 or v < -1):
        return f"{func.__name__} of a number outside [-1, 1]"
    if func is se.acosh and v < 1:
        return "acosh of a number below 1"
    if func is se.atanh and (v >= 1 or v <= -1):
        return "atanh of a number outside (-1, 1)"
    if func is se.log and v < 0:
        return "log of a negative number"
    return None


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
        self._memo: dict[se.Basic, tuple[Scalar, Scalar]] = {}

    def _num(self, e: se.Basic) -> Scalar:
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

    def dual(self, e: se.Basic) -> tuple[Scalar, Scalar]:
        """Value and directional derivative of ``e``."""
        hit = self._memo.get(e)
        if hit is not None:
            return hit
        out = self._dual(e)
        self._memo[e] = out
        return out

    def value(self, e: se.Basic) -> Scalar:
        """Value of ``e``."""
        return self.dual(e)[0]

    def _zero(self) -> Scalar:
        return fmpq(0) if self.exact else arb(0)

    def _dual(self, e: se.Basic) -> tuple[Scalar, Scalar]:
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
            if bv < 0:
                # a non-integer power of a negative number is complex (principal branch,
                # as sympy and symengine read it): no real value, not a loss of accuracy
                raise NotEvaluable(f"complex value {e} (a non-integer power of a negative number)")
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
        why = _outside_domain(func, av)
        if why is not None:
            raise NotEvaluable(f"complex value {e} ({why})")
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

    @staticmethod
    def _real(e: se.Basic, v: se.Basic) -> se.Basic:
        """``v`` (the value of ``e``), refused when it holds the imaginary unit."""
        if v.has(se.I):
            raise NotEvaluable(f"complex value {e} = {v}")
        if v.has(se.zoo) or v.has(se.nan) or v.has(se.oo):
            raise NotEvaluable(f"undefined value {e} = {v}")
        return v

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
            if not isinstance(ex, se.Integer) and bv != 0 and _certainly_negative(bv):
                # symengine keeps (-8)**(1/3) as 2*(-1)**(1/3): complex, with no I
                raise NotEvaluable(
                    f"complex value {e} (a non-integer power of a negative number)")
            v = self._real(e, self._small(bv**ex))
            d = self._small(ex * bv ** (ex - 1) * bd) if bd != 0 else zero
            return v, d
        args = [self.dual(a) for a in e.args]
        if len(args) == 1 and type(e) in (se.asin, se.acos, se.acosh, se.atanh, se.log):
            why = _outside_domain(type(e), _enclosure(args[0][0]))
            if why is not None:
                raise NotEvaluable(f"complex value {e} ({why})")
        x = [se.Symbol(f"_a{i}") for i in range(len(args))]
        f = type(e)(*x)
        v = self._real(e, self._small(f.subs(dict(zip(x, [a for a, _ in args], strict=True)))))
        d = zero
        for xi, (_, ad) in zip(x, args, strict=True):
            if ad != 0:
                df = f.diff(xi).subs(dict(zip(x, [a for a, _ in args], strict=True)))
                d = d + df * ad
        return v, self._small(d)


def _enclosure(v: se.Basic) -> arb:
    """An enclosure of an exact constant (a NaN ball when it has none)."""
    try:
        return ball(v)
    except NotEvaluable:
        return arb("nan")


def _certainly_negative(v: se.Basic) -> bool:
    return bool(_enclosure(v) < 0)


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
def precision(prec: int) -> Iterator[None]:
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


FLOAT_RELATIVE_TOLERANCE = 1e-9
"""Relative size below which a floating-point *measurement* counts as 0 (see :func:`negligible`)."""


def negligible(value: float, scale: float, rel_tol: float = FLOAT_RELATIVE_TOLERANCE) -> bool:
    r"""Whether a floating-point value counts as 0 relative to the ``scale`` it was computed at.

    ``scale`` is the size of the terms whose sum the value is (the rounding error
    of a sum is proportional to it, never to an absolute unit): the test
    $|v| \le$ ``rel_tol`` $\cdot$ ``scale`` gives the same answer for a
    computation scaled by $10^{300}$ or $e^{-100}$.  A value with no scale
    (``scale <= 0``) is 0 only when it is exactly 0.
    """
    if value == 0.0:
        return True
    if not scale > 0.0:
        return False
    return abs(value) <= rel_tol * scale


def double_inverse(entries: list[list[object]], max_precision: int = 1024) -> list[list[float]]:
    r"""The inverse of a real matrix of exact constants, entrywise rounded to doubles.

    The matrix is enclosed in balls (:func:`ball`) and inverted with arb's
    Gaussian elimination with partial pivoting at rising precision, from
    :data:`START_PRECISION_BITS` up to ``max_precision`` bits, until every entry
    of the inverse is known to $2^{-60}$ relative to the largest term of its row
    of $AB$; the result is the midpoints (0 for a ball around 0, negligible
    there).  A residual check then requires
    $|(\tilde A \tilde B - I)_{jk}| \le 10^{-9}\,(|\tilde A|\,|\tilde B|)_{jk}$
    for the doubles $\tilde A$ and $\tilde B$ (scale-free: invariant under
    scaling the rows of $A$ and the columns of $B$), so that what the float
    computations use is an inverse of what they multiply.

    Raises
    ------
    ZeroDivisionError
        If the matrix is singular or its inverse cannot be enclosed within
        ``max_precision`` bits, or the doubles fail the residual check (the
        matrix is too ill-conditioned for double precision).
    """
    from flint import arb_mat

    n = len(entries)
    prec = START_PRECISION_BITS
    while True:
        with precision(prec):
            try:
                m = arb_mat([[ball(v, prec) for v in row] for row in entries])
                inv = m.inv()
            except ZeroDivisionError:
                inv = None
            if inv is not None and _tight_inverse(inv, m, n):
                out = [
                    [0.0 if inv[j, k].contains(0) else float(inv[j, k].mid()) for k in range(n)]
                    for j in range(n)
                ]
                break
        if prec >= max_precision:
            raise ZeroDivisionError(
                f"the matrix is singular or its inverse cannot be enclosed at {prec} bits"
            )
        prec *= 2
    b = [[to_double(v) for v in row] for row in entries]
    for j in range(n):
        for k in range(n):
            exact = 1.0 if j == k else 0.0
            got = sum(out[j][l] * b[l][k] for l in range(n))
            size = sum(abs(out[j][l] * b[l][k]) for l in range(n))
            if abs(got - exact) > FLOAT_RELATIVE_TOLERANCE * size:
                raise ZeroDivisionError(
                    "the matrix is too ill-conditioned for double precision (residual "
                    f"{abs(got - exact):.3g} at entry ({j}, {k}))"
                )
    return out


def _tight_inverse(inv: Any, m: Any, n: int) -> bool:
    r"""Whether each entry of the ball inverse is known to $2^{-60}$ of its row's scale.

    The scale of entry $(j, k)$ is the largest term $|A_{jk'}|\max_l|B_{k'l}|$ of
    row $j$ of $AB$, divided by $\max_l |B_{kl}|$: an entry that is 0 (a ball
    around 0) passes when it is negligible there, and the test does not depend
    on the units of the coordinates or the scale of the frame.
    """
    tiny = arb(2) ** -60
    bmax = [max((m[k, l].abs_upper() for l in range(n)), default=arb(0)) for k in range(n)]
    for j in range(n):
        row = max(
            (inv[j, k].abs_upper() * bmax[k] for k in range(n)), default=arb(0)
        )
        if not row > 0:
            return False
        for k in range(n):
            x = inv[j, k]
            if not x.is_finite() or not x.rad() * bmax[k] <= tiny * row:
                return False
    return True
