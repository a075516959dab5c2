"""Points (``--at``) and parameter assignments (``--param``) written by users."""

from __future__ import annotations

import math

import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from nilpotent.core.model.expressions import exact_decimals, real_value
from nilpotent.core.model.points import format_point, parse_param_assignments, parse_point
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ModelError, PointError

x, y, th = sp.symbols("x y theta")
UNICYCLE = ControlSystem("unicycle", (x, y, th), ((sp.cos(th), sp.sin(th), 0), (0, 0, 1)))


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("theta=pi/3", (0, 0, sp.pi / 3)),
        ("x=1/2,y=-2", (sp.Rational(1, 2), -2, 0)),
        (" y = sqrt(2) , theta = E ", (0, sp.sqrt(2), sp.E)),
        ("theta=atan2(1, 1)", (0, 0, sp.pi / 4)),  # the comma inside the call belongs to it
        # decimals are the exact rationals they denote, every digit counted
        ("x=0.25", (sp.Rational(1, 4), 0, 0)),
        ("x=0.1000000000000000000001", (sp.Rational(10**21 + 1, 10**22), 0, 0)),
        ("x=1e-300", (sp.Rational(1, 10**300), 0, 0)),
    ],
)
def test_parse_point(text, expected):
    point = parse_point(text, UNICYCLE)
    assert point == tuple(sp.Integer(v) if isinstance(v, int) else v for v in expected)


def test_exact_values_stay_exact():
    point = parse_point("x=1/3,theta=pi/6", UNICYCLE)
    assert isinstance(point[0], sp.Rational)
    assert sp.sin(point[2]) == sp.Rational(1, 2)  # sympy evaluates sin(pi/6) exactly


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        ("z=1", ["--at", "unknown coordinate 'z'", "x, y, theta"]),
        ("x=1,x=2", ["--at", "'x' given twice"]),
        ("x", ["--at", "no '='"]),
        ("x=", ["--at", "empty value for 'x'"]),
        ("=1", ["--at", "missing name"]),
        ("", ["--at", "empty"]),
        ("x=1,,y=2", ["--at", "empty item"]),
        ("x=theta", ["--at x", "unknown name 'theta'"]),
        ("x=sqrt(-1)", ["--at x", "complex"]),
        ("x=log(-1)", ["--at x"]),
        ("x=exp(1000)", ["--at x", "too large"]),
        ("x=1/0", ["--at x", "division by zero"]),
        ("x=__import__('os')", ["--at x", "__import__"]),
        ("x=1==1", ["--at x"]),
    ],
)
def test_point_errors(text, fragments):
    with pytest.raises(PointError) as info:
        parse_point(text, UNICYCLE, option="--at")
    for fragment in fragments:
        assert fragment in str(info.value), str(info.value)


def test_point_errors_name_the_option():
    with pytest.raises(PointError, match=r"^--from: unknown coordinate"):
        parse_point("q=1", UNICYCLE, option="--from")


def test_param_assignments():
    assert parse_param_assignments(["r=1/2", "l=sqrt(2)"]) == {
        "r": sp.Rational(1, 2), "l": sp.sqrt(2)}
    assert parse_param_assignments(["r=1,l=2"]) == {"r": 1, "l": 2}
    assert parse_param_assignments([]) == {}


@pytest.mark.parametrize(
    ("items", "fragment"),
    [
        (["r"], "no '='"),
        (["r="], "empty value"),
        (["r=1", "r=2"], "given twice"),
        (["1r=2"], "not a parameter name"),
        (["r=x"], "unknown name 'x'"),
        (["r=1e999"], "too large"),
    ],
)
def test_param_errors(items, fragment):
    with pytest.raises(ModelError) as info:
        parse_param_assignments(items, option="--param")
    assert str(info.value).startswith("--param")
    assert fragment in str(info.value)


def test_format_point():
    assert format_point(UNICYCLE, (sp.sqrt(3) / 2, sp.Float(0.5), -sp.pi / 3)) == {
        "x": "sqrt(3)/2", "y": "0.5", "theta": "-pi/3"}
    assert format_point(UNICYCLE, UNICYCLE.origin()) == {"x": "0", "y": "0", "theta": "0"}
    with pytest.raises(PointError):
        format_point(UNICYCLE, (0, 0))


_values = st.one_of(
    st.fractions(min_value=-10**6, max_value=10**6, max_denominator=50).map(
        lambda f: sp.Rational(f.numerator, f.denominator)),
    st.floats(min_value=-1e6, max_value=1e6, allow_nan=False).map(sp.Float),
    st.sampled_from([sp.pi / 3, -sp.sqrt(2) / 2, sp.E, sp.atan(sp.Rational(1, 3))]),
)


@settings(max_examples=100, deadline=2000)
@given(st.tuples(_values, _values, _values))
def test_format_then_parse_point_round_trips(point):
    text = ",".join(f"{k}={v}" for k, v in format_point(UNICYCLE, point).items())
    # floats come back as the exact rationals of their shortest decimals
    assert parse_point(text, UNICYCLE) == tuple(exact_decimals(v) for v in point)


@settings(max_examples=300, deadline=2000)
@given(st.text(max_size=60))
def test_fuzz_point_text_raises_only_point_errors(text):
    try:
        point = parse_point(text, UNICYCLE)
    except PointError:
        return
    assert len(point) == 3
    assert all(not v.free_symbols for v in point)
    assert all(math.isfinite(real_value(v)) for v in point)
