"""Attacks on the heyoka engine: singular fields, non-finite starts, batch-mates that fail.

Each test asserts a promise of :mod:`nilpotent.numeric.engines.heyoka_engine`
against a closed-form solution, a second engine, or the same trajectory
integrated alone (a trajectory's result does not depend on its batch, bit for
bit).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nilpotent.models import get_model
from nilpotent.numeric import Signal, Status, bracket_inputs, compile_fields, compile_system
from nilpotent.numeric import integrate as _integrate

pytest.importorskip("heyoka")


def integrate(*args, **kwargs):
    kwargs.setdefault("engine", "heyoka")
    return _integrate(*args, **kwargs)


def _sinusoid(constant, omega, cos, duration=1.0):
    """One segment per row, one input per row entry: ``u_i = a_i + b_i cos(ω τ)``."""
    constant = np.atleast_2d(np.asarray(constant, dtype=float))  # (B, m)
    b, m = constant.shape
    cos = np.broadcast_to(np.asarray(cos, dtype=float), (b, m))
    omega = np.broadcast_to(np.asarray(omega, dtype=float).reshape(-1, 1), (b, 1))
    return Signal(np.full((b, 1), duration), np.array(omega), constant[:, None, :],
                  cos[:, None, :, None], np.zeros((b, 1, m, 1)))


def _same(a, b):
    return np.array_equal(a, b, equal_nan=True)


def _assert_alone_equals(sol, system, x0, sig, rows, **kwargs):
    """Rows of ``sol`` equal, bit for bit, those rows integrated alone."""
    for r in rows:
        one = integrate(system, x0[r:r + 1], sig[r:r + 1], **kwargs)
        assert one.status[0] == sol.status[r], r
        assert one.steps[0] == sol.steps[r], r
        assert _same(one.final[0], sol.final[r]), r
        assert _same(one.samples[0], sol.samples[r]), r


@pytest.fixture(scope="module")
def snake():
    return compile_system(get_model("trident-snake"))


def test_a_field_singular_where_a_held_coordinate_is_zero_in_a_batch_of_one():
    # x' = u1 cos(x)/y, y' = u2 with u2 = 0: y is held (a parameter) at 1 and
    # x' = cos x, x(t) = gd(t) = 2 atan(tanh(t/2)).  The spare SIMD lanes of the batch of one
    # used to get y = 0 (0·cos(x)/0 = NaN), which stopped heyoka's whole SIMD batch and
    # raised "one of the current times is not finite"
    x, y = sp.symbols("x y")
    cs = compile_fields([x, y], [[sp.cos(x) / y, 0], [0, 1]], name="attack-held-singular")
    sig = Signal(np.full((1, 1), 3.0), np.ones((1, 1)), np.array([[[1.0, 0.0]]]),
                 np.zeros((1, 1, 2, 0)), np.zeros((1, 1, 2, 0)))
    sol = integrate(cs, [[0.0, 1.0]], sig, rtol=1e-12, atol=1e-14, times=[0.0, 1.5, 3.0])
    assert sol.all_ok
    assert sol.final[0, 1] == 1.0
    assert sol.final[0, 0] == pytest.approx(2 * math.atan(math.tanh(1.5)), abs=1e-11)
    assert sol.samples[0, 1, 0] == pytest.approx(2 * math.atan(math.tanh(0.75)), abs=1e-11)


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("column", [0, 2])
def test_a_non_finite_start_in_a_partial_simd_batch_is_reported_not_raised(snake, value, column):
    # column 2 (θ) is held under [X1, X2] motions when finite; a non-finite start is
    # integrated in full and fails; the spare lanes of the partial SIMD batch copied it
    # and heyoka raised instead of reporting NON_FINITE
    rng = np.random.default_rng(11)
    x0 = rng.uniform(-0.1, 0.1, (3, 6))
    x0[1, column] = value
    sig = bracket_inputs(3, 1, 2, np.array([0.1, 0.2, 0.15]))
    sol = integrate(snake, x0, sig, times=[0.0, 1.0])
    assert Status(int(sol.status[1])) == Status.NON_FINITE
    assert np.all(sol.status[[0, 2]] == Status.SUCCESS)
    assert np.all(np.isnan(sol.samples[1, 1]))
    ref = _integrate(snake, x0[[0, 2]], sig[np.array([0, 2])], engine="scipy", rtol=1e-12,
                     atol=1e-14)
    assert np.abs(sol.final[[0, 2]] - ref.final).max() < 1e-9
    _assert_alone_equals(sol, snake, x0, sig, [0, 2], times=[0.0, 1.0])


def test_a_lane_stopped_at_a_singular_point_does_not_stop_the_others():
    # x' = u/x with u = -1 + cos(ωτ)/2: x² = x0² - 2t + sin(ωt)/ω.  x0 = 1 reaches 0 (non-finite)
    # before t = 1 while the others (many steps: ω large) are still on their way; the
    # stopped lane used to be parked at x = 0, where 0·(1/0) is NaN: heyoka then refused to go on
    x = sp.Symbol("x")
    cs = compile_fields([x], [[1 / x]], name="attack-inverse")
    omega = np.array([1.0, 2000.0, 2000.0])
    x0 = np.array([[1.0], [2.0], [3.0]])
    sig = _sinusoid(np.full((3, 1), -1.0), omega, 0.5)
    sol = integrate(cs, x0, sig, rtol=1e-12, atol=1e-14)
    assert Status(int(sol.status[0])) in (Status.NON_FINITE, Status.BLOW_UP)
    assert np.all(sol.status[1:] == Status.SUCCESS)
    exact = np.sqrt(x0[1:, 0] ** 2 - 2 + np.sin(omega[1:]) / omega[1:])
    np.testing.assert_allclose(sol.final[1:, 0], exact, rtol=1e-10)
    _assert_alone_equals(sol, cs, x0, sig, [1, 2], rtol=1e-12, atol=1e-14)


def test_spare_lanes_copy_a_trajectory_whose_field_overflows():
    # x' = 1/x from x0 = 1e-300: the Taylor coefficients overflow at once (NON_FINITE); the
    # spare lanes of the batch of two copied it and stopped the good row's lane for ever
    x = sp.Symbol("x")
    cs = compile_fields([x], [[1 / x]], name="attack-inverse")
    x0 = np.array([[1e-300], [1.0]])
    sig = _sinusoid(np.full((2, 1), 0.5), 1.0, 0.0)
    sol = integrate(cs, x0, sig, rtol=1e-12, atol=1e-14)
    assert sol.status[0] != Status.SUCCESS and sol.status[1] == Status.SUCCESS
    assert sol.final[1, 0] == pytest.approx(math.sqrt(2.0), rel=1e-11)  # x² = 1 + t


def test_max_steps_is_counted_per_trajectory_not_per_simd_batch():
    # x' = cos(ωτ): x(t) = sin(ωt)/ω.  Row 0 (ω = 300) needs far more steps than row 1 (ω = 1);
    # with max_steps just below row 0's count, row 0 fails and row 1 succeeds, as alone.
    # Row 1 used to be stopped (MAX_STEPS) by the SIMD batch's step limit spent by row 0
    x = sp.Symbol("x")
    cs = compile_fields([x], [[sp.Integer(1)]], name="attack-clock")
    sig = _sinusoid(np.zeros((2, 1)), np.array([300.0, 1.0]), 1.0)
    x0 = np.zeros((2, 1))
    ts = [0.5, 0.75]
    free = integrate(cs, x0, sig, times=ts)
    assert free.all_ok and free.steps[0] > 10 * free.steps[1]
    sol = integrate(cs, x0, sig, times=ts, max_steps=int(free.steps[0]) - 1)
    assert Status(int(sol.status[0])) == Status.MAX_STEPS
    assert Status(int(sol.status[1])) == Status.SUCCESS
    assert sol.final[1, 0] == pytest.approx(math.sin(1.0), abs=1e-12)
    np.testing.assert_allclose(sol.samples[1, :, 0], np.sin(ts), atol=1e-12)
    _assert_alone_equals(sol, cs, x0, sig, [0, 1], times=ts, max_steps=int(free.steps[0]) - 1)


def test_blow_up_state_does_not_depend_on_a_failing_batch_mate():
    # x' = u x², x(t) = 1/(1 - ∫u).  Row 0 (u ≈ 0.9) passes bound = 3 at t ≈ 0.74 and ends at
    # x ≈ 10 (BLOW_UP, reported at its end); row 1 (u ≈ 1.2) overflows near t = 0.83 while
    # row 0 is still on its way (both need many steps: ω = 5000).  Row 0 used to be judged
    # when row 1 stopped the SIMD batch: BLOW_UP at x ≈ 7.2, other steps than alone
    x = sp.Symbol("x")
    cs = compile_fields([x], [[x**2]], name="attack-riccati")
    sig = _sinusoid(np.array([[0.9], [1.2]]), 5000.0, 0.01)
    x0 = np.ones((2, 1))
    sol = integrate(cs, x0, sig, bound=3.0)
    assert Status(int(sol.status[0])) == Status.BLOW_UP
    assert Status(int(sol.status[1])) in (Status.NON_FINITE, Status.BLOW_UP)
    exact = 1 / (1 - 0.9 - 0.01 * math.sin(5000.0) / 5000.0)
    assert sol.final[0, 0] == pytest.approx(exact, rel=1e-8)
    _assert_alone_equals(sol, cs, x0, sig, [0], bound=3.0)


# --- properties: a trajectory's result does not depend on its batch or on the threads ---

_MASKS = ((1, 1, 0), (1, 0, 1), (0, 1, 1), (1, 1, 1), (0, 0, 0))  # inputs in use per row
_SPECIAL = (np.nan, np.inf, -np.inf, 5e8, -2e9)  # start values that fail (bound 1e8)


@st.composite
def _batches(draw):
    """A trident snake batch: rows with different inputs in use (some hold θ), several
    segments with per-row durations, K = 0 or 1, start values with NaN/inf/huge entries."""
    b = draw(st.integers(1, 11))
    segs = draw(st.integers(1, 3))
    k = draw(st.sampled_from((0, 1)))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    masks = np.array([_MASKS[i] for i in draw(
        st.lists(st.integers(0, len(_MASKS) - 1), min_size=b, max_size=b))], dtype=float)
    durations = rng.uniform(0.3, 1.2, (b, segs))
    if draw(st.booleans()):
        durations[:] = durations[0]
    scale = masks[:, None, :]
    if k == 0:
        sig = Signal(durations, rng.uniform(0.5, 3.0, (b, segs)),
                     rng.normal(0, 0.7, (b, segs, 3)) * scale,
                     np.zeros((b, segs, 3, 0)), np.zeros((b, segs, 3, 0)))
    else:
        sig = Signal(durations, rng.uniform(0.5, 3.0, (b, segs)), np.zeros((b, segs, 3)),
                     rng.normal(0, 0.7, (b, segs, 3, 1)) * scale[..., None],
                     rng.normal(0, 0.7, (b, segs, 3, 1)) * scale[..., None])
    x0 = rng.uniform(-1.0, 1.0, (b, 6))
    for _ in range(draw(st.integers(0, 2))):
        x0[draw(st.integers(0, b - 1)), draw(st.sampled_from((0, 2, 4)))] = draw(
            st.sampled_from(_SPECIAL))
    total = float(sig.total_durations.min())
    ts = np.sort(rng.uniform(0.0, total, draw(st.integers(0, 3))))
    if draw(st.booleans()):
        ts = np.concatenate([[0.0], ts, [total]])
    return x0, sig, ts


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(case=_batches(), threads=st.sampled_from((1, 2, 3, 7)),
       max_steps=st.sampled_from((100_000, 40, 15)))
def test_each_row_is_bit_identical_alone_permuted_and_on_any_thread_count(
        snake, case, threads, max_steps):
    x0, sig, ts = case
    kw = dict(times=ts, max_steps=max_steps)
    sol = integrate(snake, x0, sig, threads=threads, **kw)
    perm = np.random.default_rng(0).permutation(x0.shape[0])
    back = np.argsort(perm)
    mixed = integrate(snake, x0[perm], sig[perm], threads=1, **kw)
    np.testing.assert_array_equal(mixed.status[back], sol.status)
    np.testing.assert_array_equal(mixed.steps[back], sol.steps)
    assert _same(mixed.final[back], sol.final) and _same(mixed.samples[back], sol.samples)
    _assert_alone_equals(sol, snake, x0, sig, range(x0.shape[0]), threads=threads, **kw)
    # held coordinates are reported as their start values; NaN past a stop everywhere
    bad = ~np.all(np.abs(x0) <= 1e8, axis=1)
    assert np.all(sol.status[bad] != Status.SUCCESS)
    # (a sample at time 0 is the start state itself, NaN coordinates included)
    stopped = sol.status != Status.SUCCESS
    later = np.asarray(ts) > 0
    after = sol.samples[stopped][:, later]
    assert np.all(np.isnan(after).all(axis=2) | ~np.isnan(after).any(axis=2))
    assert _same(sol.samples[:, ~later], np.repeat(x0[:, None], int((~later).sum()), axis=1))


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(case=_batches())
def test_finite_rows_agree_with_solve_ivp(snake, case):
    x0, sig, ts = case
    ok = np.all(np.abs(x0) <= 1.0, axis=1)
    if not ok.any():
        return
    x0, sig = x0[ok], sig[np.flatnonzero(ok)]
    hy = integrate(snake, x0, sig, times=ts, rtol=1e-12, atol=1e-14)
    ref = _integrate(snake, x0, sig, engine="scipy", times=ts, rtol=1e-13, atol=1e-15)
    assert hy.all_ok and ref.all_ok
    assert np.abs(hy.final - ref.final).max() < 1e-9
    if ts.size:
        assert np.abs(hy.samples - ref.samples).max() < 1e-9


@pytest.mark.parametrize("max_steps", range(1, 13))
def test_a_lane_that_reaches_its_event_on_the_last_allowed_step_is_not_stopped(max_steps):
    # x' = cos(ωτ) with a sample at 0.5: row 0 (ω = 1) needs a few steps per event, row 1
    # (ω = 300) many.  When the SIMD batch's step limit (spent by row 1) falls on the step
    # where row 0 reaches its event, heyoka reports step_limit for row 0 too; row 0 used to
    # be stopped there (MAX_STEPS) although alone it goes on.  Every max_steps: as alone
    x = sp.Symbol("x")
    cs = compile_fields([x], [[sp.Integer(1)]], name="attack-clock")
    sig = _sinusoid(np.zeros((2, 1)), np.array([1.0, 300.0]), 1.0)
    x0 = np.zeros((2, 1))
    sol = integrate(cs, x0, sig, times=[0.5], max_steps=max_steps)
    assert Status(int(sol.status[1])) == Status.MAX_STEPS
    _assert_alone_equals(sol, cs, x0, sig, [0], times=[0.5], max_steps=max_steps)
    if sol.status[0] == Status.SUCCESS:
        assert sol.final[0, 0] == pytest.approx(math.sin(1.0), abs=1e-12)


def test_a_lane_stopped_on_the_step_where_another_switches_segment():
    # x' = u x, u = 1: x = x0 e^t.  Row 0 starts at NaN (stopped on the first step, its time
    # NaN); row 1 reaches the end of its short first segment on that same step and switches
    # to its second segment: resetting the lanes' times used to choke on the stopped lane's
    x = sp.Symbol("x")
    cs = compile_fields([x], [[x]], name="attack-linear")
    sig = Signal(np.array([[1e-3, 1.0], [1e-3, 1.0]]), np.ones((2, 2)), np.ones((2, 2, 1)),
                 np.zeros((2, 2, 1, 0)), np.zeros((2, 2, 1, 0)))
    x0 = np.array([[np.nan], [1.0]])
    sol = integrate(cs, x0, sig, rtol=1e-12, atol=1e-14, times=[0.5])
    assert Status(int(sol.status[0])) == Status.NON_FINITE
    assert Status(int(sol.status[1])) == Status.SUCCESS
    assert sol.final[1, 0] == pytest.approx(math.exp(1.001), rel=1e-11)
    assert sol.samples[1, 0, 0] == pytest.approx(math.exp(0.5), rel=1e-11)
    _assert_alone_equals(sol, cs, x0, sig, [1], rtol=1e-12, atol=1e-14, times=[0.5])


def test_a_batch_mate_that_fails_early_does_not_change_the_rounding_of_the_others():
    # car with 3 trailers, two segments, one sample (a case found by fuzzing): row 0 starts at
    # NaN and stops heyoka's SIMD batch on its first step, while row 1 is on its way.  A lane
    # restarted mid-way is not bit-identical (heyoka's compensated sums start afresh): row 1
    # runs again from its event, so its result is that of row 1 alone, bit for bit
    cs = compile_system(get_model("car-trailers:3"))
    x0 = np.array([[0.88874924243701892, 0.11516956254556887, np.nan, 0.70339137057761003,
                    0.60400509226418331, 2e8],
                   [0.16954946103343294, 0.84594594120185640, -0.84413504432806974,
                    -0.70955379875492519, -0.86191594156282281, -0.48589300453514395]])
    sig = Signal(np.array([[0.9938550141792146, 0.9846212196186666],
                           [0.36111697365462203, 0.34485492167350423]]), np.ones((2, 2)),
                 np.array([[[0.4643927400845625, 0.8049064106704379],
                            [0.7061863784484994, -0.6240804522201474]],
                           [[-0.6670222476464329, 1.8617551804263492],
                            [0.04770161022755551, 0.15898070591802993]]]),
                 np.zeros((2, 2, 2, 0)), np.zeros((2, 2, 2, 0)))
    ts = [0.47160614719774424]
    sol = integrate(cs, x0, sig, times=ts)
    assert Status(int(sol.status[0])) == Status.NON_FINITE and sol.status[1] == Status.SUCCESS
    _assert_alone_equals(sol, cs, x0, sig, [1], times=ts)


def test_a_sample_at_the_end_is_the_end_point_on_the_lean_and_the_general_path(snake):
    # one trajectory (a case found by fuzzing), samples at 0 and at the end: 8 copies fill a
    # SIMD batch (the lean loop); alone it takes the general path.  A lane already at the
    # sample's time used to be propagated again on the general path (heyoka took a tiny step:
    # its double-length time missed the end by an ulp): one more step and a sample an ulp off
    # the end point, unlike the same trajectory on the lean path
    x0 = np.array([[-0.8585907222500928, 0.04743562701511905, 0.9680224146953444,
                    -0.5806349490472504, -0.9775214899820464, -0.9210580813606837]])
    end = 1.3534222450157285
    sig = Signal(np.array([[end]]), np.array([[1.4202906434977842]]),
                 np.array([[[0.0, 1.1043491637529932, 0.48859695301560074]]]),
                 np.array([[[[0.0], [1.1339476656554355], [-0.44291634251438367]]]]),
                 np.array([[[[0.0], [0.18999962497042805], [-0.09322356445125386]]]]))
    ts = [0.0, end]
    lean = integrate(snake, np.repeat(x0, 8, axis=0), sig.broadcast(8), times=ts, bound=4.0)
    alone = integrate(snake, x0, sig, times=ts, bound=4.0)
    assert lean.all_ok and alone.all_ok
    np.testing.assert_array_equal(lean.samples[:, 1], lean.final)
    np.testing.assert_array_equal(alone.samples[:, 1], alone.final)
    np.testing.assert_array_equal(lean.final[0], alone.final[0])
    assert lean.steps[0] == alone.steps[0]
