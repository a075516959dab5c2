"""The one control type (numeric/signals.py): plan segments in and out, the array
form against the per-segment values (a second implementation), bracket inputs with
one pair per row, and the loop area of the bracket input (shoelace formula)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nilpotent.errors import OptionError
from nilpotent.numeric.signals import (
    InputSignal,
    Segment,
    Signal,
    bracket_inputs,
    bracket_signal,
    piecewise_constant,
    sinusoids,
)

coef = st.floats(-3, 3, allow_nan=False)


@st.composite
def controls(draw, m=None):
    m = draw(st.integers(1, 3)) if m is None else m
    count = draw(st.integers(1, 3))
    segs = []
    for _ in range(count):
        inputs = tuple(
            InputSignal(draw(coef), tuple(draw(st.lists(coef, max_size=3))),
                        tuple(draw(st.lists(coef, max_size=3))))
            for _ in range(m)
        )
        segs.append(Segment(draw(st.floats(0.1, 3)), draw(st.floats(0.2, 4)), inputs))
    return segs


def _padded(sig: InputSignal, k: int) -> tuple:
    return (sig.constant, tuple(sig.cos) + (0.0,) * (k - len(sig.cos)),
            tuple(sig.sin) + (0.0,) * (k - len(sig.sin)))


@settings(max_examples=40, deadline=None)
@given(controls())
def test_plan_segments_round_trip(segs):
    sig = Signal.from_segments(segs)
    back = sig.segments()
    k = sig.harmonics
    assert len(back) == len(segs)
    for a, b in zip(segs, back, strict=True):
        assert (a.duration, a.omega) == (b.duration, b.omega)
        assert [_padded(i, k) for i in a.inputs] == [_padded(i, k) for i in b.inputs]
    # the dict form (INTERFACE.md) reads back to the same arrays
    again = Signal.from_segments(sig.to_segments())
    for name in ("durations", "omegas", "constant", "cos", "sin"):
        np.testing.assert_array_equal(getattr(sig, name), getattr(again, name))


@settings(max_examples=40, deadline=None)
@given(controls(), st.floats(0, 1))
def test_array_form_agrees_with_segment_values(segs, fraction):
    """Signal.evaluate (arrays, einsum) against Segment.values (a loop per harmonic)."""
    sig = Signal.from_segments(segs)
    t = fraction * sig.duration
    start = 0.0
    for seg in segs:
        if t < start + seg.duration or seg is segs[-1]:  # a boundary starts the next
            expected = seg.values(t - start)
            break
        start += seg.duration
    np.testing.assert_allclose(sig.evaluate(t), expected, atol=1e-12)


def test_stack_is_a_batch_of_the_single_controls():
    rng = np.random.default_rng(1)
    rows = [[Segment(1.0 + b, 2.0, (InputSignal(rng.normal(), (rng.normal(),)),
                                     InputSignal(0.0, (), (rng.normal(), rng.normal()))))]
            for b in range(3)]
    batch = Signal.stack(rows)
    assert batch.batch == 3
    for b, row in enumerate(rows):
        one = Signal.from_segments(row)
        np.testing.assert_allclose(batch[b].evaluate(0.7), one.evaluate(0.7))
    with pytest.raises(OptionError, match="same number of segments"):
        Signal.stack([rows[0], rows[1] * 2])


def test_bracket_inputs_with_one_pair_per_row():
    amps = np.array([0.1, 0.2, 0.3])
    i = np.array([1, 2, 3])
    j = np.array([2, 3, 1])
    rows = bracket_inputs(3, i, j, amps, omega=1.5, periods=2)
    for b in range(3):
        single = bracket_inputs(3, int(i[b]), int(j[b]), amps[b], omega=1.5, periods=2)
        for name in ("durations", "omegas", "constant", "cos", "sin"):
            np.testing.assert_array_equal(getattr(rows, name)[b], getattr(single, name)[0])
    with pytest.raises(OptionError, match="different inputs"):
        bracket_inputs(3, np.array([1, 2]), np.array([2, 2]), [0.1, 0.2])


@pytest.mark.parametrize(("amp", "omega"), [(0.1, 1.0), (0.7, 3.0)])
def test_bracket_loop_encloses_pi_a_squared_counter_clockwise(amp, omega):
    """(∫u_I, ∫u_J) over one period: a closed loop of signed area +πA² (shoelace)."""
    sig = bracket_signal(2, 1, 2, amp, omega=omega)
    t = np.linspace(0.0, sig.duration, 4001)
    u = np.array([sig.evaluate(tk) for tk in t])
    dt = np.diff(t)[:, None]
    path = np.vstack([[0.0, 0.0], np.cumsum((u[1:] + u[:-1]) / 2 * dt, axis=0)])
    np.testing.assert_allclose(path[-1], 0.0, atol=1e-9)
    x, y = path[:, 0], path[:, 1]
    area = 0.5 * np.sum(x[:-1] * y[1:] - x[1:] * y[:-1])
    assert area == pytest.approx(math.pi * amp**2, rel=1e-5)


def test_constructors_refuse_bad_input():
    with pytest.raises(OptionError):
        bracket_signal(2, 1, 2, -0.1)
    with pytest.raises(OptionError):
        piecewise_constant([[1.0, 2.0]], [1.0, 2.0])
    with pytest.raises(OptionError):
        sinusoids([0.0], [[1.0], [2.0]], [[0.0]], 1.0, 1.0)
    with pytest.raises(OptionError, match="missing 'omega'"):
        Signal.from_segments([{"duration": 1.0, "inputs": []}])
    with pytest.raises(OptionError):
        Signal(np.ones((1, 1)), np.ones((1, 1)), np.zeros((1, 1, 2)), np.zeros((1, 1, 2, 1)),
               np.full((1, 1, 2, 1), np.nan))
