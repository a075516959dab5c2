"""Bracket words, the Hall basis, and the Lie bracket: identities and hand results."""

from __future__ import annotations

import itertools

import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from nilpotent.core.lie.brackets import (
    bracket,
    format_word,
    hall_basis,
    lie_derivative,
    parse_word,
    word_field,
    word_length,
    word_values_at,
)
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import OptionError

X = sp.symbols("x1 x2 x3")
x1, x2, x3 = X

# --- words -------------------------------------------------------------------

words = st.recursive(
    st.integers(min_value=1, max_value=4),
    lambda inner: st.tuples(inner, inner),
    max_leaves=8,
)


@given(words)
def test_format_parse_round_trip(w):
    text = format_word(w)
    assert parse_word(text) == w
    assert parse_word(text.replace(",", " , ")) == w
    assert word_length(w) == text.count("X")


def test_format_examples():
    assert format_word((1, (1, 2))) == "[X1,[X1,X2]]"
    assert parse_word(" [ X2 , [X1,X2] ] ") == (2, (1, 2))


@pytest.mark.parametrize(
    "text", ["", "X0", "[X1]", "[X1,X2", "[X1,X2]]", "X1 X2", "[Y1,X2]", "[X1,X9]"]
)
def test_parse_errors(text):
    with pytest.raises(OptionError):
        parse_word(text, m=3)


# --- Hall basis ---------------------------------------------------------------


def witt(m: int, k: int) -> int:
    """Dimension of the degree-k part of the free Lie algebra on m generators."""
    return sum(sp.mobius(d) * m ** (k // d) for d in sp.divisors(k)) // k


@pytest.mark.parametrize(("m", "max_length"), [(1, 5), (2, 8), (3, 6), (4, 5)])
def test_hall_basis_dimensions_follow_witt(m, max_length):
    basis = hall_basis(m, max_length)
    for k in range(1, max_length + 1):
        assert sum(1 for w in basis if word_length(w) == k) == witt(m, k)


def test_hall_basis_order_and_subwords():
    basis = hall_basis(3, 5)
    index = {w: i for i, w in enumerate(basis)}
    lengths = [word_length(w) for w in basis]
    assert lengths == sorted(lengths)
    for w in basis:
        if not isinstance(w, int):
            assert w[0] in index and w[1] in index
            assert index[w[0]] < index[w[1]] < index[w]


def _commutator_polynomial(w):
    """The word as a non-commutative polynomial {letters: coefficient}."""
    if isinstance(w, int):
        return {(w,): 1}
    a, b = _commutator_polynomial(w[0]), _commutator_polynomial(w[1])
    out: dict[tuple[int, ...], int] = {}
    for (ka, ca), (kb, cb) in itertools.product(a.items(), b.items()):
        out[ka + kb] = out.get(ka + kb, 0) + ca * cb
        out[kb + ka] = out.get(kb + ka, 0) - ca * cb
    return {k: c for k, c in out.items() if c}


@pytest.mark.parametrize(("m", "k"), [(2, 5), (2, 6), (3, 4)])
def test_hall_words_are_independent_in_the_free_associative_algebra(m, k):
    # Independent of the Hall construction: by PBW the free Lie algebra embeds in the
    # free associative algebra; independent words, Witt-many, form a basis.
    polys = [_commutator_polynomial(w) for w in hall_basis(m, k) if word_length(w) == k]
    monomials = sorted({mono for p in polys for mono in p})
    matrix = sp.Matrix([[p.get(mono, 0) for mono in monomials] for p in polys])
    assert matrix.rank() == len(polys) == witt(m, k)


# --- Lie derivative and bracket ------------------------------------------------

coeffs = st.integers(min_value=-3, max_value=3)
monomials = [sp.Integer(1), x1, x2, x3, x1 * x2, x2**2, x1 * x3, x3**2]


@st.composite
def poly_fields(draw):
    return tuple(
        sp.Add(*[draw(coeffs) * mono for mono in monomials[: draw(st.integers(1, 8))]])
        for _ in range(3)
    )


@st.composite
def poly_functions(draw):
    return sp.Add(*[draw(coeffs) * mono for mono in monomials]) + draw(coeffs) * x1**3


@settings(max_examples=25, deadline=None)
@given(poly_fields(), poly_fields())
def test_antisymmetry(a, b):
    ab, ba = bracket(a, b, X), bracket(b, a, X)
    assert all(sp.expand(p + q) == 0 for p, q in zip(ab, ba, strict=True))


@settings(max_examples=10, deadline=None)
@given(poly_fields(), poly_fields(), poly_fields())
def test_jacobi(a, b, c):
    terms = [
        bracket(a, bracket(b, c, X), X),
        bracket(b, bracket(c, a, X), X),
        bracket(c, bracket(a, b, X), X),
    ]
    assert all(sp.expand(sum(t[j] for t in terms)) == 0 for j in range(3))


@settings(max_examples=25, deadline=None)
@given(poly_fields(), poly_fields(), poly_functions())
def test_bracket_acts_as_commutator_of_derivations(a, b, f):
    # Convention [X,Y]f = X(Yf) - Y(Xf).
    lhs = lie_derivative(bracket(a, b, X), f, X)
    rhs = lie_derivative(a, lie_derivative(b, f, X), X) - lie_derivative(
        b, lie_derivative(a, f, X), X
    )
    assert sp.expand(lhs - rhs) == 0


def test_unicycle_bracket_by_hand():
    x, y, th = sp.symbols("x y theta")
    uni = ControlSystem("unicycle", (x, y, th), ((sp.cos(th), sp.sin(th), 0), (0, 0, 1)))
    # [X1, X2] = DX2.X1 - DX1.X2 = -d/dtheta (cos, sin, 0) = (sin, -cos, 0)
    assert word_field(uni, (1, 2)) == (sp.sin(th), -sp.cos(th), 0)
    assert word_field(uni, (2, 1)) == (-sp.sin(th), sp.cos(th), 0)
    assert word_values_at(uni, [(1, 2)], (0, 0, 0)) == ((0, -1, 0),)


def test_word_field_matches_nested_sympy_brackets():
    th = sp.symbols("theta0:3")
    x, y = sp.symbols("x y")
    coords = (x, y, *th)
    f1 = (
        sp.cos(th[0]),
        sp.sin(th[0]),
        0,
        sp.sin(th[0] - th[1]),
        sp.cos(th[0] - th[1]) * sp.sin(th[1] - th[2]),
    )
    f2 = (0, 0, 1, 0, 0)
    sys = ControlSystem("two-trailers", coords, (f1, f2))
    fields = {1: f1, 2: f2}

    def nested(w):
        if isinstance(w, int):
            return fields[w]
        return bracket(nested(w[0]), nested(w[1]), coords)

    point = (sp.Integer(0), sp.Integer(0), sp.pi / 3, sp.pi / 6, sp.Integer(0))
    subs = dict(zip(coords, point, strict=True))
    for w in hall_basis(2, 4):
        expected = nested(w)
        got = word_field(sys, w)
        pairs = zip(got, expected, strict=True)
        assert all(sp.expand(sp.expand_trig(a - b)) == 0 for a, b in pairs)
    # values at a point: lazily (directional derivatives) and from the built field agree
    sys2 = ControlSystem("two-trailers", coords, (f1, f2))
    word = (2, (1, (1, 2)))
    lazy = word_values_at(sys2, [word], point)[0]
    exact = tuple(sp.nsimplify(sp.simplify(e.subs(subs))) for e in nested(word))
    assert all(sp.simplify(a - b) == 0 for a, b in zip(lazy, exact, strict=True))


def test_word_field_returns_the_systems_own_symbols():
    x, y, th = sp.symbols("x y theta", real=True)
    uni = ControlSystem("unicycle", (x, y, th), ((sp.cos(th), sp.sin(th), 0), (0, 0, 1)))
    field = word_field(uni, (1, (1, 2)))
    assert set().union(*(e.free_symbols for e in field)) <= {th}
