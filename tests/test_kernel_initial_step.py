"""The compiled integrator's first step where a coordinate crosses zero (attack finding:
``plan car-trailers:1 --planner reeds-shepp --from x=2 --to x=-1`` failed in the final
re-simulation with "step size below min_step" on the numba engine only)."""

from __future__ import annotations

import numpy as np

from nilpotent.models import get_model
from nilpotent.planning.controls import constant_segment
from nilpotent.planning.simulation import PLANNING_SETTINGS, simulate_path


def test_a_straight_reverse_through_x_0_is_integrated():
    # a car with one trailer, both aligned with the x axis, reversing 3 units in 12
    # segments: a segment starts at x = 2 - 0.25 k, i.e. at x ~ 1e-14 after eight
    # (where the step guess was ~6e-14, below min_step); the exact motion is a straight
    # line, the angles stay 0 (hand derivation: theta1' = sin(theta0 - theta1) u1 / d)
    system = get_model("car-trailers:1")
    segments = [constant_segment(np.array([-0.25, 0.0]), 1.0)] * 12
    settings = PLANNING_SETTINGS.replace(engine="numba")
    times, states = simulate_path(system, [2.0, 0.0, 0.0, 0.0], segments, 5, settings)
    np.testing.assert_allclose(states[-1], [-1.0, 0.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(states[:, 0], 2.0 - 0.25 * times, atol=1e-12)
