"""The one rank engine (core.spans): certified decisions, three answers, scale invariance."""

from __future__ import annotations

import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from nilpotent.core.analysis.filtration import analyze
from nilpotent.core.decide.spans import Decision, MeasuredSpan, Span, ball, is_zero, rank
from nilpotent.core.model.expressions import exact_decimals
from nilpotent.core.model.system import ControlSystem

x1, x2, x3 = sp.symbols("x1 x2 x3")
x, y, th = sp.symbols("x y theta")


def test_exact_zeros_and_certified_nonzeros():
    assert is_zero(sp.Rational(-141, 10**14)) is False
    assert is_zero(sp.sqrt(3) * sp.sqrt(3) - 3) is True
    assert is_zero(sp.cos(sp.pi / 7) - sp.sin(5 * sp.pi / 14)) is True  # cos(a) = sin(pi/2 - a)
    assert is_zero(sp.cos(1) - sp.Rational(54030230586813971, 10**17)) is False
    # a transcendental zero that exact arithmetic cannot see stays undetermined
    assert is_zero(sp.cos(1 + sp.pi / 3) ** 2 + sp.sin(1 + sp.pi / 3) ** 2 - 1) is None


def test_three_answers():
    span = Span()
    assert span.add([1, 2, 3]) is Decision.INDEPENDENT
    assert span.add([2, 4, 6]) is Decision.DEPENDENT
    assert span.add([0, 0, sp.Rational(1, 10**300)]) is Decision.INDEPENDENT
    assert span.rank == 2
    s2 = Span()
    s2.add([sp.cos(1), 1])
    # (2cos(1)^2, 2cos(1) + 10^-400): independent, but only beyond 1024 bits
    assert s2.add([2 * sp.cos(1) ** 2, 2 * sp.cos(1) + sp.Rational(1, 10**400)]) is (
        Decision.UNDETERMINED
    )
    assert rank([[sp.sqrt(2), 1], [2, sp.sqrt(2)]]) == (1, 1)


def test_decimals_are_the_rationals_they_denote():
    assert exact_decimals(sp.Float(0.7)) == sp.Rational(7, 10)
    assert exact_decimals(sp.Float(1e-300) * x) == x / 10**300
    # 0.7, 1.3, 0.9 and 7/10, 13/10, 9/10 give the same exact decision
    assert rank([[sp.Float(0.7), sp.Float(1.3)], [sp.Rational(7, 10), sp.Rational(13, 10)]]) == (
        1, 1)


def test_balls_enclose_the_value():
    b = ball(sp.pi / 7, 200)
    assert (ball(sp.pi, 200) / 7).contains(b)  # the division is done at 53 bits
    assert b.rad() < 2**-190


def test_measured_span_is_relative():
    m = MeasuredSpan()
    assert m.try_add({0: 1e-300, 1: 0.0})
    assert not m.try_add({0: 3e-300, 1: 1e-320})
    assert m.try_add({0: 0.0, 1: 1e300})


SYSTEMS = [
    ControlSystem("unicycle", (x, y, th), ((sp.cos(th), sp.sin(th), 0), (0, 0, 1))),
    ControlSystem("martinet", (x1, x2, x3), ((1, 0, x2**2 / 2), (0, 1, 0))),
    ControlSystem("generic-rank", (x1, x2, x3), ((1, 0, x2**14), (x1, 1, 0))),
    ControlSystem("grushin", (x1, x2), ((1, 0), (0, x1))),
    ControlSystem("planes", (x1, x2, x3), ((1, 0, 0), (0, 1, x1 * 0))),
]


def _verdict(f):
    return f.bracket_generating, f.growth_vector, f.regular


@settings(max_examples=25, deadline=None)
@given(
    st.sampled_from(range(len(SYSTEMS))),
    st.integers(min_value=-300, max_value=300),
    st.lists(st.integers(min_value=-40, max_value=40), min_size=3, max_size=3),
)
def test_scaling_by_powers_of_ten_never_changes_a_verdict(index, k, quarters):
    sys = SYSTEMS[index]
    point = [sp.Rational(q, 4) for q in quarters[: sys.n]]
    scale = sp.Integer(10) ** k
    scaled = ControlSystem(
        sys.name, sys.coordinates, tuple(tuple(scale * e for e in f) for f in sys.fields)
    )
    assert _verdict(analyze(scaled, point)) == _verdict(analyze(sys, point))


@settings(max_examples=25, deadline=None)
@given(
    st.sampled_from(range(len(SYSTEMS))),
    st.lists(st.integers(min_value=-400, max_value=400), min_size=3, max_size=3),
)
def test_writing_fractions_as_decimals_never_changes_a_verdict(index, hundredths):
    sys = SYSTEMS[index]
    exact = [sp.Rational(h, 100) for h in hundredths[: sys.n]]
    decimal = [sp.Float(f"{h / 100:.2f}") for h in hundredths[: sys.n]]
    assert _verdict(analyze(sys, decimal)) == _verdict(analyze(sys, exact))


@pytest.mark.parametrize("k", [-300, -18, 18, 300])
def test_scaled_unicycle_is_bracket_generating(k):
    sys = SYSTEMS[0]
    scaled = ControlSystem(
        "u", sys.coordinates, tuple(tuple(sp.Float(f"1e{k}") * e for e in f) for f in sys.fields)
    )
    f = analyze(scaled)
    assert f.bracket_generating is True and f.growth_vector == (2, 3)
