"""Simulation layer: input signals, trajectories, original-vs-approximation comparisons
and scaling studies, checked against exact loop displacements and hand-computed brackets."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from nilpotent.core.coordinates.approximation import approximate
from nilpotent.errors import OptionError
from nilpotent.models import get_model
from nilpotent.numeric import Status, compile_fields
from nilpotent.numeric.signals import (
    FunctionSignal,
    Signal,
    bracket_signal,
    piecewise_constant,
    sinusoids,
)
from nilpotent.simulation import (
    Comparison,
    ScalingStudy,
    Trajectory,
    compare_bracket_motion,
    scaling_study,
    simulate,
)


def _bracket_at_zero(fields, names, i, j):
    """[X_i, X_j](0) = DX_j·X_i − DX_i·X_j by sympy, 1-based i, j."""
    xi = sp.Matrix(fields[i - 1])
    xj = sp.Matrix(fields[j - 1])
    q = sp.Matrix(names)
    br = xj.jacobian(q) * xi - xi.jacobian(q) * xj
    return np.array([float(v.subs(dict.fromkeys(names, 0))) for v in br])


def test_bracket_signal_formula_and_segment_round_trip():
    sig = bracket_signal(3, 1, 3, 0.2, omega=2.0, periods=2)
    assert sig.duration == pytest.approx(2 * math.pi)
    for t in (0.0, 0.3, 1.7, 5.0):
        np.testing.assert_allclose(
            sig.evaluate(t), [-0.2 * 2 * math.sin(2 * t), 0.0, 0.2 * 2 * math.cos(2 * t)],
            atol=1e-15,
        )
    again = Signal.from_segments(sig.to_segments())
    np.testing.assert_array_equal(again.cos, sig.cos)
    np.testing.assert_array_equal(again.sin, sig.sin)
    with pytest.raises(OptionError):
        bracket_signal(3, 2, 2, 0.1)
    with pytest.raises(OptionError):
        bracket_signal(3, 1, 2, 0.0)


def test_sinusoids_and_piecewise_constant_evaluate():
    sig = sinusoids([1.0, 0.0], [[0.5], []], [[], [0.0, 2.0]], omega=3.0, duration=1.0)
    t = 0.4
    np.testing.assert_allclose(sig.evaluate(t), [1 + 0.5 * math.cos(3 * t), 2 * math.sin(6 * t)])
    pc = piecewise_constant([[1.0, 2.0], [3.0, 4.0]], [0.5, 1.0])
    np.testing.assert_allclose(pc.evaluate(0.2), [1.0, 2.0])
    np.testing.assert_allclose(pc.evaluate(0.9), [3.0, 4.0])
    np.testing.assert_allclose(pc.breakpoints, [0.0, 0.5, 1.5])


def test_simulate_function_input_agrees_with_coefficient_input():
    system = get_model("unicycle")
    sig = bracket_signal(2, 1, 2, 0.3, omega=1.3)
    fn = FunctionSignal(sig.evaluate, 2, sig.duration)
    a = simulate(system, sig, [0.1, 0.0, 0.2], rtol=1e-12, atol=1e-14)
    b = simulate(system, fn, [0.1, 0.0, 0.2], rtol=1e-12, atol=1e-14)
    assert isinstance(a, Trajectory) and a.status == Status.SUCCESS
    np.testing.assert_allclose(a.final, b.final, atol=1e-10)
    np.testing.assert_allclose(a.states, b.states, atol=1e-10)
    _fig, ax = a.plot()
    assert len(ax.lines) == 3


def test_heisenberg_is_its_own_approximation_and_prediction_is_exact():
    comp = compare_bracket_motion(get_model("heisenberg"), (1, 2), 0.3, omega=2.0, periods=2)
    assert isinstance(comp, Comparison)
    # hand: [X1, X2] = ∂3 for X1 = ∂1 − x2/2 ∂3, X2 = ∂2 + x1/2 ∂3
    np.testing.assert_allclose(comp.bracket_value, [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(comp.prediction, [0, 0, 2 * math.pi * 0.09], atol=1e-15)
    np.testing.assert_allclose(comp.final_original, comp.prediction, atol=1e-10)
    assert comp.endpoint_error < 1e-10 and comp.max_error < 1e-10
    assert set(comp.errors_by_weight) == {1, 2}


@pytest.mark.parametrize(("bracket", "periods"), [((1, 2), 1), ((2, 3), 3), ((3, 1), 1)])
def test_nilpotent_loop_moves_exactly_by_area_times_bracket(bracket, periods):
    """For the step-2 nilpotent approximation the loop displacement is exactly
    K·πA²·[X̂_I, X̂_J](0) (weight-2 components are linear in the weight-1 ones)."""
    system = get_model("trident-snake")
    approx = approximate(system.specialized())
    amp = 0.25
    comp = compare_bracket_motion(system, bracket, amp, periods=periods, approximation=approx)
    br = _bracket_at_zero(approx.fields, approx.coordinates.names, *bracket)
    np.testing.assert_allclose(comp.approximate_y[-1], periods * math.pi * amp**2 * br,
                               atol=1e-11)


def test_comparison_in_privileged_coordinates_is_consistent():
    comp = compare_bracket_motion(get_model("unicycle"), (1, 2), 0.1, samples=51)
    assert comp.original.shape == comp.approximate_y.shape == (51, 3)
    # both start at p, i.e. y = 0
    np.testing.assert_allclose(comp.original_y[0], 0, atol=1e-15)
    np.testing.assert_allclose(comp.approximate_y[0], 0, atol=1e-15)
    dist = np.linalg.norm(comp.original - comp.approximate, axis=1)
    assert comp.max_error == pytest.approx(dist.max())
    assert comp.endpoint_error == pytest.approx(dist[-1])
    _fig, axes = comp.plot()
    assert len(axes) == 2


def test_scaling_slopes_on_the_trident_snake():
    """MATH.md §6: the error of weight group w scales like A^(w+1); measured here."""
    study = scaling_study(get_model("trident-snake"), (1, 2), [0.005, 0.01, 0.02, 0.04])
    assert isinstance(study, ScalingStudy)
    assert study.expected_slopes == {1: 2, 2: 3}
    for w, slope in study.slopes.items():
        assert slope is not None
        assert abs(slope - (w + 1)) < 0.1, (w, slope, study.errors[w])
    _fig, ax = study.plot()
    assert ax.get_xscale() == "log"


def test_scaling_slope_is_at_least_the_weight_plus_one_on_the_unicycle():
    study = scaling_study(get_model("unicycle"), (1, 2), [0.01, 0.02, 0.04])
    for w, slope in study.slopes.items():
        assert slope is not None and slope > w + 1 - 0.1


def test_scaling_of_an_exact_approximation_has_no_slope():
    study = scaling_study(get_model("heisenberg"), (1, 2), [0.1, 0.2])
    assert all(s is None for s in study.slopes.values())
    assert all(np.all(e <= study.floor) for e in study.errors.values())


def test_scaling_rejects_bad_amplitudes():
    with pytest.raises(OptionError):
        scaling_study(get_model("unicycle"), (1, 2), [0.1])
    with pytest.raises(OptionError):
        scaling_study(get_model("unicycle"), (1, 2), [0.1, -0.2])


@settings(max_examples=12, deadline=None)
@given(
    amp=st.floats(0.05, 1.0),
    omega=st.floats(0.5, 3.0),
    y0=st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6),
    pair=st.sampled_from([(1, 2), (2, 1), (1, 3), (3, 2)]),
)
def test_nilpotent_loop_displacement_does_not_depend_on_the_start(amp, omega, y0, pair):
    """Step-2 nilpotent fields: ŷ(T) − ŷ(0) = πA²[X̂_I, X̂_J] from any start ŷ(0)."""
    approx = _trident_approximation()
    names = approx.coordinates.names
    compiled = compile_fields(names, approx.fields, name="trident-hat")
    traj = simulate(compiled, bracket_signal(3, *pair, amp, omega), y0, samples=2,
                    engine="scipy", rtol=1e-12, atol=1e-14)
    br = _bracket_at_zero(approx.fields, names, *pair)
    np.testing.assert_allclose(traj.final - np.array(y0), math.pi * amp**2 * br, atol=1e-10)


@functools.lru_cache(maxsize=1)
def _trident_approximation():
    return approximate(get_model("trident-snake").specialized())
