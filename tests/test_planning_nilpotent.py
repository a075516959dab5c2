"""Exact steering of nilpotent systems: closed-form flow, areas, Newton, controls as data.

Oracles: hand-written Heisenberg / Engel / Goursat normal forms integrated by
scipy's solve_ivp at tight tolerance, hand-derived loop areas, finite
differences.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from nilpotent.errors import PlanningError
from nilpotent.planning import InputSignal, Segment, TriangularSystem, endpoint, steer_nilpotent
from nilpotent.planning.controls import reverse_segments
from nilpotent.planning.exact_flow import endpoint_and_jacobian
from nilpotent.planning.nilpotent import METHODS, bracket_matrix

Y = sp.symbols("y1:6")


def heisenberg() -> tuple[TriangularSystem, list]:
    # X1 = ∂1 − y2/2 ∂3, X2 = ∂2 + y1/2 ∂3: [X1, X2] = ∂3
    fields = [(1, 0, -Y[1] / 2), (0, 1, Y[0] / 2)]
    return TriangularSystem.from_fields(fields, Y[:3], (1, 1, 2)), fields


def engel() -> tuple[TriangularSystem, list]:
    fields = [(1, 0, 0, 0), (0, 1, Y[0], Y[0] ** 2 / 2)]
    return TriangularSystem.from_fields(fields, Y[:4], (1, 1, 2, 3)), fields


def goursat() -> tuple[TriangularSystem, list]:
    fields = [(1, 0, 0, 0, 0), (0, 1, Y[0], Y[0] ** 2 / 2, Y[0] ** 3 / 6)]
    return TriangularSystem.from_fields(fields, Y[:5], (1, 1, 2, 3, 4)), fields


def trident_like() -> tuple[TriangularSystem, list]:
    # three inputs, weights (1,1,1,2,2,2), weight-2 components linear in y1..y3
    y = Y[:3] + sp.symbols("y4:7")
    fields = [
        (1, 0, 0, -y[1] / 2, -y[2] / 2, 0),
        (0, 1, 0, y[0] / 2, 0, -y[2]),
        (0, 0, 1, 0, y[0] / 2, y[1]),
    ]
    return TriangularSystem.from_fields(fields, y, (1, 1, 1, 2, 2, 2)), fields


def integrate(fields, names, y0, segments) -> np.ndarray:
    """Independent oracle: lambdified fields, scipy DOP853 at rtol 1e-13."""
    mat = sp.lambdify([names], sp.Matrix(fields).T, "numpy")
    y = np.asarray(y0, dtype=float)
    for seg in segments:
        def rhs(t, z, seg=seg):
            return np.asarray(mat(z), dtype=float) @ seg.values(t)

        y = solve_ivp(rhs, (0, seg.duration), y, method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1]
    return y


SYSTEMS = {"heisenberg": heisenberg, "engel": engel, "goursat": goursat, "trident": trident_like}


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_closed_form_flow_matches_numerical_integration(name):
    system, fields = SYSTEMS[name]()
    rng = np.random.default_rng(1)
    m = system.m
    segs = [
        Segment(0.8, 1.7, tuple(
            InputSignal(rng.normal(), tuple(rng.normal(size=2)), tuple(rng.normal(size=3)))
            for _ in range(m))),
        Segment(1.3, 4.0, tuple(InputSignal(rng.normal()) for _ in range(m))),
    ]
    y0 = rng.normal(size=system.n) * 0.3
    exact = endpoint(system, y0, segs)
    oracle = integrate(fields, system_names(system), y0, segs)
    assert np.max(np.abs(exact - oracle)) < 1e-11


def system_names(system: TriangularSystem):
    return sp.symbols(" ".join(system.names))


def test_jacobian_matches_finite_differences():
    system, _ = goursat()
    rng = np.random.default_rng(2)
    segs = [
        Segment(1.0, 3.0, (InputSignal(0.2), InputSignal(-0.4))),
        Segment(1.0, 2 * math.pi, tuple(
            InputSignal(rng.normal(), tuple(rng.normal(size=2)), tuple(rng.normal(size=2)))
            for _ in range(2))),
    ]
    y0 = rng.normal(size=5) * 0.2
    value, jac = endpoint_and_jacobian(system, y0, segs, [0, 2])
    assert np.allclose(value, endpoint(system, y0, segs), atol=1e-14)
    # parameter 2 + 5 + 3: second segment, second input, cos[2]... check a few by central FD
    h = 1e-6
    theta_index = {0: (0, 0, "constant", None), 2 + 1: (1, 0, "cos", 0),
                   2 + 5 + 4: (1, 1, "sin", 1)}
    for col, (s_idx, i, kind, k) in theta_index.items():
        vals = []
        for sign in (1, -1):
            new = [list(s.inputs) for s in segs]
            sig = new[s_idx][i]
            if kind == "constant":
                sig = InputSignal(sig.constant + sign * h, sig.cos, sig.sin)
            elif kind == "cos":
                c = list(sig.cos)
                c[k] += sign * h
                sig = InputSignal(sig.constant, tuple(c), sig.sin)
            else:
                c = list(sig.sin)
                c[k] += sign * h
                sig = InputSignal(sig.constant, sig.cos, tuple(c))
            new[s_idx][i] = sig
            vals.append(endpoint(system, y0, [
                Segment(s.duration, s.omega, tuple(inp)) for s, inp in zip(segs, new, strict=True)
            ]))
        fd = (vals[0] - vals[1]) / (2 * h)
        assert np.allclose(jac[:, col], fd, atol=1e-7)


@pytest.mark.parametrize("k", [1, 2, 3])
def test_loop_area_hand_derivation(k):
    """u1 = α sin(kωt), u2 = β cos(kωt) over one period moves Heisenberg's y3 by −αβπ/(kω²)."""
    system, fields = heisenberg()
    alpha, beta, omega = 0.7, -1.3, 2.0
    cos = [0.0] * k
    sin = [0.0] * k
    sin[k - 1] = alpha
    cos[k - 1] = beta
    seg = Segment(2 * math.pi / omega, omega, (InputSignal(0, (), tuple(sin)),
                                              InputSignal(0, tuple(cos), ())))
    expected = -alpha * beta * math.pi / (k * omega**2)
    y = integrate(fields, Y[:3], np.zeros(3), [seg])
    assert y[2] == pytest.approx(expected, abs=1e-11)
    assert np.allclose(endpoint(system, np.zeros(3), [seg]), [0, 0, expected], atol=1e-14)


def test_bracket_matrix_of_heisenberg_and_trident_like():
    h, _ = heisenberg()
    assert np.allclose(bracket_matrix(h), [[0], [0], [1]])
    t, fields = trident_like()
    names = system_names(t)
    # independent: sympy brackets [Xa, Xb] = DXb·Xa − DXa·Xb at 0
    mats = [sp.Matrix(f) for f in fields]
    jac = [m.jacobian(names) for m in mats]
    cols = []
    for a in range(3):
        for b in range(a + 1, 3):
            br = jac[b] * mats[a] - jac[a] * mats[b]
            cols.append([float(v) for v in br.subs(dict.fromkeys(names, 0))])
    assert np.allclose(bracket_matrix(t), np.array(cols).T)


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_steering_reaches_goal_exactly(name):
    system, fields = SYSTEMS[name]()
    rng = np.random.default_rng(3)
    for _ in range(3):
        start = rng.normal(size=system.n) * 0.2
        goal = rng.normal(size=system.n) * 0.4
        result = steer_nilpotent(system, start, goal)
        assert result.error < 1e-12
        oracle = integrate(fields, system_names(system), start, result.segments)
        assert np.max(np.abs(oracle - goal)) < 1e-9


@pytest.mark.parametrize("name", ["heisenberg", "trident"])
def test_step2_closed_form_is_exact_without_polishing(name):
    system, _ = SYSTEMS[name]()
    rng = np.random.default_rng(4)
    start = rng.normal(size=system.n) * 0.3
    goal = rng.normal(size=system.n) * 0.3
    segments = METHODS["step2"](system, start, goal, 0)
    assert len(segments) == 2
    assert np.max(np.abs(endpoint(system, start, segments) - goal)) < 1e-13


def test_controls_scale_with_distance():
    """Homogeneity: the size of the controls is proportional to the quasi-distance."""
    system, _ = trident_like()
    goal = np.array([0.1, -0.2, 0.05, 0.03, -0.02, 0.01])
    sizes = []
    for lam in (0.1, 0.01):
        res = steer_nilpotent(system, np.zeros(6), system.dilate(goal, lam))
        sizes.append(sum(s.l1_norm() for s in res.segments))
    assert sizes[1] == pytest.approx(sizes[0] / 10, rel=1e-9)


def test_reversed_segments_retrace():
    system, _ = engel()
    rng = np.random.default_rng(5)
    segs = [Segment(0.7, 3.0, (InputSignal(0.3, (0.2, 0.1), (0.4,)),
                               InputSignal(-0.5, (), (0.3,)))),
            Segment(1.1, 2.0, (InputSignal(0.1), InputSignal(0.2, (0.5,), ())))]
    y0 = rng.normal(size=4)
    back = endpoint(system, endpoint(system, y0, segs), reverse_segments(segs))
    assert np.allclose(back, y0, atol=1e-12)


def test_non_triangular_fields_are_refused():
    with pytest.raises(PlanningError, match="not triangular"):
        TriangularSystem.from_fields([(1, Y[1]), (0, 1)], Y[:2], (1, 1))
    with pytest.raises(PlanningError, match="not a polynomial"):
        TriangularSystem.from_fields([(1, 0, sp.sin(Y[0])), (0, 1, 0)], Y[:3], (1, 1, 2))


def test_step2_method_refuses_higher_step():
    system, _ = engel()
    with pytest.raises(PlanningError, match="step"):
        steer_nilpotent(system, np.zeros(4), np.ones(4) * 0.1, method="step2")


def test_segment_json_round_trip():
    seg = Segment(2.0, 1.5, (InputSignal(0.1, (0.2, 0.3), (0.4,)), InputSignal(-1.0)))
    assert Segment.from_dict(seg.to_dict()) == seg


@settings(max_examples=25, deadline=None)
@given(
    c=st.floats(-2, 2), a=st.floats(-2, 2), b=st.floats(-2, 2),
    duration=st.floats(0.1, 5), omega=st.floats(0.2, 5),
)
def test_segment_integral_matches_quadrature(c, a, b, duration, omega):
    sig = InputSignal(c, (0.0, a), (b,))
    t = np.linspace(0, duration, 20001)
    f = sig.value(t, omega)
    quad = float(np.sum((f[1:] + f[:-1]) * np.diff(t)) / 2)
    assert sig.integral(duration, omega) == pytest.approx(quad, abs=1e-6)


def test_bracket_loop_convention_of_docs_conventions():
    """``u1 = −Aω sin ωt, u2 = Aω cos ωt`` over one period moves Heisenberg by ``πA²[X1,X2]``."""
    system, _ = heisenberg()
    amp, omega = 0.3, 1.7
    seg = Segment(2 * math.pi / omega, omega, (InputSignal(0, (), (-amp * omega,)),
                                               InputSignal(0, (amp * omega,), ())))
    assert np.allclose(endpoint(system, np.zeros(3), [seg]), [0, 0, math.pi * amp**2],
                       atol=1e-14)


@settings(max_examples=30, deadline=None)
@given(
    start=st.lists(st.floats(-1, 1), min_size=6, max_size=6),
    goal=st.lists(st.floats(-1, 1), min_size=6, max_size=6),
)
def test_step2_steering_exact_for_any_start_and_goal(start, goal):
    system, _ = trident_like()
    result = steer_nilpotent(system, start, goal)
    assert result.error <= 1e-12 * max(1.0, max(abs(g) for g in goal))
    assert np.allclose(endpoint(system, start, result.segments), goal, atol=1e-11)


def test_sampled_exact_trajectory_matches_integration():
    from nilpotent.planning.exact_flow import sample

    system, fields = engel()
    segs = [Segment(0.9, 2.0, (InputSignal(0.3, (0.2,), (0.4,)), InputSignal(-0.5, (), (0.3,)))),
            Segment(1.1, 3.0, (InputSignal(0.1), InputSignal(0.2, (0.5,), ())))]
    y0 = np.array([0.1, -0.1, 0.2, 0.0])
    times, states = sample(system, y0, segs, points_per_segment=10)
    assert times.shape == (21,) and states.shape == (21, 4)
    assert np.allclose(states[-1], endpoint(system, y0, segs), atol=1e-14)
    assert np.allclose(states[10], integrate(fields, Y[:4], y0, segs[:1]), atol=1e-11)
