"""Trident snake geometry and wheel slip, checked against elementary geometry and integration."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from nilpotent.errors import ModelError, OptionError
from nilpotent.models import get_model
from nilpotent.models.trident import (
    PAPER_LEG_ANGLES,
    TridentGeometry,
    joint_determinant,
    wheel_slip,
)

R, L = 0.7, 1.3
RNG = np.random.default_rng(7)


def random_configs(shape) -> np.ndarray:
    q = RNG.uniform(-math.pi, math.pi, size=(*shape, 6))
    q[..., :2] *= 3
    return q


def compiled(sys):
    f = sp.lambdify(sys.coordinates, sp.Matrix(sys.specialized_fields).T, "numpy")
    return lambda q: np.array(f(*q), dtype=float)  # (6, 3): column a is X_{a+1}


def test_body_is_an_equilateral_triangle_of_circumradius_r():
    geom = TridentGeometry(R, L)
    q = random_configs((40,))
    v = geom.vertices(q)
    assert v.shape == (40, 3, 2)
    centre = geom.body_centre(q)
    assert np.allclose(v.mean(axis=1), centre, atol=1e-12)  # centroid = circumcentre
    assert np.allclose(np.linalg.norm(v - centre[:, None], axis=-1), R, atol=1e-12)
    for i, j in ((0, 1), (1, 2), (0, 2)):
        assert np.allclose(np.linalg.norm(v[:, i] - v[:, j], axis=-1), R * math.sqrt(3))
    # vertex 1 lies along the body heading θ
    d = v[:, 0] - centre
    assert np.allclose(np.arctan2(d[:, 1], d[:, 0]), np.angle(np.exp(1j * q[:, 2])))


def test_legs_have_length_l_and_their_joint_angle():
    geom = TridentGeometry(R, L)
    q = random_configs((5, 7))
    v, w = geom.vertices(q), geom.wheels(q)
    assert w.shape == (5, 7, 3, 2)
    assert np.allclose(np.linalg.norm(w - v, axis=-1), L)
    # angle between the outward radius and the leg is φ_i
    radial = v - geom.body_centre(q)[..., None, :]
    leg = w - v
    cross = radial[..., 0] * leg[..., 1] - radial[..., 1] * leg[..., 0]
    dot = np.sum(radial * leg, axis=-1)
    assert np.allclose(np.exp(1j * np.arctan2(cross, dot)), np.exp(1j * q[..., 3:6]))
    # headings and unit directions
    e, n = geom.leg_directions(q), geom.lateral_directions(q)
    assert np.allclose(np.sum(e * n, axis=-1), 0.0)
    assert np.allclose(leg / L, e)


def test_rest_configuration_is_the_symmetric_star():
    w = TridentGeometry(R, L).wheels(np.zeros(6))
    expected = [
        (R + L) * np.array([math.cos(a), math.sin(a)])
        for a in (0, 2 * math.pi / 3, 4 * math.pi / 3)
    ]
    assert np.allclose(w, expected)


def test_wheel_velocity_is_the_derivative_of_wheel_position():
    geom = TridentGeometry(R, L)
    q = random_configs((30,))
    qd = RNG.normal(size=(30, 6))
    h = 1e-6
    fd = (geom.wheels(q + h * qd) - geom.wheels(q - h * qd)) / (2 * h)
    assert np.allclose(geom.wheel_velocities(q, qd), fd, atol=1e-8)
    lat = geom.lateral_velocities(q, qd)
    assert np.allclose(lat, np.einsum("kij,kj->ki", geom.constraint_matrix(q), qd), atol=1e-12)


@pytest.mark.parametrize("form", ["trident-snake", "trident-snake-joints"])
def test_wheels_move_along_their_legs_when_following_the_fields(form):
    """Integrate ±h along each field (RK4) and look at how the wheels moved."""
    sys = get_model(form, {"r": sp.Rational(7, 10), "l": sp.Rational(13, 10)})
    geom = TridentGeometry.from_system(sys)
    assert (geom.r, geom.l) == (R, L)
    f = compiled(sys)
    h = 1e-3

    def rk4(q, a, step):
        def rhs(z):
            return f(z)[:, a]

        k1 = rhs(q)
        k2 = rhs(q + step / 2 * k1)
        k3 = rhs(q + step / 2 * k2)
        k4 = rhs(q + step * k3)
        return q + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    qs = random_configs((40,))
    # stay away from the joint form's singular set (there the fields blow up)
    qs = qs[np.abs(joint_determinant(qs, geom)) > 0.5 * (R + L)][:10]
    assert len(qs) == 10
    for q in qs:
        for a in range(3):
            dw = (geom.wheels(rk4(q, a, h)) - geom.wheels(rk4(q, a, -h))) / (2 * h)
            n = geom.lateral_directions(q)
            assert np.all(
                np.abs(np.sum(dw * n, axis=-1)) < 1e-5 * (1 + np.linalg.norm(dw, axis=-1))
            )


def _inputs(t):
    return np.array([math.cos(2 * t), 0.5 * math.sin(3 * t), 0.4 * math.cos(t)])


def test_true_system_trajectory_does_not_slip():
    sys = get_model("trident-snake", {"r": sp.Rational(7, 10), "l": sp.Rational(13, 10)})
    f = compiled(sys)
    t = np.linspace(0.0, 2.0, 801)
    sol = solve_ivp(
        lambda s, q: f(q) @ _inputs(s),
        (0, 2),
        [0.1, -0.2, 0.3, 0.2, -0.4, 0.5],
        t_eval=t,
        rtol=1e-11,
        atol=1e-12,
    )
    traj = sol.y.T
    geom = TridentGeometry(R, L)
    fd = wheel_slip(geom, traj, t)
    assert fd.velocity_source == "finite-difference"
    assert fd.lateral_velocity.shape == (801, 3)
    assert np.all(fd.slip_distance < 1e-4) and np.all(fd.max_lateral_speed < 1e-3)
    vel = np.array([f(q) @ _inputs(s) for s, q in zip(t, traj, strict=True)])
    exact = wheel_slip(geom, traj, t, velocities=vel)
    assert exact.velocity_source == "given"
    assert np.all(exact.max_lateral_speed < 1e-12)
    assert exact.total_slip < 1e-12


def test_paper_form_trajectory_slips_as_derived():
    """Along g1 + g2/2 of eq. (vf) (θ stays at θ0) the lateral speed of wheel i is
    (sin β_i − sin(θ0 + β_i)) + (cos(θ0 + β_i) − cos β_i)/2, β_i = c_i + φ_i."""
    sys = get_model("trident-snake-paper")
    f = compiled(sys)
    u = np.array([1.0, 0.5, 0.0])
    c = np.array([float(a) for a in PAPER_LEG_ANGLES])
    for theta0 in (0.0, 0.8):
        t = np.linspace(0.0, 1.5, 1201)
        sol = solve_ivp(
            lambda s, q: f(q) @ u,
            (0, 1.5),
            [0, 0, theta0, 0.3, -0.2, 0.1],
            t_eval=t,
            rtol=1e-11,
            atol=1e-12,
        )
        traj = sol.y.T
        slip = wheel_slip(TridentGeometry(), traj, t, "trident-snake-paper")
        beta = traj[:, 3:6] + c
        th = traj[:, 2:3]
        expected = (np.sin(beta) - np.sin(th + beta)) + 0.5 * (np.cos(th + beta) - np.cos(beta))
        assert np.allclose(slip.lateral_velocity, expected, atol=1e-5)
        same = wheel_slip(TridentGeometry(offsets=PAPER_LEG_ANGLES), traj, t)
        assert np.allclose(same.slip_distance, slip.slip_distance)
        if theta0 == 0.0:
            assert slip.total_slip < 1e-5
        else:
            assert np.all(slip.slip_distance > 0.05)
            assert np.allclose(
                slip.slip_distance, np.trapezoid(np.abs(expected), t, axis=0), rtol=1e-4
            )


def test_bad_inputs_are_refused():
    with pytest.raises(ModelError):
        TridentGeometry(0.0, 1.0)
    with pytest.raises(ModelError):
        TridentGeometry.for_form("trident-snake-2")
    geom = TridentGeometry()
    with pytest.raises(OptionError):
        geom.wheels(np.zeros(5))
    t = np.linspace(0, 1, 5)
    with pytest.raises(OptionError):
        wheel_slip(geom, np.zeros((4, 6)), t)
    with pytest.raises(OptionError):
        wheel_slip(geom, np.zeros((5, 6)), t[::-1])
    with pytest.raises(OptionError):
        wheel_slip(geom, np.zeros((5, 6)), t, velocities=np.zeros((4, 6)))


def test_wrapped_angles_do_not_count_as_slip():
    """The same trajectory with its angles given modulo 2π slips the same."""
    sys = get_model("trident-snake")
    f = compiled(sys)
    t = np.linspace(0.0, 4.0, 2001)
    u = np.array([0.3, 0.0, 2.5])  # turns more than a full circle
    sol = solve_ivp(
        lambda s, q: f(q) @ u, (0, 4), [0, 0, 3.0, 3.0, -3.0, 0.0], t_eval=t, rtol=1e-11, atol=1e-12
    )
    traj = sol.y.T
    wrapped = traj.copy()
    wrapped[:, 2:6] = np.angle(np.exp(1j * traj[:, 2:6]))
    assert np.abs(np.diff(wrapped[:, 2], axis=0)).max() > 6  # it really wraps
    a = wheel_slip(TridentGeometry(), traj, t)
    b = wheel_slip(TridentGeometry(), wrapped, t)
    assert np.allclose(a.lateral_velocity, b.lateral_velocity, atol=1e-9)
    assert b.total_slip < 1e-4
