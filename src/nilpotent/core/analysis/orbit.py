r"""Bracket generation certified along an orbit (Nagano's theorem).

For analytic fields, the rank of the Lie algebra $\mathrm{Lie}(X_1, \dots,
X_m)$ at a point equals the dimension of the orbit through it, and the orbit
is an immersed submanifold (Nagano 1966; Jurdjevic, *Geometric Control
Theory*, ch. 2, Thm. 2.3 / Sussmann's orbit theorem).  So the rank is constant
along orbits: $p$ is bracket-generating as soon as some point $q$ reached from
$p$ by following the fields is.  At a singular point where the degree of
non-holonomy is far beyond any feasible bracket search (the car with $n$
trailers, Jean 1996), :func:`certify_by_orbit` proves the rank this way:

1. *Flow with a rigorous enclosure.*  Follow $X_i$ for a time $T$ (in steps
   of length $h$).  Each step starts from a box $B_0$ (the exact point at the
   first step, enclosed in arb balls) and finds an *a-priori box* $B$ with
   $B_0 + [0, h]\,X_i(B) \subseteq B$ (interval evaluation by python-flint's
   ``arb``), which proves that the solutions from $B_0$ exist on $[0, h]$ and
   stay in $B$.  The end point is then enclosed by the Taylor polynomial of
   order $k - 1$ at $B_0$ plus the Lagrange remainder $h^k c_k(B)$, the Taylor
   coefficients computed by Picard iteration on truncated power series
   (``arb_series``) and enclosing their values over the boxes.  A field whose
   components do not depend on the coordinates it moves (a translation,
   ``X2 = ∂θ0`` of the car) has an exact flow $p + T X_i(p)$, and its series
   terminate: the enclosure is then exact up to rounding.
2. *Analyticity along the path.*  Every field is checked to be analytic on
   every a-priori box (the grammar's functions are analytic where they are
   defined: ``log`` and fractional powers need a positive argument, ``tan`` a
   nonzero cosine, negative powers a nonzero base, ``atan2`` a box off its
   branch cut); an expression outside these rules refuses the certificate.
3. *Rank on the end box.*  The Hall words of an adapted frame (chosen at the
   midpoint of the end box) are evaluated over the whole end box by
   forward-mode interval arithmetic; if the ball enclosing the determinant
   excludes 0, the brackets span $\mathbb{R}^n$ at *every* point of the box,
   hence at the end point $q$, hence at $p$.

Nothing here can certify a point that is not bracket-generating: there the
orbit has dimension $< n$, every bracket is tangent to it, so every frame
determinant vanishes at the true end point, which is in the box, and the ball
cannot exclude 0 (the offhooked trailer on its invariant hypersurface is a
test).  Bracket convention $[X,Y] = DY\cdot X - DX\cdot Y$.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction

import flint
import symengine as se
import sympy as sp
from flint import arb, arb_mat, arb_series

from nilpotent.core.decide.evaluation import Evaluator, Inaccurate, NotEvaluable, ball, precision
from nilpotent.core.lie.brackets import Word, format_word, se_coordinates, to_symengine
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ComputationLimitError
from nilpotent.strict_json import json_object

__all__ = ["ORBIT_TIME_BUDGET", "OrbitCertificate", "certify_by_orbit"]

ORBIT_TIME_BUDGET = 20.0
"""Seconds :func:`certify_by_orbit` may spend before giving up (nothing is then concluded)."""

TAYLOR_ORDER = 16
"""Order $k$ of the Taylor enclosure of one flow step (remainder $h^k c_k(B)$)."""

STEP = Fraction(1, 8)
"""Longest time step of the validated flow."""

TIMES = (Fraction(1, 2), Fraction(-1, 2), Fraction(1), Fraction(-1), Fraction(1, 4),
         Fraction(-1, 4))
"""Flow times tried, for each field (then pairs of flows)."""

PRECISIONS = (128, 256)
"""Working precisions (bits) of the enclosures."""


@dataclass(frozen=True)
class OrbitCertificate:
    """A proof that a point is bracket-generating, by a point of its orbit.

    Attributes
    ----------
    flows:
        ``(i, T)``: follow $X_i$ (1-based) for the time $T$, in order.
    exact:
        Whether every flow was an exact translation (no enclosure error).
    box:
        The end box, per coordinate ``(lower, upper)`` as decimal strings
        (outward-rounded bounds), containing the end point $q$.
    frame:
        The Hall words whose determinant is certified nonzero on the box.
    determinant:
        The ball (``arb``, as text) enclosing that determinant over the box.
    precision_bits:
        The working precision used.
    """

    flows: tuple[tuple[int, Fraction], ...]
    exact: bool
    box: tuple[tuple[str, str], ...]
    frame: tuple[Word, ...]
    determinant: str
    precision_bits: int

    def statement(self) -> str:
        """One sentence saying what was proved and how."""
        path = ", then ".join(f"the flow of X{i} for time {_fmt(t)}" for i, t in self.flows)
        how = "exactly (a translation)" if self.exact else "with a validated enclosure"
        return (
            f"proved by the orbit theorem (Nagano, analytic fields): {path}, followed {how}, "
            f"ends in a box where det({', '.join(format_word(w) for w in self.frame)}) "
            f"is in {self.determinant}, never 0; the Lie algebra has rank n on that box, "
            "hence along the orbit, hence at the point"
        )

    def to_json(self, names: Sequence[str]) -> dict[str, object]:
        """The ``certified_by`` object of the analysis JSON."""
        first = self.flows[0] if len(self.flows) == 1 else None
        out: dict[str, object] = {"method": "orbit"}
        if first is not None:
            out["flow"] = f"X{first[0]}"
            out["time"] = _fmt(first[1])
        out.update(
            {
                "flows": [{"field": f"X{i}", "time": _fmt(t)} for i, t in self.flows],
                "exact_flow": self.exact,
                "box": {n: list(b) for n, b in zip(names, self.box, strict=True)},
                "frame": [format_word(w) for w in self.frame],
                "determinant": self.determinant,
                "precision_bits": self.precision_bits,
                "statement": self.statement(),
            }
        )
        return json_object(out)


def _fmt(t: Fraction) -> str:
    return str(t.numerator) if t.denominator == 1 else f"{t.numerator}/{t.denominator}"


class _Refused(Exception):
    """The enclosure could not be made (not analytic on a box, no a-priori box, blow-up)."""


# --- analyticity on a box -----------------------------------------------------------------


# analytic on the whole real line; exp(u) is E**u in symengine (the Pow branch below):
# se.exp is a function, not a class, and isinstance() refused it (a TypeError, found by
# tests/test_polynomial_fields.py's random systems)
_ENTIRE = (se.sin, se.cos, se.atan, se.sinh, se.cosh, se.tanh)


def _check_analytic(e: se.Basic, ev: Evaluator, seen: set) -> None:
    """Raise :class:`_Refused` unless ``e`` is analytic on the box of ``ev``."""
    if e in seen or not e.free_symbols:
        return
    seen.add(e)
    if e.is_Symbol:
        return
    for a in e.args:
        _check_analytic(a, ev, seen)
    if isinstance(e, se.Add | se.Mul):
        return
    try:
        if isinstance(e, se.Pow):
            base, ex = e.args
            bv = ev.value(base)
            if isinstance(ex, se.Integer):
                if int(ex) < 0 and bv.contains(0):
                    raise _Refused
                return
            if ex.free_symbols or not bv > 0:
                if ex.free_symbols and bv > 0:
                    return
                raise _Refused
            return
        if isinstance(e, _ENTIRE):
            return
        if isinstance(e, se.tan):
            if ev.value(se.cos(e.args[0])).contains(0):
                raise _Refused
            return
        if isinstance(e, se.log):
            if not ev.value(e.args[0]) > 0:
                raise _Refused
            return
        if isinstance(e, se.atan2):
            y, x = (ev.value(a) for a in e.args)
            if not (x > 0 or y > 0 or y < 0):
                raise _Refused
            return
    except (Inaccurate, NotEvaluable, ZeroDivisionError):
        raise _Refused from None
    raise _Refused


# --- power series of expressions ------------------------------------------------------------


def _series_of(e: se.Basic, env: dict, k: int, memo: dict) -> arb_series:
    """The truncated power series (length ``k + 1``) of ``e`` along series-valued coordinates."""
    hit = memo.get(e)
    if hit is not None:
        return hit
    out = _series(e, env, k, memo)
    memo[e] = out
    return out


def _const(v: arb, k: int) -> arb_series:
    return arb_series([v], prec=k + 1)


def _series(e: se.Basic, env: dict, k: int, memo: dict) -> arb_series:
    if e.is_Symbol:
        return env[e]
    if not e.free_symbols:
        v = ball(e, flint.ctx.prec)
        if not v.is_finite():
            raise _Refused
        return _const(v, k)
    args = [_series_of(a, env, k, memo) for a in e.args]
    if isinstance(e, se.Add):
        out = args[0]
        for a in args[1:]:
            out = out + a
        return out
    if isinstance(e, se.Mul):
        out = args[0]
        for a in args[1:]:
            out = out * a
        return out
    if isinstance(e, se.Pow):
        ex = e.args[1]
        b = args[0]
        if isinstance(ex, se.Integer):
            j = int(ex)
            if j < 0:
                b, j = b.inv(), -j
            out = _const(arb(1), k)
            for _ in range(j):
                out = out * b
            return out
        if isinstance(ex, se.Rational) and ex == se.Rational(1, 2):
            return b.sqrt()
        return (args[1] * b.log()).exp()
    fn = _SERIES_FUNCTIONS.get(type(e))
    if fn is not None:
        return fn(*args)
    raise _Refused


def _atan2(y: arb_series, x: arb_series) -> arb_series:
    y0, x0 = y.coeffs()[0], x.coeffs()[0]
    if x0 > 0:
        return (y * x.inv()).atan()
    if y0 > 0:
        return _const(arb.pi() / 2, y.prec - 1) - (x * y.inv()).atan()
    if y0 < 0:
        return _const(-arb.pi() / 2, y.prec - 1) - (x * y.inv()).atan()
    raise _Refused


def _half(a: arb_series, b: arb_series) -> arb_series:
    return (a + b) * arb(0.5)


_SERIES_FUNCTIONS: dict[type, Callable[..., arb_series]] = {
    se.sin: arb_series.sin,
    se.cos: arb_series.cos,
    se.tan: arb_series.tan,
    se.exp: arb_series.exp,
    se.log: arb_series.log,
    se.atan: arb_series.atan,
    se.sinh: lambda a: _half(a.exp(), -((-a).exp())),
    se.cosh: lambda a: _half(a.exp(), (-a).exp()),
    se.tanh: lambda a: (a * 2).exp().__sub__(1) * ((a * 2).exp() + 1).inv(),
    se.atan2: _atan2,
}


def _taylor(
    field: Sequence[se.Basic], coords: Sequence[se.Symbol], start: Sequence[arb], k: int
) -> list[list[arb]]:
    """Taylor coefficients ``c_0..c_k`` of the flow from (every point of) the box ``start``."""
    xs = [_const(v, k) for v in start]
    for _ in range(k + 1):
        env = dict(zip(coords, xs, strict=True))
        memo: dict = {}
        new = []
        for x0, f in zip(start, field, strict=True):
            if f == 0:
                new.append(_const(x0, k))
                continue
            s = _series_of(f, env, k, memo).integral()
            c = list(s.coeffs()[: k + 1])
            c += [arb(0)] * (k + 1 - len(c))
            c[0] = x0
            new.append(arb_series(c, prec=k + 1))
        xs = new
    out = []
    for x in xs:
        c = list(x.coeffs()[: k + 1])
        c += [arb(0)] * (k + 1 - len(c))
        if not all(v.is_finite() for v in c):
            raise _Refused
        out.append(c)
    return out


def _values(field: Sequence[se.Basic], env: dict) -> list[arb]:
    ev = Evaluator(env, exact=False)
    try:
        out = [ev.value(f) if f != 0 else arb(0) for f in field]
    except (Inaccurate, NotEvaluable, ZeroDivisionError):
        raise _Refused from None
    if not all(v.is_finite() for v in out):
        raise _Refused
    return out


def _a_priori(
    fields: Sequence[Sequence[se.Basic]], i: int, coords, start: Sequence[arb], h: arb
) -> list[arb]:
    """A box ``B`` with ``start + [0, h]·X_i(B) ⊆ B`` on which every field is analytic."""
    field = fields[i]
    span = arb(0).union(h)  # [0, h] or [h, 0]
    vel = _values(field, dict(zip(coords, start, strict=True)))
    box = [s + span * v for s, v in zip(start, vel, strict=True)]
    for _ in range(12):
        widened = [b + arb(0, 2 * b.rad() + arb(2) ** (-flint.ctx.prec // 2)) for b in box]
        env = dict(zip(coords, widened, strict=True))
        vel = _values(field, env)
        image = [s + span * v for s, v in zip(start, vel, strict=True)]
        if all(w.contains(b) for w, b in zip(widened, image, strict=True)):
            ev = Evaluator(env, exact=False)
            seen: set = set()
            for f in fields:
                for c in f:
                    _check_analytic(c, ev, seen)
            return widened
        box = [w.union(b) for w, b in zip(widened, image, strict=True)]
    raise _Refused


def _flow(
    fields: Sequence[Sequence[se.Basic]], coords, start: Sequence[arb], i: int, T: Fraction
) -> list[arb]:
    """An enclosure of the end points of the flow of ``X_i`` for time ``T`` from the box."""
    steps = max(1, -(-abs(T) // STEP))
    h = arb(fmpq_of(T / steps))
    box = list(start)
    for _ in range(int(steps)):
        big = _a_priori(fields, i, coords, box, h)
        near = _taylor(fields[i], coords, box, TAYLOR_ORDER - 1)
        far = _taylor(fields[i], coords, big, TAYLOR_ORDER)
        out = []
        for cn, cf in zip(near, far, strict=True):
            v = arb(0)
            for c in reversed(cn):  # Horner: sum_{j<k} c_j h^j
                v = v * h + c
            v = v + cf[TAYLOR_ORDER] * h**TAYLOR_ORDER
            out.append(v)
        if not all(v.is_finite() for v in out):
            raise _Refused
        box = [v.intersection(b) for v, b in zip(out, big, strict=True)]
    return box


def fmpq_of(t: Fraction) -> flint.fmpq:
    return flint.fmpq(t.numerator, t.denominator)


def _is_translation(field: Sequence[se.Basic], coords: Sequence[se.Symbol]) -> bool:
    moving = {x for x, c in zip(coords, field, strict=True) if c != 0}
    return all(not (c.free_symbols & moving) for c in field)


# --- the certificate -----------------------------------------------------------------------


def certify_by_orbit(
    sys: ControlSystem,
    point: Sequence[sp.Expr],
    *,
    time_budget: float = ORBIT_TIME_BUDGET,
) -> OrbitCertificate | None:
    """Prove that ``sys`` is bracket-generating at ``point`` through its orbit, or None.

    Tries the flows of each field for the times :data:`TIMES`, then pairs of
    flows, at the precisions :data:`PRECISIONS`, until a frame determinant is
    certified nonzero on the enclosure of the end point (module docstring), or
    ``time_budget`` seconds have passed.  ``None`` concludes nothing.

    Parameters
    ----------
    sys:
        The system (parameters substituted); its fields must be analytic on
        the path (checked on every box; else None).
    point:
        The point $p$ (exact sympy numbers aligned with the coordinates).

    Returns
    -------
    OrbitCertificate or None
        A certificate that the Lie algebra has rank $n$ at ``point``.
    """
    from nilpotent.core.analysis.growth import generic_growth_at
    from nilpotent.core.lie.word_values import Undefined, WordValues

    started = time.monotonic()
    coords = se_coordinates(sys)
    fields = [[to_symengine(c) for c in f] for f in sys.specialized_fields]
    m = sys.m
    plans: list[tuple[tuple[int, Fraction], ...]] = [
        ((i, t),) for t in TIMES for i in range(m)
    ]
    plans += [
        ((j, t1), (i, t2))
        for t1 in TIMES[:2]
        for t2 in TIMES[:4]
        for j in range(m)
        for i in range(m)
        if i != j
    ]
    for prec in PRECISIONS:
        with precision(prec):
            start = [ball(to_symengine(v), prec) for v in point]
            if not all(v.is_finite() for v in start):
                return None
            for plan in plans:
                if time.monotonic() - started > time_budget:
                    return None
                try:
                    box = list(start)
                    for i, t in plan:
                        box = _flow(fields, coords, box, i, t)
                except (_Refused, Inaccurate, NotEvaluable, ZeroDivisionError):
                    continue
                mid = [sp.Rational(str(Fraction(*_mid_ratio(b)))) for b in box]
                try:
                    _, frame = generic_growth_at(sys, mid)
                except (Undefined, Inaccurate, NotEvaluable, ZeroDivisionError):
                    continue
                except ComputationLimitError:
                    return None  # the frame's fields are too large to build: nothing proved
                if len(frame) != sys.n:
                    continue
                try:
                    at = WordValues(sys, mid, symbolic=False, box=box)
                    cols = [at.balls(w, prec) for w in frame]
                except (Undefined, Inaccurate, NotEvaluable, ZeroDivisionError):
                    continue
                except ComputationLimitError:
                    return None
                n = sys.n
                mat = arb_mat(n, n, [cols[c][r] for r in range(n) for c in range(n)])
                det = mat.det()
                if det.is_finite() and not det.contains(0):
                    return OrbitCertificate(
                        flows=tuple((i + 1, t) for i, t in plan),
                        exact=all(_is_translation(fields[i], coords) for i, _ in plan),
                        box=tuple((_bound(b, lower=True), _bound(b, lower=False)) for b in box),
                        frame=tuple(frame),
                        determinant=det.str(5, radius=True),
                        precision_bits=prec,
                    )
    return None


def _mid_ratio(b: arb) -> tuple[int, int]:
    man, ex = b.mid().man_exp()
    man, ex = int(man), int(ex)
    return (man * 2**ex, 1) if ex >= 0 else (man, 2 ** (-ex))


def _bound(b: arb, lower: bool) -> str:
    """A bound of the ball as the shortest decimal of a double, rounded outward."""
    exact = Fraction(*_mid_ratio(b.lower() if lower else b.upper()))
    x = float(exact)
    if lower and Fraction(x) > exact:
        x = math.nextafter(x, -math.inf)
    elif not lower and Fraction(x) < exact:
        x = math.nextafter(x, math.inf)
    return repr(x)
