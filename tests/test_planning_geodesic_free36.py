"""Shortest geodesics of the free (3,6) group (``planning.geodesic_forms``), checked independently.

The free step-2 group with three inputs, ``v̇_ab = (h_a u_b − h_b u_a)/2``
(``(a, b) = (1,2), (1,3), (2,3)``): with ``x = h(1)`` and the area vector
``w = ½∫ h × u dt = (v₂₃, −v₁₃, v₁₂)``, rotations ``R ∈ SO(3)`` act by
``(x, w) ↦ (Rx, Rw)`` (``Ra × Rb = R(a × b)``) and preserve lengths.  Closed forms
used here, derived independently of the code:

* ``x ⊥ w``: the projection of a curve on the plane ⊥ ``w`` does not lengthen
  it and keeps ``w``'s component, and a planar curve makes no other area: the
  distance is Heisenberg's (Dido's problem) with chord ``|x|`` and area ``|w|``;
* ``x = 0``: the isoperimetric inequality for the projection on the plane
  ⊥ ``w`` gives ``L ≥ √(4π|w|)``, reached by a circle;
* dilations ``(x, w) ↦ (λx, λ²w)`` scale lengths by ``λ``;
* any goal: ``|d − √(4π|w|)| ≤ |x|`` — the segment to ``x`` followed by a circle
  of area ``|w|`` reaches it (a straight segment from 0 makes no area, a closed
  loop adds its own), and a curve closed by its chord (no area either) is a
  loop of area vector ``w``, so ``(d + |x|)² ≥ 4π|w|`` (isoperimetric).

Elsewhere the oracle is a brute multi-start: Levenberg–Marquardt (written here)
on normal extremals ``u = e^{tΩ}u₀`` (Pontryagin; ``Ω`` any skew matrix), the
endpoint from Van Loan's block exponential (not the closed forms under test),
from many random starts; the code's length must not exceed the best found.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from closed_forms import dido_distance as heisenberg_distance
from nilpotent.models import get_model
from nilpotent.planning import TriangularSystem, endpoint
from nilpotent.planning.geodesic import (
    Step2Structure,
    _van_loan_integrals,
    geodesic_controls,
    shortest_geodesic,
)
from nilpotent.planning.geodesic_forms import reduced_free3_solutions, rodrigues_integrals
from nilpotent.planning.local_model import numeric_model


def free_36() -> TriangularSystem:
    y = sp.symbols("y1:7")
    fields = [[sp.Integer(0)] * 6 for _ in range(3)]
    for i in range(3):
        fields[i][i] = sp.Integer(1)
    for k, (a, b) in enumerate([(0, 1), (0, 2), (1, 2)]):
        fields[b][3 + k] += y[a] / 2
        fields[a][3 + k] -= y[b] / 2
    return TriangularSystem.from_fields(fields, y, (1, 1, 1, 2, 2, 2))


TRI = free_36()
ST = Step2Structure.from_triangular(TRI)


def goal_of(x: np.ndarray, w: np.ndarray) -> np.ndarray:
    return np.array([x[0], x[1], x[2], w[2], -w[1], w[0]])


def check_reached(geo, goal, start=None) -> None:
    # the exact flow of the plan segments (independent code) reaches the goal
    segs = geodesic_controls(ST, geo)
    reached = endpoint(TRI, np.zeros(6) if start is None else start, segs)
    assert np.max(np.abs(reached - goal)) < 1e-10 * (1 + np.max(np.abs(goal)))


@pytest.mark.parametrize("m", [1, 2, 3])
def test_rodrigues_integrals_are_the_block_exponential(m: int) -> None:
    rng = np.random.default_rng(m)
    for scale in (1e-7, 0.3, 1.99, 2.01, 7.0, 40.0):
        a = rng.normal(size=(3, m, m))
        omega = (a - np.transpose(a, (0, 2, 1))) * scale
        u0 = rng.normal(size=(3, m))
        got, ref = rodrigues_integrals(omega, u0), _van_loan_integrals(omega, u0)
        for g, r in zip(got, ref, strict=True):
            assert np.max(np.abs(g - r)) < 1e-12 * (1 + np.max(np.abs(r)))
        # analytic in (Ω, u₀): the complex-step derivatives agree too
        d_om, d_u = rng.normal(size=omega.shape), rng.normal(size=u0.shape)
        d_om = d_om - np.transpose(d_om, (0, 2, 1))
        h = 1e-30
        got = rodrigues_integrals(omega + 1j * h * d_om, u0 + 1j * h * d_u)
        ref = _van_loan_integrals(omega + 1j * h * d_om, u0 + 1j * h * d_u)
        for g, r in zip(got, ref, strict=True):
            assert np.max(np.abs(g.imag - r.imag)) / h < 1e-11 * (1 + np.max(np.abs(r.imag)) / h)


def test_reduced_area_formula_against_integration() -> None:
    # the reduction's w = |x_⊥|² q e − ½ (x·e) κ x_⊥ of the extremal with axis e, angle θ,
    # integrated numerically (Rodrigues' rotation by hand, w' = ½ h × u)
    rng = np.random.default_rng(5)
    for theta in (0.7, 3.0, 5.9, 7.5, 11.0):
        e = rng.normal(size=3)
        e /= np.linalg.norm(e)
        x = rng.normal(size=3)
        k = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])

        def rot(t, k=k, theta=theta):
            return np.eye(3) + math.sin(theta * t) * k + (1 - math.cos(theta * t)) * k @ k

        flow = np.eye(3) + (1 - math.cos(theta)) / theta * k + (
            1 - math.sin(theta) / theta) * k @ k
        u0 = np.linalg.solve(flow, x)

        def rhs(t, z, rot=rot, u0=u0):
            u = rot(t) @ u0
            return np.concatenate([u, np.cross(z[:3], u) / 2])

        z = solve_ivp(rhs, (0, 1), np.zeros(6), method="DOP853", rtol=1e-12, atol=1e-13).y[:, -1]
        assert np.max(np.abs(z[:3] - x)) < 1e-9
        alpha = x @ e
        perp = x - alpha * e
        q = (theta - math.sin(theta)) / (8 * math.sin(theta / 2) ** 2)
        kappa = 2 / theta - 1 / math.tan(theta / 2)
        assert np.max(np.abs(z[3:] - (perp @ perp * q * e - alpha * kappa * perp / 2))) < 1e-9


def test_x_perpendicular_to_w_is_the_heisenberg_distance_in_every_orientation() -> None:
    rng = np.random.default_rng(20261202)
    for _ in range(20):
        r, area = rng.uniform(0.05, 2.0), rng.uniform(0.0, 2.0) * rng.choice([-1, 1])
        rot = Rotation.random(random_state=rng).as_matrix()
        goal = goal_of(rot @ np.array([r, 0, 0]), rot @ np.array([0, 0, area]))
        geo = shortest_geodesic(ST, np.zeros(6), goal)
        assert geo.length == pytest.approx(heisenberg_distance(r, area), rel=1e-9)
        check_reached(geo, goal)


def test_x_perpendicular_to_w_from_a_start_off_the_origin() -> None:
    # left translation by p: v_ab += (p_a g_b − p_b g_a)/2 on top of p + g
    p, g = np.array([0.3, -0.5, 0.8, 0.1, -0.2, 0.4]), goal_of(
        np.array([0.0, 0.6, 0.0]), np.array([0.0, 0.0, -0.9]))
    goal = p + g
    for k, (a, b) in enumerate([(0, 1), (0, 2), (1, 2)]):
        goal[3 + k] += (p[a] * g[b] - p[b] * g[a]) / 2
    geo = shortest_geodesic(ST, p, goal)
    assert geo.length == pytest.approx(heisenberg_distance(0.6, 0.9), rel=1e-9)
    check_reached(geo, goal, p)


def test_vertical_goals_are_circles() -> None:
    rng = np.random.default_rng(8)
    for _ in range(6):
        w = rng.normal(size=3) * rng.uniform(0.01, 3)
        geo = shortest_geodesic(ST, np.zeros(6), goal_of(np.zeros(3), w))
        assert geo.length == pytest.approx(math.sqrt(4 * math.pi * np.linalg.norm(w)), rel=1e-9)
        check_reached(geo, goal_of(np.zeros(3), w))


def test_rotation_equivariance_and_dilation() -> None:
    rng = np.random.default_rng(9)
    for _ in range(12):
        x, w = rng.normal(size=3) * rng.uniform(0.05, 2), rng.normal(size=3) * rng.uniform(0, 2)
        geo = shortest_geodesic(ST, np.zeros(6), goal_of(x, w))
        check_reached(geo, goal_of(x, w))
        assert geo.length >= np.linalg.norm(x) * (1 - 1e-12)
        circle = math.sqrt(4 * math.pi * np.linalg.norm(w))
        assert abs(geo.length - circle) <= np.linalg.norm(x) * (1 + 1e-12)
        rot = Rotation.random(random_state=rng).as_matrix()
        turned = shortest_geodesic(ST, np.zeros(6), goal_of(rot @ x, rot @ w))
        assert turned.length == pytest.approx(geo.length, rel=1e-9)
        lam = rng.uniform(0.1, 10)
        grown = shortest_geodesic(ST, np.zeros(6), goal_of(lam * x, lam**2 * w))
        assert grown.length == pytest.approx(lam * geo.length, rel=1e-9)


def test_nearly_vertical_goals_approach_the_circle() -> None:
    # |x|² ≪ |w| (θ within ~|x| of 2π, where the equations are ill-conditioned): the
    # length is within |x| of √(4π|w|); a goal 1e-200 away keeps its length (no underflow)
    rng = np.random.default_rng(12)
    for k in range(0, 16, 2):
        x, w = rng.normal(size=3) * 10.0 ** (-k / 1.5), rng.normal(size=3)
        geo = shortest_geodesic(ST, np.zeros(6), goal_of(x, w))
        check_reached(geo, goal_of(x, w))
        circle = math.sqrt(4 * math.pi * np.linalg.norm(w))
        assert abs(geo.length - circle) <= np.linalg.norm(x) * (1 + 1e-9) + 1e-12 * circle
    x = np.array([3e-200, -1e-200, 2e-200])
    geo = shortest_geodesic(ST, np.zeros(6), goal_of(x, np.zeros(3)))
    assert geo.length == pytest.approx(float(np.sqrt(np.sum((x * 1e200) ** 2))) * 1e-200,
                                       rel=1e-12, abs=0)


def test_goals_with_w_parallel_to_x_are_reached() -> None:
    # w ∥ x ≠ 0 has no extremal of rotation angle below 2π (the reduction: w₂ = 0 forces
    # sin φ = 0 there); the previous multi-start failed on these
    for x, c in [((1.0, 0.0, 0.0), 0.3), ((0.3, -0.4, 0.5), -1.0), ((0.0, 0.2, 0.0), 2.0)]:
        xv = np.array(x)
        geo = shortest_geodesic(ST, np.zeros(6), goal_of(xv, c * xv))
        check_reached(geo, goal_of(xv, c * xv))
        assert geo.length > np.linalg.norm(xv)


def _brute_shortest(goal: np.ndarray, rng: np.random.Generator, starts: int) -> float:
    """Shortest normal extremal found by Levenberg–Marquardt from random starts.

    The endpoint comes from Van Loan's block exponential (not the closed forms
    under test), the Jacobian from forward differences; all starts at once.
    """

    def end(z: np.ndarray) -> np.ndarray:
        om = z[:, 3:]
        zero = np.zeros(len(z))
        omega = np.stack([np.stack([zero, -om[:, 2], om[:, 1]], -1),
                          np.stack([om[:, 2], zero, -om[:, 0]], -1),
                          np.stack([-om[:, 1], om[:, 0], zero], -1)], 1)
        u_int, mm = _van_loan_integrals(omega, z[:, :3])
        v = [(mm[:, b, a] - mm[:, a, b]) / 2 for a, b in [(0, 1), (0, 2), (1, 2)]]
        return np.concatenate([u_int, np.stack(v, -1)], 1) - goal

    size = max(float(np.linalg.norm(goal[:3])), math.sqrt(float(np.linalg.norm(goal[3:]))))
    axis = rng.normal(size=(starts, 3))
    z = np.concatenate([
        rng.normal(size=(starts, 3)) * size * rng.uniform(0.5, 4, (starts, 1)),
        axis / np.linalg.norm(axis, axis=1)[:, None] * rng.uniform(0, 5 * math.pi, (starts, 1)),
    ], 1)
    res = end(z)
    mu = np.full(starts, 1e-3)
    h = 1e-7
    for _ in range(100):
        live = (np.max(np.abs(res), axis=1) > 1e-12) & (mu < 1e8)
        if not np.any(live):
            break
        jac = np.stack([(end(z + h * e) - res) / h for e in np.eye(6)], -1)
        jtj = np.transpose(jac, (0, 2, 1)) @ jac + mu[:, None, None] * np.eye(6)
        step = np.linalg.solve(jtj, -np.einsum("sni,sn->si", jac, res)[:, :, None])[:, :, 0]
        cand = end(z + step)
        better = live & (np.sum(cand**2, 1) < np.sum(res**2, 1))
        z[better], res[better] = z[better] + step[better], cand[better]
        mu = np.where(better, mu / 3, mu * 4)
    ok = np.max(np.abs(res), axis=1) < 1e-10
    assert ok.sum() >= 3  # the oracle itself found extremals
    return float(np.min(np.linalg.norm(z[ok, :3], axis=1)))


@pytest.mark.slow
def test_shortest_against_a_brute_multistart() -> None:
    rng = np.random.default_rng(2026)
    goals = [
        goal_of(np.array([0.4, -0.9, 0.4]), np.array([2.7, -0.1, 2.4])),  # |w| ≫ |x|²
        goal_of(np.array([0.36, 0.64, -2.29]), np.array([-0.1, 1.3, 2.4])),  # near the helices
        goal_of(np.array([1.0, 0.0, 0.0]), np.array([0.3, 0.0, 0.0])),  # w ∥ x
        goal_of(np.array([-0.81, -0.40, 0.66]), np.array([-6.6e-4, -1.8e-4, 4.9e-4])),  # w small
        *(goal_of(rng.normal(size=3), rng.normal(size=3)) for _ in range(2)),
    ]
    for goal in goals:
        geo = shortest_geodesic(ST, np.zeros(6), goal)
        check_reached(geo, goal)
        assert geo.length <= _brute_shortest(goal, rng, 40) * (1 + 1e-9)


def test_reduced_solutions_solve_the_reduced_equations() -> None:
    for target in ([0.1, 0.2], [1.0, 0.0], [-0.3, 0.05], [50.0, 3.0], [1e-4, 1e-4]):
        sols = reduced_free3_solutions(np.array(target))
        assert len(sols) > 0
        assert np.all(np.diff(sols[:, 2]) >= 0)  # shortest first
        for phi, theta, length in sols:
            q = (theta - math.sin(theta)) / (8 * math.sin(theta / 2) ** 2)
            kappa = 2 / theta - 1 / math.tan(theta / 2)
            s, c = math.sin(phi), math.cos(phi)
            w = (s * s * c * (q - kappa / 2), s**3 * q + s * c * c * kappa / 2)
            assert np.allclose(w, target, rtol=1e-7, atol=1e-9)
            stretch = theta / (2 * math.sin(theta / 2))
            assert length == pytest.approx(math.hypot(c, s * stretch), rel=1e-12)


def test_trident_snake_approximations_off_the_origin() -> None:
    # the trident snake's nilpotent approximation at a generic state: a free (3,6)-type
    # structure in a non-orthonormal basis; its geodesics reach and are no shorter than
    # the horizontal displacement in the control coordinates
    tri = get_model("trident-snake")
    rng = np.random.default_rng(4)
    for x0 in (np.zeros(6), np.array([0.1, -0.2, 0.3, 0.2, -0.1, 0.05])):
        model = numeric_model(tri, x0)
        st = Step2Structure.from_triangular(model.nilpotent)
        assert st.free3_maps is not None
        for _ in range(4):
            goal = model.forward(x0 + rng.uniform(-0.15, 0.15, size=6))
            geo = shortest_geodesic(st, np.zeros(6), goal)
            segs = geodesic_controls(st, geo)
            reached = endpoint(model.nilpotent, np.zeros(6), segs)
            assert np.max(np.abs(reached - goal)) < 1e-10
            h = list(st.h_index)
            assert geo.length >= np.linalg.norm(np.linalg.solve(st.b, goal[h])) * (1 - 1e-12)
