"""Non-holonomic orders: hand values, multiplicativity, privileged monomials, field orders."""

from __future__ import annotations

import math

import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from nilpotent.core.coordinates.orders import field_order, function_order, weighted_order
from nilpotent.core.lie.brackets import bracket
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import OptionError

x1, x2, x3 = sp.symbols("x1:4")
x, y, th = sp.symbols("x y theta")
UNICYCLE = ControlSystem("unicycle", (x, y, th), ((sp.cos(th), sp.sin(th), 0), (0, 0, 1)))
# Heisenberg: x1, x2, x3 are privileged at 0 with weights (1, 1, 2) (X1 X2 x3 = 1/2).
HEIS = ControlSystem("heisenberg", (x1, x2, x3), ((1, 0, -x2 / 2), (0, 1, x1 / 2)))
MARTINET = ControlSystem("martinet", (x1, x2, x3), ((1, 0, x2**2 / 2), (0, 1, 0)))
WEIGHTS = (1, 1, 2)


def test_unicycle_orders_by_hand():
    o = (0, 0, 0)
    # X1 x = cos(theta) -> 1 at 0; y: X1 y = sin(theta) = 0 at 0, X2 X1 y = cos(theta) = 1.
    assert function_order(UNICYCLE, x, o) == 1
    assert function_order(UNICYCLE, th, o) == 1
    assert function_order(UNICYCLE, y, o) == 2
    assert function_order(UNICYCLE, 1 + y, o) == 0
    assert function_order(UNICYCLE, sp.Integer(0), o) == math.inf
    # away from theta = 0, y is no longer of order 2
    assert function_order(UNICYCLE, y, (0, 0, sp.pi / 4)) == 1


def test_martinet_third_coordinate_has_order_three():
    # X1 x3 = x2^2/2, X2 X1 x3 = x2, X2 X2 X1 x3 = 1: order 3 at 0 (weight 3)
    assert function_order(MARTINET, x3, (0, 0, 0)) == 3
    # at (0, 1, 0): X1 x3 = 1/2; but x3 - x1/2 has X1 = X2 = 0 there and X2 X1 = x2 = 1
    assert function_order(MARTINET, x3, (0, 1, 0)) == 1
    assert function_order(MARTINET, x3 - x1 / 2, (0, 1, 0)) == 2


def test_max_order_cut_off():
    assert function_order(HEIS, x3**3, (0, 0, 0), max_order=4) == math.inf
    assert function_order(HEIS, x3**3, (0, 0, 0), max_order=6) == 6
    with pytest.raises(OptionError):
        function_order(HEIS, x3, None, max_order=-1)


exponents = st.tuples(st.integers(0, 2), st.integers(0, 2), st.integers(0, 1))


@settings(max_examples=20, deadline=None)
@given(exponents)
def test_privileged_monomials_have_their_weighted_degree(alpha):
    mono = x1 ** alpha[0] * x2 ** alpha[1] * x3 ** alpha[2]
    expected = sum(w * a for w, a in zip(WEIGHTS, alpha, strict=True))
    assert function_order(HEIS, mono, (0, 0, 0)) == expected


@settings(max_examples=15, deadline=None)
@given(exponents, exponents, st.integers(-2, 2))
def test_order_of_product_and_sum(a, b, c):
    f = x1 ** a[0] * x2 ** a[1] * x3 ** a[2] + c * x3 ** (a[2] + 1)
    g = x1 ** b[0] * x2 ** b[1] * x3 ** b[2]
    of, og = function_order(HEIS, f, None), function_order(HEIS, g, None)
    assert function_order(HEIS, sp.expand(f * g), None) >= of + og
    assert function_order(HEIS, sp.expand(f + g), None) >= min(of, og)


def test_weighted_order():
    assert weighted_order(x1 * x2 + x3**2, (x1, x2, x3), WEIGHTS) == 2
    assert weighted_order(sp.cos(x1) - 1, (x1, x2, x3), WEIGHTS) == 2
    assert weighted_order(sp.Integer(0), (x1, x2, x3), WEIGHTS) == math.inf


def test_field_orders_in_privileged_coordinates():
    names = (x1, x2, x3)
    # X_i have order -1, their bracket (= d/dx3) order -2 (MATH.md §3)
    for fld in HEIS.fields:
        assert field_order(fld, WEIGHTS, names) == -1
    b = bracket(HEIS.fields[0], HEIS.fields[1], names)
    assert tuple(b) == (0, 0, 1)
    assert field_order(b, WEIGHTS, names) == -2
    assert field_order((0, 0, x1), WEIGHTS, names) == -1
    assert field_order((0, 0, x1**2), WEIGHTS, names) == 0
    assert field_order((x3, 0, 0), WEIGHTS, names) == 1
    assert field_order((0, 0, 0), WEIGHTS, names) == math.inf
    polys = [sp.Poly(c, *names) for c in (1, 0, -x2 / 2)]
    assert field_order(polys, WEIGHTS) == -1
    with pytest.raises(OptionError):
        field_order((1, 0, 0), WEIGHTS)


@settings(max_examples=15, deadline=None)
@given(exponents, st.integers(0, 2))
def test_field_order_agrees_with_function_orders(alpha, j):
    # ord(Z) >= sigma  <=>  ord(Z f) >= sigma + ord(f) for every f: check on the
    # coordinates, where it is the definition in privileged coordinates.
    names = (x1, x2, x3)
    mono = x1 ** alpha[0] * x2 ** alpha[1] * x3 ** alpha[2]
    comps = tuple(mono if k == j else 0 for k in range(3))
    sigma = field_order(comps, WEIGHTS, names)
    ord_mono = function_order(HEIS, mono, None)
    assert sigma == ord_mono - WEIGHTS[j]
