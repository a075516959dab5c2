"""Weighted Taylor jets and truncated polynomials, against plain sympy."""

from __future__ import annotations

import hypothesis.strategies as st
import pytest
import symengine as se
import sympy as sp
from hypothesis import given, settings

from nilpotent.core.coordinates.jets import Poly, ZeroTest, bracket, weighted_jets
from nilpotent.errors import PointError

X = sp.symbols("x1 x2 x3")
Y = sp.symbols("y1 y2 y3")
FUNCS = [sp.sin, sp.cos, sp.exp, lambda u: 1 / (1 + u), lambda u: sp.sqrt(1 + u)]


def sympy_weighted_jet(expr, subs, weights, degree):
    """Weighted parts of degree <= degree of expr(x = subs(y)), by sympy series in t."""
    t = sp.Symbol("t")
    e = expr.xreplace(subs).xreplace({y: t**w * y for y, w in zip(Y, weights, strict=True)})
    ser = sp.series(e, t, 0, degree + 1).removeO()
    return sp.expand(ser.subs(t, 1))


@settings(max_examples=25, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.sampled_from(range(len(FUNCS))), st.sampled_from(range(3)), st.integers(-2, 2)
        ),
        min_size=1,
        max_size=3,
    ),
    st.lists(st.integers(1, 3), min_size=3, max_size=3),
    st.integers(1, 4),
    st.lists(st.integers(-2, 2), min_size=3, max_size=3),
)
def test_weighted_jets_match_sympy_series(terms, weights, degree, quad):
    """f(x) = Σ c·F(x_k) along x = (y1, y2 + q0 y1², y3 + q1 y1 y2 + q2 y2²): jets as sympy."""
    expr = sp.Add(*[c * FUNCS[i](X[k]) for i, k, c in terms])
    y1, y2, y3 = Y
    images = (y1, y2 + quad[0] * y1**2, y3 + quad[1] * y1 * y2 + quad[2] * y2**2)
    ys = [se.Symbol(str(y)) for y in Y]
    args = [Poly.from_expr(se.S(e), ys) for e in images]
    [jet] = weighted_jets([se.S(expr)], [se.S(x) for x in X], args, weights, degree)
    expected = sympy_weighted_jet(expr, dict(zip(X, images, strict=True)), weights, degree)
    assert sp.expand(jet.to_sympy(Y) - expected) == 0


def test_poly_arithmetic_and_truncation():
    ys = [se.Symbol(str(y)) for y in Y]
    p = Poly.from_expr(se.S(1 + Y[0] + Y[1] ** 2), ys)
    q = Poly.from_expr(se.S(Y[0] - Y[2]), ys)
    w = (1, 1, 2)
    assert sp.expand(p.mul(q).to_sympy(Y) - (1 + Y[0] + Y[1] ** 2) * (Y[0] - Y[2])) == 0
    prod = p.mul(q, w, 2).to_sympy(Y)  # keep weighted degree <= 2: y1 - y3 + y1**2
    assert sp.expand(prod - (Y[0] - Y[2] + Y[0] ** 2)) == 0
    comp = p.compose([q, q, q]).to_sympy(Y)
    assert sp.expand(comp - (1 + (Y[0] - Y[2]) + (Y[0] - Y[2]) ** 2)) == 0


def test_bracket_convention():
    """[X, Y] = DY·X − DX·Y: [∂1, y1 ∂2] = ∂2."""
    ys = [se.Symbol(str(y)) for y in Y[:2]]
    one, zero = Poly.constant(2, 1), Poly(2)
    X1 = (one, zero)
    X2 = (zero, Poly.from_expr(ys[0], ys))
    b = bracket(X1, X2)
    assert b[0].is_zero() and b[1].terms == {(0, 0): 1}


def test_zero_test():
    z = ZeroTest()
    assert z(se.S(0)) and not z(se.S(1))
    assert z(se.cos(se.Rational(1, 5)) ** 2 + se.sin(se.Rational(1, 5)) ** 2 - 1)
    assert z.numeric_decisions == 1
    # floats: relative to the scale they were computed at, never to an absolute unit
    assert z(se.RealDouble(1e-17), 1.0) and not z(se.RealDouble(1e-3), 1.0)
    assert not z(se.RealDouble(1e-17))  # no scale: only an exact 0 is 0
    assert not z(se.RealDouble(1e-60), 1e-55) and z(se.RealDouble(1e-70), 1e-55)
    assert not z(se.RealDouble(1e280), 1e285) and z(se.RealDouble(1e270), 1e285)


def test_not_smooth():
    a = se.Symbol("a")
    with pytest.raises(PointError, match="not smooth"):
        weighted_jets([se.sqrt(a)], [a], [Poly.variable(1, 0)], [1], 2)


# --- sympy form of a polynomial: direct canonical construction vs sympy's constructors ----

_X = sp.symbols("x0:4")
_SHIFTS = (0, sp.Rational(1, 3), -2, sp.pi / 2, sp.sqrt(2))


def _through_constructors(p: Poly, symbols) -> sp.Expr:
    """The second method: the whole sum built in symengine, converted by sympy's constructors."""
    ses = [se.S(x) for x in symbols]
    total = se.Add(
        *[se.Mul(c, *[x**a for x, a in zip(ses, m, strict=True) if a]) for m, c in p.terms.items()]
    )
    return sp.S(total)


@st.composite
def _polys(draw):
    n = 4
    monos = draw(
        st.lists(st.tuples(*[st.integers(0, 3)] * n), min_size=0, max_size=12, unique=True)
    )
    coeffs = st.one_of(
        st.integers(-5, 5).map(se.Integer),
        st.tuples(st.integers(-7, 7), st.integers(1, 6)).map(lambda t: se.Rational(*t)),
    )
    return Poly(n, {m: draw(coeffs) for m in monos})


@settings(max_examples=300, deadline=None)
@given(p=_polys(), shifts=st.lists(st.sampled_from(_SHIFTS), min_size=4, max_size=4))
def test_to_sympy_builds_the_expression_sympy_builds(p, shifts):
    """Same tree (arguments in the same order: same printed text) as sympy's constructors."""
    symbols = [x - c if c != 0 else x for x, c in zip(_X, shifts, strict=True)]
    got = p.to_sympy(symbols)
    want = _through_constructors(p, symbols)
    assert sp.srepr(got) == sp.srepr(want)
    assert str(got) == str(want)
    assert sp.expand(got - want) == 0


def test_to_sympy_falls_back_for_irrational_coefficients_and_repeated_symbols():
    p = Poly(2, {(1, 0): se.sqrt(2) / 2, (0, 2): se.Integer(3), (0, 0): se.Integer(1)})
    assert p._to_sympy_canonical(_X[:2]) is None
    assert sp.srepr(p.to_sympy(_X[:2])) == sp.srepr(_through_constructors(p, _X[:2]))
    q = Poly(2, {(1, 0): se.Integer(1), (0, 1): se.Integer(1)})
    assert q._to_sympy_canonical([_X[0], _X[0]]) is None
    assert q.to_sympy([_X[0], _X[0]]) == 2 * _X[0]


@settings(max_examples=100, deadline=None)
@given(
    a=_polys(),
    b=_polys(),
    weights=st.lists(st.integers(1, 3), min_size=4, max_size=4),
    degree=st.one_of(st.none(), st.integers(0, 10)),
)
def test_truncated_product_and_composition_match_sympy(a, b, weights, degree):
    """``mul``/``compose`` truncated: sympy's expanded result, terms of higher degree dropped."""

    def truncated(e: sp.Expr) -> dict:
        poly = sp.Poly(e, *_X)
        return {
            m: c
            for m, c in poly.terms()
            if c != 0
            and (degree is None or sum(x * w for x, w in zip(m, weights, strict=True)) <= degree)
        }

    def as_dict(p: Poly) -> dict:
        return {m: sp.S(c) for m, c in p.terms.items()}

    ea, eb = a.to_sympy(_X), b.to_sympy(_X)
    assert as_dict(a.mul(b, weights, degree)) == truncated(sp.expand(ea * eb))
    # composition: a of total degree <= 2, arguments of at most 3 terms (sympy stays quick)
    small_a = Poly(4, {m: c for m, c in a.terms.items() if sum(m) <= 2})
    small_b = Poly(4, dict(list(b.terms.items())[:3]))
    args = [small_b, Poly.variable(4, 1) + small_b, Poly.variable(4, 0), small_b]
    arg_exprs = [p.to_sympy(_X) for p in args]
    want = sp.expand(small_a.to_sympy(_X).xreplace(dict(zip(_X, arg_exprs, strict=True))))
    assert as_dict(small_a.compose(args, weights, degree)) == truncated(want)
