r"""Truncated polynomials with exact coefficients, and weighted Taylor jets at a point.

This is the arithmetic under privileged coordinates and the nilpotent
approximation (the mathematics page, §4–5).  A :class:`Poly` is a sparse polynomial in
``nvars`` variables whose coefficients are exact symengine numbers
(``1/2``, ``sqrt(3)/2``, ``cos(1/5)``; floats only where the input has floats).

Weighted degree
    With weights $w = (w_1, \dots, w_n)$ the weighted degree of the monomial
    $y^\alpha$ is $w(\alpha) = \sum_k w_k \alpha_k$; the ordinary degree is the
    case $w = (1, \dots, 1)$.  "Truncated at degree $D$" means: every term of
    weighted degree $> D$ is dropped, every term of degree $\le D$ is exact.

Weighted Taylor jets (:func:`weighted_jets`)
    The jet of an expression $f(x)$ along a polynomial map $x = \varphi(y)$
    is computed by substituting $y_k \to t^{w_k} y_k$ and expanding in the
    single variable $t$ up to $t^D$ with symengine's univariate ``series``:
    the coefficient of $t^d$ is exactly the weighted-degree-$d$ part of
    $f(\varphi(y))$.  Nothing of degree $> D$ is ever expanded.

Zero tests
    Coefficients are expanded and compared with 0 structurally.  Where a
    coefficient mixes transcendental numbers (``cos(1/5)**2 + sin(1/5)**2 - 1``)
    the structural test can miss a zero; :class:`ZeroTest` then asks the rank
    engine (:func:`nilpotent.core.decide.spans.is_zero`: exact or certified) and counts
    the zeros it could not prove, so that results can say they were not decided
    exactly.
"""

from __future__ import annotations

import functools
import operator
from collections.abc import Iterable, Mapping, Sequence
from typing import cast

import symengine as se
import sympy as sp

from nilpotent.core.decide.spans import is_zero, negligible, to_double
from nilpotent.errors import PointError

Monomial = tuple[int, ...]

_CANONICAL_ORDER = functools.cmp_to_key(sp.Basic.compare)
"""The order in which sympy's ``Add`` and ``Mul`` keep their arguments."""

__all__ = [
    "Monomial",
    "Poly",
    "ZeroTest",
    "bracket",
    "lie_derivative",
    "to_symengine",
    "weighted_degree",
    "weighted_jets",
]


def to_symengine(expr: object) -> se.Basic:
    """Convert a sympy expression (or a number) to symengine."""
    return se.S(expr)


def weighted_degree(mono: Monomial, weights: Sequence[int]) -> int:
    r"""The weighted degree $\sum_k w_k \alpha_k$ of the monomial $y^\alpha$."""
    return sum(map(operator.mul, mono, weights))


def _clean(c: se.Basic) -> se.Basic:
    if c.is_Number:
        return c
    return se.expand(c)


class ZeroTest:
    r"""Decide whether an exact coefficient is zero.

    Structural first (symengine's canonical form after expansion); where that
    leaves a constant that is not a number, :func:`nilpotent.core.decide.spans.is_zero`
    decides (exact for rational and algebraic values, a certified ball proves a
    nonzero); a constant that stays within a ball around 0 at
    :data:`~nilpotent.core.decide.spans.MAX_PRECISION_BITS` bits without an exact proof
    counts as 0 and as a numerical decision.  A float (a value computed in
    floating point) is zero when it is negligible relative to its ``scale``,
    the size of the terms it was summed from
    (:func:`nilpotent.core.decide.spans.negligible`, :attr:`Poly.mags`): no absolute
    threshold, so the decisions do not change when a system is scaled.  A float
    without a scale is zero only when it is exactly 0.  ``unit`` (default 0) is a
    least scale, for floats in units where 1 is natural: the adapted coordinates
    $z$ of :mod:`nilpotent.core.coordinates.privileged`, where the frame is the unit
    ($Y_k(p) = \partial_{z_k}$) whatever the scale of the system, and where a
    coefficient computed from values at the rounded point can carry an error
    its tracked magnitude does not see.
    :attr:`numeric_decisions` counts the coefficients decided zero numerically.
    """

    def __init__(self, digits: int = 50, unit: float = 0.0) -> None:
        self.digits = digits
        self.unit = unit
        self.numeric_decisions = 0

    def __call__(self, c: se.Basic, scale: float | None = None) -> bool:
        c = _clean(se.S(c))
        if c == 0:
            return True
        if isinstance(c, se.RealDouble | se.ComplexDouble):
            value = abs(complex(c))
            if negligible(value, max(value if scale is None else scale, self.unit)):
                self.numeric_decisions += 1
                return True
            return False
        if c.is_Number:
            return False
        if c.free_symbols:
            return False
        # the one rank engine: exact (rational, algebraic) or a certified nonzero ball
        verdict = is_zero(c)
        if verdict is None:  # 0 to 1024 bits but not provably: a numerical decision
            self.numeric_decisions += 1
            return True
        return verdict


def _size(c: se.Basic) -> float:
    """$|c|$ as a double (the magnitude of a coefficient nobody tracked)."""
    try:
        return abs(complex(c))
    except (TypeError, RuntimeError):
        return abs(to_double(c))


class Poly:
    r"""A sparse polynomial $\sum_\alpha c_\alpha y^\alpha$ with exact coefficients.

    ``terms`` maps exponent tuples to nonzero symengine coefficients.  A
    :class:`Poly` is never mutated after construction; every operation returns
    a new one.  Operations that multiply accept ``weights`` and ``degree`` and
    then drop the terms of weighted degree above ``degree`` (``degree=None``:
    no truncation).
    """

    __slots__ = ("mags", "nvars", "terms")

    def __init__(
        self,
        nvars: int,
        terms: Mapping[Monomial, se.Basic] | None = None,
        mags: Mapping[Monomial, float] | None = None,
    ) -> None:
        self.nvars = nvars
        clean: dict[Monomial, se.Basic] = {}
        if terms:
            for mono, c in terms.items():
                c = _clean(c)
                if c != 0:
                    clean[mono] = c
        self.terms = clean
        self.mags: dict[Monomial, float] | None = (
            None if mags is None else {m: mags[m] if m in mags else _size(c)
                                       for m, c in clean.items()}
        )
        """Magnitudes of floating-point coefficients (``None``: not tracked).

        ``mags[m]`` bounds the sizes of the terms whose sum ``terms[m]`` is, as
        computed: the scale of its rounding error, what the zero test compares it
        with (:class:`ZeroTest`).  Tracked once :meth:`tracked` starts it (floats
        from :func:`weighted_jets`, fields read back from floats); every operation
        with a tracked operand tracks its result (an untracked operand counts
        $|c|$), and exact computations never pay for it.
        """

    def tracked(self) -> Poly:
        """This polynomial with its magnitudes tracked (from $|c|$ where not yet)."""
        if self.mags is not None:
            return self
        return Poly(self.nvars, self.terms, {})

    def magnitude(self, mono: Monomial) -> float | None:
        """The tracked magnitude of the coefficient of ``mono`` (``None``: not tracked)."""
        if self.mags is None:
            return None
        return self.mags.get(mono, 0.0)

    def _mag(self, mono: Monomial) -> float:
        if self.mags is not None and mono in self.mags:
            return self.mags[mono]
        c = self.terms.get(mono)
        return 0.0 if c is None else _size(c)

    def _keep(self, terms: Mapping[Monomial, se.Basic]) -> Poly:
        """A sub-polynomial of this one (its magnitudes kept)."""
        return Poly(self.nvars, terms, self.mags)

    # --- constructors -------------------------------------------------------
    @classmethod
    def constant(cls, nvars: int, c: object) -> Poly:
        return cls(nvars, {(0,) * nvars: se.S(c)})

    @classmethod
    def variable(cls, nvars: int, k: int) -> Poly:
        mono = [0] * nvars
        mono[k] = 1
        return cls(nvars, {tuple(mono): se.Integer(1)})

    @classmethod
    def from_expr(
        cls, expr: se.Basic, variables: Sequence[se.Symbol], ignore: Iterable[se.Symbol] = ()
    ) -> Poly:
        """Read an expression polynomial in ``variables`` (exponents of ``ignore`` dropped)."""
        n = len(variables)
        index = {v: k for k, v in enumerate(variables)}
        skip = set(ignore)
        expr = se.expand(se.S(expr))
        terms: dict[Monomial, se.Basic] = {}
        if expr == 0:
            return cls(n)
        parts = expr.args if isinstance(expr, se.Add) else (expr,)
        for term in parts:
            exps = [0] * n
            coeff: list[se.Basic] = []
            factors = term.args if isinstance(term, se.Mul) else (term,)
            for f in factors:
                if f in skip:
                    continue
                if f in index:
                    exps[index[f]] += 1
                    continue
                if isinstance(f, se.Pow):
                    base, ex = f.args
                    if base in skip:
                        continue
                    if base in index and ex.is_Integer and int(ex) > 0:
                        exps[index[base]] += int(ex)
                        continue
                if f.free_symbols & set(index):
                    raise ArithmeticError(f"not a polynomial in {list(variables)}: factor {f}")
                coeff.append(f)
            key = tuple(exps)
            c = se.Mul(*coeff) if len(coeff) > 1 else (coeff[0] if coeff else se.Integer(1))
            terms[key] = terms[key] + c if key in terms else c
        return cls(n, terms)

    # --- inspection ---------------------------------------------------------
    def is_zero(self) -> bool:
        return not self.terms

    def __bool__(self) -> bool:
        return bool(self.terms)

    def __repr__(self) -> str:
        return f"Poly({self.nvars}, {self.terms!r})"

    def value_at_zero(self) -> se.Basic:
        return self.terms.get((0,) * self.nvars, se.Integer(0))

    def degrees(self, weights: Sequence[int]) -> set[int]:
        """The set of weighted degrees of the terms."""
        return {weighted_degree(m, weights) for m in self.terms}

    def is_zero_at(self, mono: Monomial, zero: ZeroTest) -> bool:
        """Whether the coefficient of ``mono`` is zero (``zero`` at its tracked magnitude)."""
        c = self.terms.get(mono)
        return c is None or zero(c, self.magnitude(mono))

    def order(self, weights: Sequence[int], zero: ZeroTest | None = None) -> int | None:
        """Least weighted degree of a nonzero term (``None`` for the zero polynomial)."""
        degs = [
            weighted_degree(m, weights)
            for m, c in self.terms.items()
            if zero is None or not zero(c, self.magnitude(m))
        ]
        return min(degs) if degs else None

    def homogeneous_part(self, weights: Sequence[int], d: int) -> Poly:
        return self._keep(
            {m: c for m, c in self.terms.items() if weighted_degree(m, weights) == d}
        )

    def truncate(self, weights: Sequence[int], degree: int | None) -> Poly:
        if degree is None:
            return self
        return self._keep(
            {m: c for m, c in self.terms.items() if weighted_degree(m, weights) <= degree},
        )

    def drop_zeros(self, zero: ZeroTest) -> Poly:
        return self._keep(
            {m: c for m, c in self.terms.items() if not zero(c, self.magnitude(m))}
        )

    # --- ring operations ----------------------------------------------------
    def _sum(self, other: Poly, sign: int) -> Poly:
        terms = dict(self.terms)
        for m, c in other.terms.items():
            if sign > 0:
                terms[m] = terms[m] + c if m in terms else c
            else:
                terms[m] = terms[m] - c if m in terms else -c
        if self.mags is None and other.mags is None:
            return Poly(self.nvars, terms)
        mags = {m: self._mag(m) for m in self.terms}
        for m in other.terms:
            mags[m] = mags.get(m, 0.0) + other._mag(m)
        return Poly(self.nvars, terms, mags)

    def __add__(self, other: Poly) -> Poly:
        return self._sum(other, 1)

    def __sub__(self, other: Poly) -> Poly:
        return self._sum(other, -1)

    def __neg__(self) -> Poly:
        return self._keep({m: -c for m, c in self.terms.items()})

    def scale(self, c: object) -> Poly:
        c = se.S(c)
        if c == 0:
            return Poly(self.nvars)
        terms = {m: c * v for m, v in self.terms.items()}
        if self.mags is None:
            return Poly(self.nvars, terms)
        k = _size(c)
        return Poly(self.nvars, terms, {m: k * self._mag(m) for m in self.terms})

    def mul(
        self, other: Poly, weights: Sequence[int] | None = None, degree: int | None = None
    ) -> Poly:
        """The product, truncated at weighted ``degree`` when given.

        With a truncation, the terms of ``other`` are visited by increasing
        weighted degree and the scan stops at the first pair beyond ``degree``.
        """
        if self.mags is not None or other.mags is not None:
            return self._mul_tracked(other, weights, degree)
        terms: dict[Monomial, se.Basic] = {}
        get = terms.get
        add = operator.add
        if degree is None:
            for ma, ca in self.terms.items():
                for mb, cb in other.terms.items():
                    m = tuple(map(add, ma, mb))
                    v = ca * cb
                    old = get(m)
                    terms[m] = v if old is None else old + v
            return Poly(self.nvars, terms)
        assert weights is not None
        pairs_b = sorted(
            ((weighted_degree(m, weights), m, c) for m, c in other.terms.items()),
            key=operator.itemgetter(0),
        )
        if not pairs_b:
            return Poly(self.nvars)
        lowest = pairs_b[0][0]
        for ma, ca in self.terms.items():
            room = degree - weighted_degree(ma, weights)
            if room < lowest:
                continue
            for db, mb, cb in pairs_b:
                if db > room:
                    break
                m = tuple(map(add, ma, mb))
                v = ca * cb
                old = get(m)
                terms[m] = v if old is None else old + v
        return Poly(self.nvars, terms)

    def _mul_tracked(
        self, other: Poly, weights: Sequence[int] | None, degree: int | None
    ) -> Poly:
        """:meth:`mul` with the magnitudes: the sum of the products of the magnitudes."""
        terms: dict[Monomial, se.Basic] = {}
        mags: dict[Monomial, float] = {}
        add = operator.add
        for ma, ca in self.terms.items():
            ka = self._mag(ma)
            room = None if degree is None else degree - weighted_degree(ma, weights or ())
            for mb, cb in other.terms.items():
                if room is not None and weighted_degree(mb, weights or ()) > room:
                    continue
                m = tuple(map(add, ma, mb))
                v = ca * cb
                terms[m] = terms[m] + v if m in terms else v
                mags[m] = mags.get(m, 0.0) + ka * other._mag(mb)
        return Poly(self.nvars, terms, mags)

    def diff(self, k: int) -> Poly:
        """The partial derivative with respect to variable ``k`` (0-based)."""
        terms: dict[Monomial, se.Basic] = {}
        mags: dict[Monomial, float] | None = None if self.mags is None else {}
        for m, c in self.terms.items():
            a = m[k]
            if a:
                mm = list(m)
                mm[k] = a - 1
                terms[tuple(mm)] = c * a
                if mags is not None:
                    mags[tuple(mm)] = a * self._mag(m)
        return Poly(self.nvars, terms, mags)

    def restrict(self, keep: int) -> Poly:
        """Set the variables of index ``>= keep`` to 0."""
        return self._keep({m: c for m, c in self.terms.items() if not any(m[keep:])})

    def compose(
        self,
        args: Sequence[Poly],
        weights: Sequence[int] | None = None,
        degree: int | None = None,
    ) -> Poly:
        """Substitute ``args[k]`` for variable ``k``, truncating in the args' variables."""
        if not args:
            return self
        nv = args[0].nvars
        powers: list[list[Poly]] = [[Poly.constant(nv, 1)] for _ in args]
        acc: dict[Monomial, se.Basic] = {}
        tracked = self.mags is not None or any(a.mags is not None for a in args)
        mags: dict[Monomial, float] = {}
        for mono, c in self.terms.items():
            term = Poly.constant(nv, c)
            if tracked:
                term = Poly(nv, term.terms, {(0,) * nv: self._mag(mono)})
            for k, a in enumerate(mono):
                if not a:
                    continue
                pk = powers[k]
                while len(pk) <= a:
                    pk.append(pk[-1].mul(args[k], weights, degree))
                term = term.mul(pk[a], weights, degree)
                if not term.terms:
                    break
            for m, v in term.terms.items():
                acc[m] = acc[m] + v if m in acc else v
                if tracked:
                    mags[m] = mags.get(m, 0.0) + term._mag(m)
        return Poly(nv, acc, mags if tracked else None)

    # --- conversions ----------------------------------------------------------
    def to_symengine(self, symbols: Sequence[se.Symbol]) -> se.Basic:
        out = []
        for m, c in self.terms.items():
            f = [c]
            for s, a in zip(symbols, m, strict=True):
                if a:
                    f.append(s**a if a > 1 else s)
            out.append(se.Mul(*f))
        return se.Add(*out) if out else se.Integer(0)

    def _to_sympy_canonical(self, symbols: Sequence[sp.Expr]) -> sp.Expr | None:
        """The sympy expression built directly in sympy's canonical form, or ``None``.

        Applies to rational coefficients and variables that are distinct symbols or
        shifted symbols ``x - c`` (``c`` a number).  A term ``q * prod(v_k**a_k)`` is
        ``Mul(q, *powers)`` with the factors in sympy's canonical order
        (:meth:`sympy.Basic.compare`, by which ``Mul`` and ``Add`` sort their
        arguments); the few terms sympy rewrites (a number times one shifted variable,
        which ``Mul`` distributes, and the constant) go through sympy's constructors;
        the sum is their union in canonical order, the number first, as ``Add``
        builds it (the other terms are distinct monomials: nothing to collect), without
        the constructors' checks and flattening on every term (seconds on thousands
        of terms).  Elsewhere ``None``: the constructors decide.
        """
        bases: list[sp.Symbol] = []
        for x in symbols:
            if isinstance(x, sp.Symbol):
                bases.append(x)
                continue
            if not isinstance(x, sp.Add):
                return None
            syms = [a for a in x.args if isinstance(a, sp.Symbol)]
            if len(syms) != 1 or not all(a.is_number for a in x.args if a is not syms[0]):
                return None
            bases.append(syms[0])
        if len(set(bases)) != len(bases):
            return None
        powers: dict[tuple[int, int], sp.Expr] = {}
        special: list[sp.Expr] = []
        terms: list[sp.Expr] = []
        for m, c in self.terms.items():
            if isinstance(c, se.Integer):
                q: sp.Expr = sp.Integer(int(c))
            elif isinstance(c, se.Rational):
                num, den = c.get_num_den()
                q = sp.Rational(int(num), int(den))
            else:
                return None
            factors: list[sp.Expr] = []
            for k, a in enumerate(m):
                if a:
                    pw = powers.get((k, a))
                    if pw is None:
                        pw = powers[(k, a)] = symbols[k] if a == 1 else sp.Pow(symbols[k], a)
                    factors.append(pw)
            if not factors or (len(factors) == 1 and isinstance(factors[0], sp.Add)):
                special.append(sp.Mul(q, *factors))
                continue
            factors.sort(key=_CANONICAL_ORDER)
            if q == 1 and len(factors) == 1:
                terms.append(factors[0])
            else:
                args = factors if q == 1 else [q, *factors]
                terms.append(cast(sp.Expr, sp.Mul._from_args(args)))
        number: sp.Expr = sp.Integer(0)
        if special:
            rest = sp.Add(*special)
            for a in sp.Add.make_args(rest):
                if a.is_Number:
                    number = a
                elif a != 0:
                    terms.append(a)
        terms.sort(key=_CANONICAL_ORDER)
        if number != 0:
            terms.insert(0, number)
        if not terms:
            return sp.Integer(0)
        return terms[0] if len(terms) == 1 else cast(sp.Expr, sp.Add._from_args(terms))

    def to_sympy(self, symbols: Sequence[sp.Expr], *, keep_factors: bool = False) -> sp.Expr:
        """The polynomial as a sympy expression in ``symbols`` (symbols or expressions).

        With ``keep_factors`` the products are not evaluated, so a float coefficient is
        not distributed over a factor such as ``(x - 1/3)`` (which would round ``1/3``).
        """
        if not keep_factors:
            direct = self._to_sympy_canonical(symbols)
            if direct is not None:
                return direct
            # built by symengine (fast on thousands of terms), converted once
            ses = [se.S(x) for x in symbols]
            total = se.Add(
                *[
                    se.Mul(c, *[x**a for x, a in zip(ses, m, strict=True) if a])
                    for m, c in sorted(self.terms.items())
                ]
            )
            return sp.S(total)
        # unevaluated products and sum, built from their arguments directly (the public
        # constructors sympify and inspect every argument: seconds on thousands of terms)
        powers: dict[tuple[int, int], sp.Expr] = {}
        out = []
        for m, c in sorted(self.terms.items()):
            f: list[sp.Expr] = [sp.S(c)]
            for k, (s, a) in enumerate(zip(symbols, m, strict=True)):
                if a:
                    pw = powers.get((k, a))
                    if pw is None:
                        pw = powers[(k, a)] = s**a
                    f.append(pw)
            if len(f) == 1:
                out.append(f[0])
            elif f[0] == 1:
                out.append(f[1] if len(f) == 2 else sp.Mul._from_args(f[1:]))
            else:
                out.append(sp.Mul._from_args(f))
        if len(out) > 1:
            return cast(sp.Expr, sp.Add._from_args(out))
        return out[0] if out else sp.Integer(0)


def lie_derivative(
    field: Sequence[Poly], f: Poly, weights: Sequence[int] | None = None, degree: int | None = None
) -> Poly:
    r"""$Xf = \sum_k X_k\,\partial f/\partial y_k$ for polynomial ``field`` and ``f``."""
    out = Poly(f.nvars)
    for k, comp in enumerate(field):
        if not comp.terms:
            continue
        d = f.diff(k)
        if d.terms:
            out = out + comp.mul(d, weights, degree)
    return out


def bracket(X: Sequence[Poly], Y: Sequence[Poly]) -> tuple[Poly, ...]:
    r"""$[X, Y] = DY\cdot X - DX\cdot Y$ for polynomial fields (no truncation)."""
    return tuple(lie_derivative(X, yj) - lie_derivative(Y, xj) for xj, yj in zip(X, Y, strict=True))


def _series_pairs(expr: se.Basic, t: se.Symbol, degree: int) -> list[tuple[int, se.Basic]]:
    """``(k, coefficient of t**k)`` for k <= degree: symengine's series, else sympy's.

    symengine's univariate series lacks some functions (``Abs``); sympy's
    ``series`` is the (slow, rare) fallback.  A non-integer or negative power of
    ``t`` (no Taylor expansion) raises :class:`ArithmeticError`.
    """
    try:
        raw = se.series(expr, t, n=degree + 1, as_deg_coef_pair=True)
        pairs = [(deg, se.S(coef)) for deg, coef in raw]
    except RuntimeError:
        ts = t._sympy_()
        ser = sp.series(expr._sympy_(), ts, 0, degree + 1).removeO()
        poly = sp.Poly(ser, ts)  # PolynomialError for sqrt(t), 1/t
        pairs = [(m[0], se.S(c)) for m, c in poly.terms()]
    out = []
    for deg, coef in pairs:
        if int(deg) != deg or int(deg) < 0:
            raise ArithmeticError(f"a term t**{deg}")
        out.append((int(deg), coef))
    return out


def weighted_jets(
    exprs: Sequence[se.Basic],
    xsyms: Sequence[se.Symbol],
    args: Sequence[Poly],
    weights: Sequence[int],
    degree: int,
    numeric: bool = False,
) -> list[Poly]:
    r"""Weighted Taylor jets of ``exprs`` along the polynomial map $x = \varphi(y)$.

    Parameters
    ----------
    exprs:
        Expressions in ``xsyms`` (symengine).
    xsyms:
        The symbols $x_1..x_n$ of the expressions.
    args:
        ``args[k]`` is $x_k$ as a :class:`Poly` in $y$ (constant term: the point).
    weights:
        Weights of the $y$ variables.
    degree:
        Keep the terms of weighted degree ``<= degree``.
    numeric:
        Evaluate every coefficient to a float.

    Returns
    -------
    list of Poly
        The truncated jet of $f(\varphi(y))$ in $y$, one per expression, computed
        by $y_k \to t^{w_k} y_k$ and a univariate series in $t$ to order ``degree``.

    Raises
    ------
    PointError
        If an expression is not smooth at the point (no Taylor expansion:
        ``sqrt(x)``, ``(x**2)**(1/3)`` at ``x = 0``).

    Examples
    --------
    >>> x = se.Symbol("x")
    >>> [p] = weighted_jets([se.sin(x)], [x], [Poly.variable(1, 0)], [1], 3)
    >>> sorted(p.terms.items())
    [((1,), 1), ((3,), -1/6)]
    """
    nv = args[0].nvars if args else 0
    t = se.Symbol("_nilpotent_t")
    ys = [se.Symbol(f"_nilpotent_y{k}") for k in range(nv)]
    tys = [t**w * y for w, y in zip(weights, ys, strict=True)]
    base: dict[se.Symbol, se.Basic] = {}
    if numeric:
        # the map's coefficients that are rounding noise (negligible against their
        # magnitudes) would enter the series as values: they are dropped first
        args = [a.drop_zeros(ZeroTest()) if a.mags is not None else a for a in args]
        # symengine's series does not expand around float constants: expand around
        # symbols standing for the constant terms, then evaluate the coefficients.
        moved = []
        for k, a in enumerate(args):
            c = a.value_at_zero()
            if c != 0:
                sym = se.Symbol(f"_nilpotent_p{k}")
                base[sym] = c
                a = a - Poly.constant(nv, c) + Poly.constant(nv, sym)
            moved.append(a)
        args = moved
    sub = {x: a.to_symengine(tys) for x, a in zip(xsyms, args, strict=True)}
    out: list[Poly] = []
    for e in exprs:
        e = se.S(e)
        if e == 0:
            out.append(Poly(nv))
            continue
        es = e.xreplace(sub) if sub else e
        if not es.has(t):
            out.append(Poly.from_expr(es.xreplace(base) if base else es, ys))
            continue
        try:
            pairs = _series_pairs(es, t, degree)
            acc = Poly(nv)
            for deg, coef in pairs:
                if deg > degree:
                    continue
                if base:
                    coef = coef.xreplace(base)
                acc = acc + Poly.from_expr(coef, ys, ignore=(t,))
        except (RuntimeError, ArithmeticError, ValueError, TypeError, sp.PolynomialError) as exc:
            reason = " ".join(str(exc).split()).replace("_nilpotent_", "")
            raise PointError(
                f"{e} is not smooth at the point: it has no Taylor expansion there ({reason})"
            ) from exc
        out.append(acc.truncate(weights, degree))
    if numeric:
        # rounded once from the jet: each coefficient's magnitude is tracked from here on
        out = [
            Poly(p.nvars, {m: se.RealDouble(to_double(c)) for m, c in p.terms.items()}, {})
            for p in out
        ]
    return out
