"""Batched integrators against closed-form flows, solve_ivp at tight tolerance, and
the convergence order of the fixed-step method (a fitted log–log slope)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

from nilpotent.errors import IntegrationError, OptionError
from nilpotent.models import get_model
from nilpotent.numeric import (
    Signal,
    Status,
    bracket_inputs,
    compile_fields,
    compile_system,
    integrate,
)

numba = pytest.importorskip("numba")

X1, X2, X3 = sp.symbols("x1 x2 x3")
#: Heisenberg: X1 = ∂1 − x2/2 ∂3, X2 = ∂2 + x1/2 ∂3; [X1, X2] = ∂3 (DY·X − DX·Y).
HEIS = compile_fields((X1, X2, X3), [(1, 0, -X2 / 2), (0, 1, X1 / 2)], name="heisenberg-test")


def _piecewise(values, durations):
    values = np.asarray(values, dtype=float)
    s, m = values.shape
    return Signal(
        np.asarray(durations, dtype=float)[None], np.ones((1, s)), values[None],
        np.zeros((1, s, m, 0)), np.zeros((1, s, m, 0)),
    )


@pytest.mark.parametrize(
    ("method", "engine"),
    [("adaptive", "numba"), ("fixed", "numba"), ("fixed", "numpy"), ("adaptive", "scipy")],
)
@pytest.mark.parametrize("periods", [1, 3])
def test_heisenberg_loop_moves_x3_by_pi_a_squared(method, engine, periods):
    """Exact: x3 changes by the signed area ½∮(x1 dx2 − x2 dx1) = K·πA² (x1, x2 return)."""
    amps = np.array([0.05, 0.3, 1.0])
    x0 = np.array([[0.0, 0.0, 0.0], [0.2, -0.1, 0.5], [1.0, 2.0, -3.0]])
    sol = integrate(HEIS, x0, bracket_inputs(2, 1, 2, amps, omega=2.0, periods=periods),
                    method=method, engine=engine, rtol=1e-12, atol=1e-14)
    assert sol.all_ok and sol.engine == engine
    # from x0 = (a, b, c) the loop is a circle in (x1, x2) starting at (a, b):
    # ½∮(x1 dx2 − x2 dx1) does not depend on the start: πA²·K
    expected = x0.copy()
    expected[:, 2] += periods * math.pi * amps**2
    np.testing.assert_allclose(sol.final, expected, atol=1e-10, rtol=0)
    assert sol.tolerance <= 1e-10


def test_unicycle_constant_inputs_closed_form():
    """u = (v, w) constant: θ = θ0 + wt, x = x0 + v/w (sin θ − sin θ0),
    y = y0 − v/w (cos θ − cos θ0)."""
    compiled = compile_system(get_model("unicycle"))
    segs = [(0.7, 0.9, 1.3), (-0.4, 2.0, 0.8), (1.1, -0.5, 2.1)]  # (v, w, duration)
    x = np.array([0.3, -0.2, 0.4])
    expected = x.copy()
    for v, w, d in segs:
        th0 = expected[2]
        th1 = th0 + w * d
        expected = np.array([
            expected[0] + v / w * (math.sin(th1) - math.sin(th0)),
            expected[1] - v / w * (math.cos(th1) - math.cos(th0)),
            th1,
        ])
    inputs = _piecewise([[v, w] for v, w, _ in segs], [d for *_, d in segs])
    for method, engine in [("adaptive", "scipy"), ("fixed", "numpy")]:
        sol = integrate(compiled, x, inputs, method=method, engine=engine, steps=128,
                        rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(sol.final[0], expected, atol=1e-10, rtol=0)


def test_batched_adaptive_matches_tight_solve_ivp_on_the_trident_snake():
    compiled = compile_system(get_model("trident-snake"))
    rng = np.random.default_rng(5)
    n = 40
    amps = rng.uniform(0.01, 0.3, n)
    x0 = rng.uniform(-0.3, 0.3, (n, 6))
    inputs = bracket_inputs(3, 2, 3, amps, omega=1.5)
    times = np.linspace(0, 2 * math.pi / 1.5, 7)
    ours = integrate(compiled, x0, inputs, engine="numba", times=times)
    ref = integrate(compiled, x0[:8], Signal(
        inputs.durations[:8], inputs.omegas[:8], inputs.constant[:8], inputs.cos[:8],
        inputs.sin[:8]), engine="scipy", times=times, rtol=1e-13, atol=1e-15)
    assert ours.all_ok and ref.all_ok
    np.testing.assert_allclose(ours.final[:8], ref.final, atol=1e-9, rtol=0)
    np.testing.assert_allclose(ours.samples[:8], ref.samples, atol=1e-9, rtol=0)
    np.testing.assert_allclose(ours.samples[:, 0], x0)
    np.testing.assert_allclose(ours.samples[:, -1], ours.final)


def test_fixed_step_convergence_order_is_eight():
    """Errors against a tight reference for N = 12..32 steps: fitted slope ≈ −8."""
    compiled = compile_system(get_model("unicycle"))
    inputs = bracket_inputs(2, 1, 2, [1.2], omega=1.0, periods=1)
    x0 = np.array([[0.1, 0.2, 0.3]])
    ref = integrate(compiled, x0, inputs, engine="scipy", rtol=1e-13, atol=1e-15).final
    ns = np.array([12, 16, 24, 32])
    errs = []
    for n in ns:
        sol = integrate(compiled, x0, inputs, method="fixed", engine="numpy", steps=int(n))
        errs.append(np.abs(sol.final - ref).max())
        if n == 24:
            # in the asymptotic range the step-halving estimate is of the right size
            true = errs[-1]
            assert true / 5 < sol.error_estimate[0] < true * 5
    slope = np.polyfit(np.log(ns), np.log(errs), 1)[0]
    assert -9.0 < slope < -7.0, (slope, errs)


def test_numba_and_numpy_fixed_step_agree_to_rounding():
    compiled = compile_system(get_model("heisenberg"))
    rng = np.random.default_rng(7)
    x0 = rng.normal(size=(5, 3))
    inputs = bracket_inputs(2, 2, 1, rng.uniform(0.1, 1, 5), omega=0.7, periods=2)
    times = np.linspace(0, 4 * math.pi / 0.7, 9)
    a = integrate(compiled, x0, inputs, method="fixed", engine="numba", steps=16, times=times)
    b = integrate(compiled, x0, inputs, method="fixed", engine="numpy", steps=16, times=times)
    np.testing.assert_allclose(a.final, b.final, atol=1e-13)
    np.testing.assert_allclose(a.samples, b.samples, atol=1e-13)
    assert a.steps.tolist() == b.steps.tolist()


@pytest.mark.parametrize(("method", "engine"),
                         [("adaptive", "numba"), ("fixed", "numba"), ("fixed", "numpy"),
                          ("adaptive", "scipy")])
def test_blow_up_is_reported_not_raised(method, engine):
    """dx/dt = u x² with u = 1 from x = 1 blows up at t = 1 (x = 1/(1 − t))."""
    x = sp.Symbol("x")
    compiled = compile_fields((x,), [(x**2,)], name="riccati")
    inputs = _piecewise([[1.0], [1.0]], [0.5, 1.5])
    sol = integrate(compiled, [[1.0], [-1.0]], inputs, method=method, engine=engine,
                    bound=1e6, steps=4000)
    assert Status(int(sol.status[0])) in (Status.BLOW_UP, Status.STEP_TOO_SMALL,
                                          Status.MAX_STEPS, Status.NON_FINITE)
    assert not sol.ok[0]
    # x = −1 decays: x(2) = −1/(1 + 2) = −1/3
    assert sol.ok[1]
    assert abs(sol.final[1, 0] + 1 / 3) < 1e-8
    with pytest.raises(IntegrationError):
        sol.raise_for_status()


def test_leaving_the_bound_stops_the_batched_trajectory():
    sol = integrate(HEIS, np.zeros((2, 3)), bracket_inputs(2, 1, 2, [0.1, 2.0]),
                    engine="numba", bound=1.0)
    assert sol.status.tolist() == [Status.SUCCESS, Status.BLOW_UP]
    assert np.abs(sol.final[1]).max() > 1.0


def test_max_steps_stops_the_trajectory():
    sol = integrate(HEIS, np.zeros((2, 3)), bracket_inputs(2, 1, 2, [0.1, 0.2]),
                    engine="numba", max_steps=3)
    assert np.all(sol.status == Status.MAX_STEPS)


def test_option_errors():
    inputs = bracket_inputs(2, 1, 2, [0.1])
    with pytest.raises(OptionError):
        integrate(HEIS, np.zeros(3), inputs, method="euler")
    with pytest.raises(OptionError):
        integrate(HEIS, np.zeros(3), inputs, method="adaptive", engine="numpy")
    with pytest.raises(OptionError):
        integrate(HEIS, np.zeros(3), inputs, times=[0.0, 100.0])
    with pytest.raises(OptionError):
        integrate(HEIS, np.zeros(4), inputs)
    with pytest.raises(OptionError):
        integrate(HEIS, np.zeros(3), inputs, method="fixed", steps=7)
    with pytest.raises(OptionError):
        bracket_inputs(2, 1, 1, [0.1])


def test_samples_across_segments_agree_between_engines():
    """Three segments (constant, then sinusoids), samples on and between the boundaries."""
    rng = np.random.default_rng(11)
    batch = 3
    durations = np.tile([0.7, 1.1, 0.5], (batch, 1))
    omegas = np.tile([1.0, 2.5, 4.0], (batch, 1))
    constant = rng.normal(size=(batch, 3, 2))
    cos = rng.normal(size=(batch, 3, 2, 2))
    sin = rng.normal(size=(batch, 3, 2, 2))
    cos[:, 0] = sin[:, 0] = 0.0
    inputs = Signal(durations, omegas, constant, cos, sin)
    x0 = rng.normal(size=(batch, 3))
    times = np.array([0.0, 0.3, 0.7, 1.0, 1.8, 2.0, 2.3])
    ref = integrate(HEIS, x0, inputs, engine="scipy", times=times, rtol=1e-13, atol=1e-15)
    for method, engine in [("adaptive", "numba"), ("fixed", "numba"), ("fixed", "numpy")]:
        sol = integrate(HEIS, x0, inputs, method=method, engine=engine, times=times,
                        rtol=1e-12, atol=1e-14, steps=64)
        np.testing.assert_allclose(sol.samples, ref.samples, atol=1e-10, err_msg=engine)
        np.testing.assert_allclose(sol.final, ref.samples[:, -1], atol=1e-10)


@pytest.mark.parametrize(("method", "engine"),
                         [("adaptive", "numba"), ("fixed", "numba"), ("adaptive", "scipy")])
def test_a_singular_field_gives_a_status_not_an_exception(method, engine):
    """dx/dt = u/x from x = 0: the field is infinite at the start."""
    x = sp.Symbol("x")
    compiled = compile_fields((x,), [(1 / x,)], name="singular")
    inputs = _piecewise([[1.0]], [1.0])
    sol = integrate(compiled, [[0.0], [1.0]], inputs, method=method, engine=engine,
                    max_steps=2000, steps=256)
    assert not sol.ok[0]
    # from x = 1: x² = 1 + 2t, so x(1) = sqrt(3)
    assert sol.ok[1] and abs(sol.final[1, 0] - math.sqrt(3)) < 1e-8


@pytest.mark.parametrize(("engine", "method"), [("numba", "adaptive"), ("numba", "fixed"),
                                                ("heyoka", "adaptive"), ("scipy", "adaptive"),
                                                ("numpy", "fixed"), ("auto", "adaptive")])
def test_an_empty_batch_gives_an_empty_solution(engine, method):
    # no initial states: nothing to integrate, every array has 0 rows and the right shape
    from nilpotent.numeric.engines import ENGINES

    if engine != "auto" and not ENGINES[engine].available():
        pytest.skip(f"{engine} not installed")
    cs = compile_system(get_model("trident-snake"))
    sol = integrate(cs, np.zeros((0, 6)), bracket_inputs(3, 1, 2, np.zeros(0)),
                    engine=engine, method=method, times=[0.0, 1.0])
    assert sol.final.shape == (0, 6) and sol.samples.shape == (0, 2, 6)
    assert sol.status.shape == sol.steps.shape == (0,) and sol.all_ok


@pytest.mark.parametrize(("engine", "method"), [("numba", "adaptive"), ("numba", "fixed"),
                                                ("heyoka", "adaptive"), ("scipy", "adaptive"),
                                                ("numpy", "fixed")])
def test_a_sample_time_a_rounding_past_the_end_is_the_end(engine, method):
    # a time within the allowed 1e-12 slack past the duration (e.g. a sum of segment
    # durations rounded up) is the end: its sample is the end point on every engine (NaN
    # on some engines before), and the reported time is the duration
    from nilpotent.numeric.engines import ENGINES

    if not ENGINES[engine].available():
        pytest.skip(f"{engine} not installed")
    cs = compile_system(get_model("trident-snake"))
    sig = bracket_inputs(3, 1, 2, np.full(3, 0.1))
    end = float(sig.total_durations.min())
    sol = integrate(cs, np.zeros((3, 6)), sig, engine=engine, method=method,
                    times=[0.0, end * (1 + 5e-13)])
    assert sol.all_ok and sol.times[-1] == end
    np.testing.assert_array_equal(sol.samples[:, -1], sol.final)
