"""Shortest steering of step-2 nilpotent systems (``planning.geodesic``, ``--objective length``).

The reference distance of the Heisenberg group is derived here, independently
of the code: with ``ẋ₃ = (x₁u₂ − x₂u₁)/2`` (the built-in ``heisenberg`` model,
``X1 = ∂1 − x2/2 ∂3``, ``X2 = ∂2 + x1/2 ∂3``), ``x₃(1)`` is the signed area
swept by ``(x₁, x₂)`` seen from the start.  Minimising the length of a plane
curve from 0 to ``(x₁, x₂)`` (chord ``r``) that encloses, with the chord, the
area ``|x₃|`` is Dido's problem: the curve is a circular arc.  An arc of angle
``φ`` and radius ``R`` has length ``L = Rφ``, chord ``r = 2R sin(φ/2)`` and
segment area ``R²(φ − sin φ)/2``, hence

    |x₃| / r² = (φ − sin φ) / (8 sin²(φ/2)),     d = r φ / (2 sin(φ/2)),

``φ ∈ [0, 2π)`` (the left side increases from 0 to ∞); for ``r = 0`` (a full
circle) ``d = √(4π|x₃|)``.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.linalg
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

import nilpotent.cli.cmd_plan  # noqa: F401  (registers the command)
from closed_forms import heisenberg_distance
from nilpotent.errors import PlanningError
from nilpotent.models import get_model
from nilpotent.planning import TriangularSystem, endpoint, plan, steer_nilpotent
from nilpotent.planning.geodesic import (
    Step2Structure,
    _expm,
    control_length,
    geodesic_controls,
    shortest_geodesic,
)
from nilpotent.planning.local_model import numeric_model

Y3 = sp.symbols("y1 y2 y3")
HEIS = TriangularSystem.from_fields(
    ((1, 0, -Y3[1] / 2), (0, 1, Y3[0] / 2)), Y3, (1, 1, 2))


def free_36() -> TriangularSystem:
    """The free step-2 nilpotent system with 3 inputs: ``v̇_ab = (h_a u_b − h_b u_a)/2``."""
    y = sp.symbols("y1:7")
    fields = [[sp.Integer(0)] * 6 for _ in range(3)]
    for i in range(3):
        fields[i][i] = sp.Integer(1)
    for k, (a, b) in enumerate([(0, 1), (0, 2), (1, 2)]):
        fields[b][3 + k] += y[a] / 2
        fields[a][3 + k] -= y[b] / 2
    return TriangularSystem.from_fields(fields, y, (1, 1, 1, 2, 2, 2))


def test_reference_formula_limits() -> None:
    # the vertical case, and the arc formula close to it, against sqrt(4π|z|)
    assert heisenberg_distance(0, 0, 0.3) == pytest.approx(math.sqrt(4 * math.pi * 0.3))
    assert heisenberg_distance(1e-6, 0, 0.3) == pytest.approx(
        math.sqrt(4 * math.pi * 0.3), rel=1e-4)
    assert heisenberg_distance(0.3, 0.4, 0) == pytest.approx(0.5)


def test_heisenberg_length_is_the_closed_form_distance_on_unseen_goals() -> None:
    rng = np.random.default_rng(20261201)
    for _ in range(25):
        goal = rng.normal(size=3) * rng.uniform(0.05, 3.0)
        geo = shortest_geodesic(HEIS, (0, 0, 0), goal)
        assert geo.length == pytest.approx(heisenberg_distance(*goal), rel=1e-6)
        segs = geodesic_controls(Step2Structure.from_triangular(HEIS), geo)
        # the exact flow of the plan segments (independent code) reaches the goal
        assert np.max(np.abs(endpoint(HEIS, np.zeros(3), segs) - goal)) < 1e-10
        # and so does a tight numerical integration of the true Heisenberg fields
        seg = segs[0]

        def rhs(t, x, seg=seg):
            u = seg.values(t)
            return [u[0], u[1], (x[0] * u[1] - x[1] * u[0]) / 2]

        x = solve_ivp(rhs, (0, seg.duration), np.zeros(3), method="DOP853",
                      rtol=1e-13, atol=1e-14).y[:, -1]
        assert np.max(np.abs(x - goal)) < 1e-10
        assert control_length(segs) == pytest.approx(geo.length, rel=1e-12)


def test_heisenberg_special_goals() -> None:
    for goal in [(0, 0, 0.7), (0, 0, -0.2), (0.3, -0.4, 0.0), (1e-9, 0, 1.0)]:
        geo = shortest_geodesic(HEIS, (0, 0, 0), goal)
        assert geo.length == pytest.approx(heisenberg_distance(*goal), rel=1e-6)
        assert geo.error < 1e-12


def test_heisenberg_tiny_goals_do_not_underflow_the_dilation() -> None:
    # a horizontal goal 1e-200 away: the dilation's scale² (1e-400) underflows to 0
    # when formed as a power; the geodesic is the straight segment of length |x|
    for goal in [(1e-200, 0.0, 0.0), (0.0, -3e-170, 0.0), (5e-324, 0.0, 0.0)]:
        geo = shortest_geodesic(HEIS, (0, 0, 0), goal)
        assert math.isfinite(geo.length)
        assert geo.length == pytest.approx(math.hypot(goal[0], goal[1]), rel=1e-6)
        assert geo.error <= 1e-12 * max(abs(g) for g in goal)


def test_heisenberg_from_a_start_off_the_origin() -> None:
    # left translation by p: (p1, p2, p3)·(a, b, c) = (p1+a, p2+b, p3+c+(p1 b − p2 a)/2)
    p = np.array([0.4, -1.1, 0.3])
    g = np.array([-0.2, 0.5, 0.9])
    goal = p + g
    goal[2] += (p[0] * g[1] - p[1] * g[0]) / 2
    geo = shortest_geodesic(HEIS, p, goal)
    assert geo.length == pytest.approx(heisenberg_distance(*g), rel=1e-6)
    assert geo.error < 1e-12


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    st.tuples(*[st.floats(-2, 2) for _ in range(3)]).filter(
        lambda g: max(abs(g[0]), abs(g[1]), abs(g[2]) ** 0.5) > 0.05),
    st.floats(0.1, 5.0),
    st.floats(-math.pi, math.pi),
)
def test_heisenberg_dilation_and_rotation(goal, lam, angle) -> None:
    base = shortest_geodesic(HEIS, (0, 0, 0), goal).length
    dilated = (lam * goal[0], lam * goal[1], lam**2 * goal[2])
    assert shortest_geodesic(HEIS, (0, 0, 0), dilated).length == pytest.approx(
        lam * base, rel=1e-9)
    c, s = math.cos(angle), math.sin(angle)
    rotated = (c * goal[0] - s * goal[1], s * goal[0] + c * goal[1], goal[2])
    assert shortest_geodesic(HEIS, (0, 0, 0), rotated).length == pytest.approx(base, rel=1e-9)


def test_free_36_geodesics_reach_and_beat_the_loops() -> None:
    tri = free_36()
    stc = Step2Structure.from_triangular(tri)
    rng = np.random.default_rng(7)
    for _ in range(6):
        goal = rng.normal(size=6) * 0.5
        geo = shortest_geodesic(stc, np.zeros(6), goal)
        segs = geodesic_controls(stc, geo)
        assert np.max(np.abs(endpoint(tri, np.zeros(6), segs) - goal)) < 1e-10
        loops = steer_nilpotent(tri, np.zeros(6), goal, method="step2").segments
        assert geo.length <= control_length(loops) * (1 + 1e-9)
        # ball-box lower bound: |h(1) − h(0)| ≤ length (the h-part moves at speed ‖u‖)
        assert geo.length >= np.linalg.norm(goal[:3]) * (1 - 1e-12)


def test_free_36_geodesic_is_locally_shortest() -> None:
    """Independent check: a direct shooting (piecewise-constant controls, endpoint
    constraint, scipy SLSQP from the geodesic's own samples perturbed) finds nothing
    shorter than the geodesic (beyond its discretisation error)."""
    from scipy.optimize import minimize

    tri = free_36()
    goal = np.array([0.3, -0.2, 0.1, 0.2, -0.1, 0.15])
    geo = shortest_geodesic(tri, np.zeros(6), goal)
    k = 24

    def end(flat):
        # exact flow of piecewise-constant controls (steps 1/k), by hand: on a step
        # h_a(t) = h_a + u_a t, so v_ab gains (h_a u_b − h_b u_a)/(2k) (the u_a u_b cancel)
        h = np.zeros(3)
        v = np.zeros(3)
        for u in flat.reshape(k, 3):
            pairs = ((0, 1), (0, 2), (1, 2))
            v += np.array([h[a] * u[b] - h[b] * u[a] for a, b in pairs]) / (2 * k)
            h = h + u / k
        return np.concatenate([h, v])

    segs = geodesic_controls(Step2Structure.from_triangular(tri), geo)
    mids = (np.arange(k) + 0.5) / k
    guess = (segs[0].values(mids).T * (1 + 0.05 * np.sin(7 * mids))[:, None]).ravel()
    res = minimize(lambda f: np.sum(f.reshape(k, 3) ** 2) / k, guess, method="SLSQP",
                   constraints={"type": "eq", "fun": lambda f: end(f) - goal},
                   options={"maxiter": 200, "ftol": 1e-12})
    assert np.max(np.abs(end(res.x) - goal)) < 1e-7
    shooting_length = float(np.sum(np.linalg.norm(res.x.reshape(k, 3), axis=1)) / k)
    assert shooting_length >= geo.length * (1 - 1e-3)


def test_expm_against_scipy() -> None:
    rng = np.random.default_rng(3)
    a = rng.normal(size=(5, 8, 8)) * np.array([0.01, 0.5, 2, 10, 40])[:, None, None]
    ref = np.array([scipy.linalg.expm(x) for x in a])
    got = _expm(a)
    assert np.max(np.abs(got - ref) / (1 + np.abs(ref))) < 1e-11


def test_control_length_of_a_circle() -> None:
    # u = (−Aω sin ωt, Aω cos ωt): constant speed Aω, length AωT (independent of the code)
    from nilpotent.numeric.signals import InputSignal, Segment

    seg = Segment(2.0, 3.0, (InputSignal(0.0, (), (-0.5 * 3,)), InputSignal(0.0, (0.5 * 3,))))
    assert control_length([seg]) == pytest.approx(0.5 * 3 * 2.0, rel=1e-12)
    # a straight segment: |u|·T
    lin = Segment(0.5, 1.0, (InputSignal(3.0), InputSignal(-4.0)))
    assert control_length([seg, lin]) == pytest.approx(3.0 + 2.5, rel=1e-12)


@pytest.mark.parametrize("eps", [1e-1, 1e-2, 1e-3, 0.0])
def test_control_length_where_the_speed_nearly_vanishes(eps: float) -> None:
    # u = (cos t, ε) on [0, 2π]: ‖u‖ has near-kinks at t = π/2, 3π/2, where a fixed
    # Gauss rule erred by 4e-5 (ε = 1e-2).  Exact: ∫₀^{2π} √(ε² + cos²t) dt
    # = 4√(1 + ε²)·E(1/(1 + ε²)), E the complete elliptic integral (parameter m)
    from scipy.special import ellipe

    from nilpotent.numeric.signals import InputSignal, Segment

    seg = Segment(2 * math.pi, 1.0, (InputSignal(0.0, (1.0,)), InputSignal(eps)))
    exact = 4 * math.sqrt(1 + eps**2) * float(ellipe(1 / (1 + eps**2)))
    assert control_length([seg]) == pytest.approx(exact, rel=1e-10)


def test_step_3_is_refused_with_a_clear_error() -> None:
    y = sp.symbols("y1:5")
    engel = TriangularSystem.from_fields(
        ((1, 0, 0, 0), (0, 1, y[0], y[0] ** 2 / 2)), y, (1, 1, 2, 3))
    with pytest.raises(PlanningError, match="step <= 2"):
        shortest_geodesic(engel, (0,) * 4, (0.1, 0, 0, 0.1))
    with pytest.raises(PlanningError, match="step <= 2"):
        steer_nilpotent(engel, (0,) * 4, (0.1, 0, 0, 0.1), method="step2")
    # the "geodesic" method shoots for step >= 3 (tests/test_planning_shooting.py)


def test_plan_objective_length_on_heisenberg() -> None:
    h = get_model("heisenberg")
    goal = (0.3, -0.2, 0.4)
    p = plan(h, (0, 0, 0), goal, objective="length")
    fields = p.length_fields[0]
    assert p.error <= 1e-8
    assert fields["lower_bound"] == pytest.approx(heisenberg_distance(*goal), rel=1e-9)
    assert fields["lower_bound_kind"] == "exact"
    assert p.length == pytest.approx(heisenberg_distance(*goal), rel=1e-9)
    reach = plan(h, (0, 0, 0), goal)
    assert reach.length > p.length * 1.05  # loops are not geodesics
    with pytest.raises(PlanningError, match="objective"):
        plan(h, (0, 0, 0), goal, objective="shortest")
    with pytest.raises(PlanningError, match="contradicts"):
        plan(h, (0, 0, 0), goal, objective="length", method="step2")


def test_trident_snake_length_objective_reaches_and_is_shorter() -> None:
    tri = get_model("trident-snake")
    goal = (0.1, -0.05, 0.08, 0.1, -0.05, 0.02)
    short = plan(tri, (0,) * 6, goal, objective="length")
    reach = plan(tri, (0,) * 6, goal)
    assert short.error <= 1e-8
    assert short.length <= reach.length
    # the local model at the start is the free (3,6) approximation: its geodesic distance
    model = numeric_model(tri, np.zeros(6))
    assert Step2Structure.from_triangular(model.nilpotent).skew.shape == (3, 3, 3)
    assert short.length_fields[0]["lower_bound_kind"] == "approximation"


def test_cli_objective_length_json(run_cli) -> None:
    status, stdout, stderr = run_cli("plan", "heisenberg", "--to", "x1=1/5,x2=1/10,x3=-3/10",
                                     "--objective", "length", "--json")
    assert status == 0, stderr
    out = json.loads(stdout)
    assert out["length"] == pytest.approx(heisenberg_distance(0.2, 0.1, -0.3), rel=1e-9)
    assert out["length_ratio"] == pytest.approx(1.0, abs=1e-9)
    assert out["error"] <= 1e-8
    status, stdout, stderr = run_cli("plan", "heisenberg", "--to", "x1=1", "--objective", "fast")
    assert status == 2
    assert "--objective" in stdout + stderr


def test_step_3_reach_plan_leaves_the_shooting_bound_null_with_its_reason(run_cli) -> None:
    # the shooting costs seconds: a `reach` plan of step 3 does not pay it in its report
    status, stdout, stderr = run_cli("plan", "engel", "--to", "x1=1/10,x4=1/100", "--json")
    assert status == 0, stderr
    out = json.loads(stdout)
    assert out["length"] > 0
    assert out["lower_bound"] is None and out["length_ratio"] is None
    assert "--objective length" in out["null_reasons"]["lower_bound"]


def test_arc_angle_of_a_tiny_area_is_not_lost_to_cancellation() -> None:
    # (θ − sin θ)/(8 sin²(θ/2)) = θ/12 + O(θ³): for q = 1e-12 the angle is 1.2e-11; with
    # θ − sin θ evaluated in doubles it came out ~1e-8 (θ − sin θ rounds to 0 below that)
    from nilpotent.planning.geodesic import _arc_angle

    for q in (1e-12, 1e-9, 1e-6):
        assert _arc_angle(q) == pytest.approx(12 * q, rel=1e-6)
    theta = _arc_angle(0.3)
    ratio = (theta - math.sin(theta)) / (8 * math.sin(theta / 2) ** 2)
    assert ratio == pytest.approx(0.3, rel=1e-12)
