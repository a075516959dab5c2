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
