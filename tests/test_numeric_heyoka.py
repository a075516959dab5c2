"""The heyoka engine against solve_ivp and against closed-form solutions."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from nilpotent.errors import MissingExtraError
from nilpotent.models import get_model
from nilpotent.numeric import (
    Signal,
    Status,
    bracket_inputs,
    compile_fields,
    compile_system,
    integrate,
)
from nilpotent.numeric.engines import heyoka_engine
from nilpotent.numeric.engines.base import compiled_memo

pytest.importorskip("heyoka")


def _constant_input(value: float) -> Signal:
    """One input, one segment of duration 1, ``u = value``."""
    return Signal(np.ones((1, 1)), np.ones((1, 1)), np.full((1, 1, 1), value),
                          np.zeros((1, 1, 1, 0)), np.zeros((1, 1, 1, 0)))


@pytest.fixture(scope="module")
def snake():
    return compile_system(get_model("trident-snake"))


def test_bracket_motion_matches_solve_ivp(snake):
    # 11 trajectories: one full SIMD batch and a padded one (for batch sizes <= 8)
    rng = np.random.default_rng(1)
    amps = rng.uniform(0.01, 0.3, 11)
    x0 = rng.uniform(-0.1, 0.1, (11, 6))
    inputs = bracket_inputs(3, 1, 2, amps)
    hy = integrate(snake, x0, inputs, engine="heyoka", rtol=1e-12, atol=1e-14)
    ref = integrate(snake, x0, inputs, engine="scipy", rtol=1e-13, atol=1e-15)
    assert hy.engine == "heyoka" and hy.all_ok and ref.all_ok
    assert np.abs(hy.final - ref.final).max() < 1e-10
    assert np.all(hy.steps > 0) and np.all(hy.rejected == 0)


def test_segments_and_samples_match_solve_ivp(snake):
    rng = np.random.default_rng(2)
    b, s, k = 5, 3, 2
    inputs = Signal(
        rng.uniform(0.5, 1.5, (b, s)), rng.uniform(0.5, 2.0, (b, s)),
        rng.normal(0, 0.3, (b, s, 3)), rng.normal(0, 0.3, (b, s, 3, k)),
        rng.normal(0, 0.3, (b, s, 3, k)),
    )
    x0 = rng.uniform(-0.1, 0.1, (b, 6))
    ts = np.linspace(0.0, float(inputs.total_durations.min()), 6)
    hy = integrate(snake, x0, inputs, engine="heyoka", times=ts, rtol=1e-12, atol=1e-14)
    ref = integrate(snake, x0, inputs, engine="scipy", times=ts, rtol=1e-13, atol=1e-15)
    assert hy.all_ok
    assert np.abs(hy.final - ref.final).max() < 1e-10
    assert np.abs(hy.samples - ref.samples).max() < 1e-10
    np.testing.assert_array_equal(hy.samples[:, 0], x0)


def test_blow_up_stops_only_its_lane():
    # dx/dt = u x^2 with u = 1: x(t) = x0 / (1 - x0 t) blows up at t = 1/x0
    x = sp.Symbol("x")
    cs = compile_fields([x], [[x**2]], name="riccati")
    x0 = np.array([[0.1], [0.2], [2.0], [0.3]])  # t = 1 is past 1/2.0 only
    sol = integrate(cs, x0, _constant_input(1.0), engine="heyoka", rtol=1e-12, atol=1e-12,
                    bound=1e6)
    assert Status(int(sol.status[2])) in (Status.BLOW_UP, Status.NON_FINITE)
    good = [0, 1, 3]
    assert np.all(sol.status[good] == Status.SUCCESS)
    exact = x0[good, 0] / (1 - x0[good, 0])
    np.testing.assert_allclose(sol.final[good, 0], exact, rtol=1e-10)


def test_max_steps_is_reported(snake):
    sol = integrate(snake, np.zeros((3, 6)), bracket_inputs(3, 1, 2, 0.2), engine="heyoka",
                    max_steps=2)
    assert np.all(sol.status == Status.MAX_STEPS)
    with pytest.raises(Exception, match="too many steps"):
        sol.raise_for_status()


def test_missing_heyoka_names_the_install(monkeypatch):
    x = sp.Symbol("x")
    cs = compile_fields([x], [[sp.Integer(1)]], name="fresh")  # nothing compiled yet
    monkeypatch.setattr(heyoka_engine, "heyoka_available", lambda: False)
    with pytest.raises(MissingExtraError, match="pip install"):
        integrate(cs, np.zeros((1, 1)), _constant_input(1.0), engine="heyoka")


def test_threads_give_the_same_end_points(snake):
    rng = np.random.default_rng(3)
    x0 = rng.uniform(-0.1, 0.1, (20, 6))
    inputs = bracket_inputs(3, 2, 3, rng.uniform(0.01, 0.3, 20))
    one = integrate(snake, x0, inputs, engine="heyoka", threads=1)
    two = integrate(snake, x0, inputs, engine="heyoka", threads=2)
    np.testing.assert_array_equal(one.final, two.final)
    np.testing.assert_array_equal(one.steps, two.steps)


def test_a_trajectory_does_not_depend_on_its_batch(snake):
    # rows with brackets (1,2) and (2,3) mixed in one batch (two specialised integrators)
    # give bit-identical end points to the same rows integrated in batches of their own
    rng = np.random.default_rng(8)
    x0 = rng.uniform(-0.1, 0.1, (30, 6))
    amps = rng.uniform(0.01, 0.3, 30)
    ii = np.where(np.arange(30) % 3 == 0, 2, 1)
    jj = np.where(np.arange(30) % 3 == 0, 3, 2)
    mixed = integrate(snake, x0, bracket_inputs(3, ii, jj, amps), engine="heyoka")
    for i, j in ((1, 2), (2, 3)):
        rows = np.flatnonzero(ii == i)
        alone = integrate(snake, x0[rows], bracket_inputs(3, i, j, amps[rows]),
                          engine="heyoka")
        np.testing.assert_array_equal(mixed.final[rows], alone.final)


def test_threads_identical_with_failures_and_many_batches():
    # dx/dt = u x^2 blows up at t = 1/x0: lanes with x0 > 1 fail in several SIMD batches,
    # the others succeed; 1, 2 and 3 threads give bit-identical end points and steps
    x = sp.Symbol("x")
    cs = compile_fields([x], [[x**2]], name="riccati-threads")
    rng = np.random.default_rng(4)
    x0 = rng.uniform(0.05, 0.9, (203, 1))
    x0[::17, 0] = 2.0  # blow-up before t = 1
    runs = [integrate(cs, x0, _constant_input(1.0).broadcast(203), engine="heyoka",
                      rtol=1e-12, atol=1e-12, bound=1e6, threads=t) for t in (1, 2, 3)]
    fails = np.zeros(203, dtype=bool)
    fails[::17] = True
    for sol in runs:
        assert np.all(sol.status[fails] != Status.SUCCESS)
        assert np.all(sol.status[~fails] == Status.SUCCESS)
        np.testing.assert_allclose(sol.final[~fails, 0],
                                   x0[~fails, 0] / (1 - x0[~fails, 0]), rtol=1e-10)
    for sol in runs[1:]:
        np.testing.assert_array_equal(sol.status, runs[0].status)
        np.testing.assert_array_equal(sol.final[~fails], runs[0].final[~fails])
        np.testing.assert_array_equal(sol.steps[~fails], runs[0].steps[~fails])


def test_lean_path_equals_general_path(snake):
    # full SIMD batches (the lean loop) against the same trajectories one at a time (a
    # padded batch: the general per-event path); the lanes are independent, so the end
    # points and step counts are the same
    rng = np.random.default_rng(5)
    x0 = rng.uniform(-0.1, 0.1, (16, 6))
    amps = rng.uniform(0.01, 0.3, 16)
    lean = integrate(snake, x0, bracket_inputs(3, 1, 3, amps), engine="heyoka", threads=2)
    for k in range(16):
        one = integrate(snake, x0[k], bracket_inputs(3, 1, 3, amps[k]), engine="heyoka")
        np.testing.assert_array_equal(lean.final[k], one.final[0])
        assert lean.steps[k] == one.steps[0]


def test_unused_parameters_left_out_change_nothing(snake):
    # the integrator specialised to the inputs in use (u_2 = 0 dropped) against the one with
    # every parameter: equal end points up to rounding
    rng = np.random.default_rng(6)
    x0 = rng.uniform(-0.1, 0.1, (16, 6))
    sig = bracket_inputs(3, 1, 3, rng.uniform(0.01, 0.3, 16))
    lean = integrate(snake, x0, sig, engine="heyoka")
    tol = heyoka_engine.heyoka_tolerance(1e-10, 1e-12)
    integ = heyoka_engine.taylor_integrator(snake, sig.harmonics, tol, None)
    assert integ.parameters == 1 + 3 * (1 + 2 * sig.harmonics)
    ta = integ.template
    pars = heyoka_engine._parameters(sig)
    out = np.empty((16, 6))
    bs = integ.batch_size
    for lo in range(0, 16, bs):
        hi = min(lo + bs, 16)
        lanes = lo + np.arange(bs) % (hi - lo)
        ta.state[:] = x0[lanes].T
        ta.pars[:] = pars[lanes, 0].T
        ta.set_time(np.zeros(bs))
        ta.propagate_until(np.full(bs, 2 * np.pi))
        out[lo:hi] = ta.state[:, : hi - lo].T
    assert np.abs(lean.final - out).max() < 1e-13


def test_samples_at_start_and_end_take_the_lean_path_unchanged(snake):
    # samples at 0 and at the end only (the lean loop) against samples that also stop
    # half-way (the general path): the start and end samples agree; the end is the final
    rng = np.random.default_rng(7)
    x0 = rng.uniform(-0.1, 0.1, (37, 6))
    inputs = bracket_inputs(3, 1, 2, rng.uniform(0.01, 0.3, 37))
    end = float(inputs.total_durations.min())
    lean = integrate(snake, x0, inputs, engine="heyoka", times=[0.0, end], threads=2)
    general = integrate(snake, x0, inputs, engine="heyoka", times=[0.0, end / 2, end],
                        threads=1)
    np.testing.assert_array_equal(lean.samples[:, 0], x0)
    np.testing.assert_array_equal(lean.samples[:, 1], lean.final)
    assert np.abs(lean.final - general.samples[:, 2]).max() < 1e-12
    np.testing.assert_array_equal(general.samples[:, 2], general.final)


def test_a_coordinate_the_inputs_cannot_move_is_held_not_integrated(snake):
    # [X1, X2] bracket motions of the trident snake: X1 and X2 have 0 in the θ row (q2),
    # so θ is frozen (a parameter); it is reported as its start value, exactly, in the end
    # points and in every sample, and the other coordinates agree with the integrator that
    # integrates all six (every parameter, nothing frozen) up to rounding
    rng = np.random.default_rng(9)
    x0 = rng.uniform(-0.1, 0.1, (21, 6))
    x0[0, 2] = 3.0  # a heading beyond 1: the held value does not loosen the tolerance
    sig = bracket_inputs(3, 1, 2, rng.uniform(0.01, 0.3, 21))
    end = float(sig.total_durations.min())
    sol = integrate(snake, x0, sig, engine="heyoka", times=[0.0, end / 3, end])
    assert sol.all_ok
    np.testing.assert_array_equal(sol.final[:, 2], x0[:, 2])
    np.testing.assert_array_equal(sol.samples[:, :, 2], np.repeat(x0[:, 2:3], 3, axis=1))
    tol = heyoka_engine.heyoka_tolerance(1e-10, 1e-12)
    held = [v for k, v in compiled_memo(snake).items() if k[0] == "heyoka" and k[4]]
    assert held and all(v.frozen == (2,) for v in held)
    assert all(v.template.state.shape[0] == 5 for v in held)
    full = heyoka_engine.taylor_integrator(snake, sig.harmonics, tol, None)
    ta, bs = full.template, full.batch_size
    pars = heyoka_engine._parameters(sig)
    for lo in range(0, 21, bs):
        hi = min(lo + bs, 21)
        lanes = lo + np.arange(bs) % (hi - lo)
        ta.state[:] = x0[lanes].T
        ta.pars[:] = pars[lanes, 0].T
        ta.set_time(np.zeros(bs))
        ta.propagate_until(np.full(bs, end))
        assert np.abs(sol.final[lo:hi] - ta.state[:, : hi - lo].T).max() < 1e-13


def test_a_held_coordinate_beyond_the_bound_fails_as_when_integrated(snake):
    # a start value that is not finite or beyond `bound` is not frozen: the trajectory is
    # integrated in full and stopped (beyond the bound / non-finite) like any other, while
    # the rows beside it are unaffected (bit-identical to a batch without it)
    rng = np.random.default_rng(10)
    x0 = rng.uniform(-0.1, 0.1, (12, 6))
    amps = rng.uniform(0.01, 0.3, 12)
    bad = x0.copy()
    bad[3, 2] = 5e8
    bad[7, 2] = np.nan
    sol = integrate(snake, bad, bracket_inputs(3, 1, 2, amps), engine="heyoka", bound=1e8)
    assert Status(int(sol.status[3])) == Status.BLOW_UP
    assert Status(int(sol.status[7])) == Status.NON_FINITE
    rest = [k for k in range(12) if k not in (3, 7)]
    assert np.all(sol.status[rest] == Status.SUCCESS)
    alone = integrate(snake, x0[rest], bracket_inputs(3, 1, 2, amps[rest]), engine="heyoka")
    np.testing.assert_array_equal(sol.final[rest], alone.final)


def test_the_integrator_reads_only_the_parameters_in_use(snake):
    # [X1, X3] motions use ω, the sine amplitude of u1 and the cosine amplitude of u3: the
    # compiled integrator has those three parameters (nothing else; X1 and X3 both move
    # every coordinate, so nothing is frozen), in layout order
    sig = bracket_inputs(3, 1, 3, np.array([0.1]))
    integrate(snake, np.zeros((1, 6)), sig, engine="heyoka")
    pars = heyoka_engine._parameters(sig)[0, 0]
    used = tuple(int(p) for p in np.flatnonzero(pars))
    integ = [v for k, v in compiled_memo(snake).items()
             if k[0] == "heyoka" and k[3] is not None and v.slots == used]
    assert integ and integ[0].frozen == () and integ[0].parameters == len(used)


def test_default_thread_count_is_one_more_than_the_cores(monkeypatch):
    monkeypatch.setattr(heyoka_engine, "default_threads", lambda: 2)
    assert heyoka_engine.default_workers() == 3
    monkeypatch.setattr(heyoka_engine, "default_threads", lambda: 1)
    assert heyoka_engine.default_workers() == 1
