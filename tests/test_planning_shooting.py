"""Shortest steering of nilpotent systems of step ≥ 3 (``planning.shooting``).

Independent references: the Hamiltonian equations of the Engel group written by
hand below and integrated by scipy (not the product's integrator); the step-2
closed form (:func:`~nilpotent.planning.geodesic.shortest_geodesic`, Van Loan's
block exponential, a different method); the certified bound ``‖B⁺Δh‖``
(``∫‖u‖ ≥ ‖∫u‖``); the Martinet line, abnormal by a hand computation: along
``y = 0`` the linearisation of ``X̂₁ = ∂x + y²/2 ∂z, X̂₂ = ∂y`` has
``δż = y δy u₁ + y²/2 δu₁ = 0``, so the endpoint differential has rank 2 < 3,
and the line to ``(a, 0, 0)`` has length ``a = |Δx|``, the least possible.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import nilpotent.cli.cmd_plan  # noqa: F401  (registers the command)
from nilpotent.models import get_model
from nilpotent.planning import TriangularSystem, endpoint, plan, steer_nilpotent
from nilpotent.planning.geodesic import control_length, shortest_geodesic
from nilpotent.planning.shooting import shortest_normal_geodesic, weight_one_bound

Y = sp.symbols("y1:5")
ENGEL = TriangularSystem.from_fields(
    ((1, 0, 0, 0), (0, 1, Y[0], Y[0] ** 2 / 2)), Y, (1, 1, 2, 3))
HEIS = TriangularSystem.from_fields(((1, 0, -Y[1] / 2), (0, 1, Y[0] / 2)), Y[:3], (1, 1, 2))
MARTINET = TriangularSystem.from_fields(((1, 0, Y[1] ** 2 / 2), (0, 1, 0)), Y[:3], (1, 1, 3))
ENGEL_GOALS = [(0.3, -0.2, 0.1, 0.02), (0.1, 0.2, 0.3, 0.1), (-0.5, 0.4, -0.1, 0.05)]


def engel_hamiltonian(_t: float, z: np.ndarray) -> np.ndarray:
    """``H = ½(p₁² + (p₂ + y₁p₃ + y₁²p₄/2)²)`` of ``X₁ = ∂₁, X₂ = ∂₂ + y₁∂₃ + y₁²/2 ∂₄``."""
    y1, _, _, _, p1, _, p3, p4 = z
    h2 = z[5] + y1 * p3 + y1**2 * p4 / 2
    return np.array([p1, h2, h2 * y1, h2 * y1**2 / 2, -h2 * (p3 + y1 * p4), 0.0, 0.0, 0.0])


@pytest.mark.parametrize("goal", ENGEL_GOALS)
def test_shooting_solves_the_hamiltonian_equations(goal) -> None:
    g = shortest_normal_geodesic(ENGEL, np.zeros(4), goal)
    z0 = np.concatenate([np.zeros(4), g.covector])
    sol = solve_ivp(engel_hamiltonian, (0, 1), z0, method="DOP853", rtol=1e-12, atol=1e-13)
    end = sol.y[:, -1]
    assert np.max(np.abs(end[:4] - goal)) < 1e-8
    speed = [np.linalg.norm(ENGEL.field_values(z[:4]).T @ z[4:]) for z in sol.y.T]
    assert np.ptp(speed) < 1e-9 * max(speed)  # H is conserved: constant speed
    assert g.length == pytest.approx(speed[0], rel=1e-9)  # length = √(2H) on [0, 1]
    # the controls returned reach the goal on the exact flow; their length is the geodesic's
    assert np.max(np.abs(endpoint(ENGEL, np.zeros(4), g.segments) - goal)) < 1e-12
    assert control_length(g.segments) == pytest.approx(g.length, rel=1e-6)
    assert g.length >= weight_one_bound(ENGEL, np.zeros(4), np.array(goal)) - 1e-12
    assert not g.abnormal


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_shooting_agrees_with_the_step_2_closed_form(seed) -> None:
    rng = np.random.default_rng(seed)
    goal = rng.normal(size=3)
    start = 0.3 * rng.normal(size=3)
    shot = shortest_normal_geodesic(HEIS, start, goal)
    closed = shortest_geodesic(HEIS, start, goal)
    assert shot.length == pytest.approx(closed.length, rel=1e-8)


def test_length_scales_with_the_dilation() -> None:
    goal = np.array(ENGEL_GOALS[0])
    base = shortest_normal_geodesic(ENGEL, np.zeros(4), goal).length
    for lam in (0.1, 3.0):
        dilated = ENGEL.dilate(goal, lam)
        assert shortest_normal_geodesic(ENGEL, np.zeros(4), dilated).length == pytest.approx(
            lam * base, rel=1e-8)


@pytest.mark.parametrize("a", [0.5, 2.0, -1.0])
def test_martinet_line_is_found_and_reported_abnormal(a) -> None:
    g = shortest_normal_geodesic(MARTINET, np.zeros(3), (a, 0.0, 0.0))
    assert g.length == pytest.approx(abs(a), rel=1e-9)  # the least length, |Δx|
    assert g.abnormal and g.rank == 2
    assert np.max(np.abs(endpoint(MARTINET, np.zeros(3), g.segments) - (a, 0, 0))) < 1e-12


def test_martinet_off_the_line_is_normal_and_not_abnormal() -> None:
    goal = (0.5, 0.3, 0.01)
    g = shortest_normal_geodesic(MARTINET, np.zeros(3), goal)
    assert not g.abnormal and g.rank == 3
    assert g.length >= math.hypot(0.5, 0.3) - 1e-12
    assert np.max(np.abs(endpoint(MARTINET, np.zeros(3), g.segments) - goal)) < 1e-12


def test_steer_nilpotent_geodesic_on_step_3_reaches_exactly() -> None:
    s = steer_nilpotent(ENGEL, np.zeros(4), ENGEL_GOALS[1], method="geodesic")
    assert s.error < 1e-12
    loops = steer_nilpotent(ENGEL, np.zeros(4), ENGEL_GOALS[1])
    assert control_length(s.segments) <= control_length(loops.segments)


@pytest.mark.slow
def test_plan_objective_length_on_engel_is_verified_and_shorter(monkeypatch) -> None:
    # the report's shooting is capped in seconds: no cap here, so the load cannot matter
    monkeypatch.setattr("nilpotent.planning.length.LOWER_BOUND_SECONDS", math.inf)
    eng = get_model("engel")
    goal = (0.1, 0.0, 0.0, 0.05)
    short = plan(eng, (0,) * 4, goal, objective="length")
    reach = plan(eng, (0,) * 4, goal)
    assert short.error <= 1e-8  # re-simulated on the true model
    assert short.length < reach.length
    fields = short.length_fields[0]
    assert fields["lower_bound"] is not None and fields["lower_bound_kind"] == "approximation"
    assert fields["abnormal"] is False


@pytest.mark.slow
def test_cli_step_3_objective_length(run_cli, monkeypatch) -> None:
    monkeypatch.setattr("nilpotent.planning.length.LOWER_BOUND_SECONDS", math.inf)
    status, stdout, stderr = run_cli("plan", "engel", "--to", "x1=1/10,x4=1/20",
                                     "--objective", "length", "--time-limit", "900", "--json")
    assert status == 0, stderr
    out = json.loads(stdout)
    assert out["error"] <= 1e-8
    assert out["lower_bound"] > 0 and out["abnormal"] is False
    assert out["length"] >= out["lower_bound"] * (1 - 1e-6)
