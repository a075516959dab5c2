"""``--planner reeds-shepp`` for ``car-trailers:2``: the lattice search over exact motions.

Independent results: the closed-form drives (trailer 1 on a circle, trailer 2's hitch angle
by the Riccati solution) against scipy's DOP853 on the model's own fields; the plans
replayed by scipy (tests/replay.py), their end against the goal, their hitch angles against
the limits, their bodies against one another (the checker's self-clearance) and the world.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from nilpotent.models import get_model
from nilpotent.models.outlines import HITCH_LIMIT
from nilpotent.planning.global_planner import plan_global
from nilpotent.planning.trailer_lattice import (
    arc_states,
    drive_controls,
    hitch_flow,
    lattice_geometry,
)
from nilpotent.planning.verify import Checker
from nilpotent.planning.world import load_world
from replay import resimulate

SYSTEM = get_model("car-trailers:2")


def _json(plan) -> list[dict]:
    return [s.to_dict() for s in plan.segments]


def _scipy(x0: np.ndarray, u: tuple[float, float], times: np.ndarray) -> np.ndarray:
    mat = sp.lambdify([SYSTEM.coordinates], sp.Matrix(SYSTEM.specialized_fields).T, "numpy")
    sol = solve_ivp(lambda t, z: np.asarray(mat(z), dtype=float) @ np.array(u), (0.0, 1.0),
                    x0, method="DOP853", rtol=1e-12, atol=1e-13, t_eval=times)
    assert sol.success
    return sol.y.T


def test_geometry_of_the_built_in_model():
    g = lattice_geometry(SYSTEM, Checker(SYSTEM))
    assert g.hitches == pytest.approx((1.0, 1.0))
    assert g.phi_max == pytest.approx(HITCH_LIMIT)


# |κ| < 1/d2 (an equilibrium of φ2), |κ| > 1/d2 (none), κ = 0; forwards and backwards
@pytest.mark.parametrize("phi1, phi2, s1", [(0.5, -0.3, 0.9), (0.5, 0.6, -0.4),
                                            (1.1, 0.2, 0.5), (-1.2, -0.1, -0.3),
                                            (0.0, 0.7, 1.2), (0.0, -0.4, -0.6)])
def test_drive_in_closed_form_matches_scipy(phi1, phi2, s1):
    """A drive with φ1 held: the closed form at 11 points against scipy's integration of
    the model's fields under the drive's constant controls (unit time, so the sample at
    time t is the closed form at t·s1)."""
    g = lattice_geometry(SYSTEM, Checker(SYSTEM))
    th1 = 0.4
    x0 = np.array([0.3, -0.2, th1 + phi1, th1, th1 - phi2])
    times = np.linspace(0.0, 1.0, 11)
    ref = _scipy(x0, drive_controls(x0, s1, g), times)
    ours = arc_states(x0, times * s1, g)
    assert np.abs(ours - ref).max() <= 1e-9
    assert np.abs(ours[:, 2] - ours[:, 3] - phi1).max() <= 1e-12  # φ1 held


def test_hitch_flow_tends_to_its_equilibrium_forwards():
    """Forwards, φ2 tends to the stable equilibrium sin φ2 = κ d2 (|κ| d2 < 1), from either
    side; backwards it leaves it."""
    kappa = 0.5
    eq = math.asin(kappa)
    for phi in (-1.0, 0.0, 1.2):
        assert hitch_flow(phi, kappa, 1.0, np.array([30.0]))[0] == pytest.approx(eq, abs=1e-9)
    assert abs(hitch_flow(eq + 0.01, kappa, 1.0, np.array([-2.0]))[0] - eq) > 0.05


def _check_plan(out, start, goal, world) -> np.ndarray:
    q = resimulate(SYSTEM, start, _json(out.plan), samples=60)
    assert np.linalg.norm(q[-1] - np.array(goal)) <= 1e-5
    assert np.abs(np.diff(q[:, 2:], axis=1)).max() <= HITCH_LIMIT + 1e-9
    checker = Checker(SYSTEM, world)
    assert np.all(checker.self_clearance(q) > 0)
    if world is not None:
        assert np.all(checker.measures(q)[0] > -1e-9)
    return q


def test_free_space_plan_is_exact_and_replays():
    """A sideways shift in free space: every piece driven exactly (no steering iterations),
    and the scipy replay reaches the goal within the hitch limits, bodies apart."""
    start, goal = (0.0, 0.0, 0.0, 0.0, 0.0), (3.0, 1.0, 0.0, 0.0, 0.0)
    out = plan_global(SYSTEM, start, goal, 1e-6, time_limit=600, planner="reeds-shepp",
                      direct=False)
    assert out.planner == "reeds-shepp"
    assert all(p.iterations == 0 for p in out.pieces)
    _check_plan(out, start, goal, None)


@pytest.mark.slow
def test_parking_two_trailers():
    """The first pair of benchmarks/plan_world.py's ``parking2`` (rounded) parked: the scipy
    replay reaches the goal, keeps both hitch angles within 1.4, its bodies apart and out of
    the obstacles at every sample."""
    start = (-0.09, 0.84, -0.27, -0.56, -0.38)
    goal = (2.03, -0.51, 0.0, -0.02, -0.02)
    world = load_world("parking")
    out = plan_global(SYSTEM, start, goal, 1e-6, world=world, time_limit=600,
                      planner="reeds-shepp")
    assert all(p.iterations == 0 for p in out.pieces)
    _check_plan(out, start, goal, world)
