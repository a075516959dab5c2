"""The trident snake forms checked against the robot's physics, not against the code.

The wheel positions are written here from the robot's description
(``W_i = (x, y) + r u(θ + α_i) + l u(θ + α_i + φ_i)``, ``u(a) = (cos a, sin a)``)
and differentiated by sympy; no side slip means ``n_i · Ẇ_i = 0`` with
``n_i = (−sin ψ_i, cos ψ_i)``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

from nilpotent.models import get_model
from nilpotent.models.trident import BODY_LEG_ANGLES, PAPER_LEG_ANGLES

R_TEST, L_TEST = sp.Rational(7, 10), sp.Rational(13, 10)
RNG = np.random.default_rng(20261123)


def random_configs(k: int, spread: float = math.pi) -> np.ndarray:
    q = RNG.uniform(-spread, spread, size=(k, 6))
    q[:, :2] *= 2
    return q


def lateral_velocity_exprs(sys, offsets, r, l, *, symbolic=False):
    """n_i · (dW_i/dq · X_a) for each field X_a and wheel i: sympy expressions.

    ``symbolic``: use the fields with their parameter symbols (else substituted).
    """
    x, y, th, *phis = sys.coordinates
    out = []
    for field in sys.fields if symbolic else sys.specialized_fields:
        row = []
        for a, p in zip(offsets, phis, strict=True):
            psi = th + a + p
            w = sp.Matrix([x, y]) + r * sp.Matrix([sp.cos(th + a), sp.sin(th + a)])
            w += l * sp.Matrix([sp.cos(psi), sp.sin(psi)])
            vel = sum(
                (sp.diff(w, c) * field[j] for j, c in enumerate(sys.coordinates)), sp.zeros(2, 1)
            )
            row.append(-sp.sin(psi) * vel[0] + sp.cos(psi) * vel[1])
        out.append(row)
    return out


def numeric(exprs, coords):
    f = sp.lambdify(coords, exprs, "numpy")
    return lambda q: np.array(f(*q), dtype=float)


def bracket(a, b, coords):
    """[A, B] = DB·A − DA·B."""
    n = len(coords)
    return tuple(
        sum(a[j] * sp.diff(b[i], coords[j]) - b[j] * sp.diff(a[i], coords[j]) for j in range(n))
        for i in range(n)
    )


# --- the body-velocity form ---------------------------------------------------------------


def test_body_form_rolls_without_side_slip_symbolically():
    sys = get_model("trident-snake")
    r, l = sp.symbols("r l")
    for row in lateral_velocity_exprs(sys, BODY_LEG_ANGLES, r, l, symbolic=True):
        for e in row:  # exact: in exponentials the expression expands to 0
            assert sp.expand(sp.expand(sp.expand_trig(e)).rewrite(sp.exp)) == 0
    # the fields above were the symbolic ones (parameters r, l left free)
    assert {str(s) for f in sys.fields for e in f for s in e.free_symbols} >= {"r", "l"}


def test_body_form_inputs_are_body_frame_velocities():
    sys = get_model("trident-snake")
    th = sys.coordinates[2]
    rot = sp.Matrix([[sp.cos(th), -sp.sin(th)], [sp.sin(th), sp.cos(th)]])
    for a, v in enumerate(([1, 0], [0, 1])):
        planar = rot * sp.Matrix(v)
        assert sp.Matrix(sys.fields[a][:2]) == planar
        assert sys.fields[a][2] == 0
    assert sys.fields[2][:3] == (0, 0, 1)


def test_body_form_with_unit_sizes_is_the_papers_section_4():
    """Section 4 of the paper, typed in from the text (angles 0, 2π/3, 4π/3)."""
    sys = get_model("trident-snake")
    _, _, th, p1, p2, p3 = sys.coordinates
    t = 2 * sp.pi / 3
    g1 = (sp.cos(th), sp.sin(th), 0, sp.sin(p1), sp.sin(p2 + t), sp.sin(p3 + 2 * t))
    g2 = (-sp.sin(th), sp.cos(th), 0, -sp.cos(p1), -sp.cos(p2 + t), -sp.cos(p3 + 2 * t))
    g3 = (0, 0, 1, -(1 + sp.cos(p1)), -(1 + sp.cos(p2)), -(1 + sp.cos(p3)))
    for ours, paper in zip(sys.specialized_fields, (g1, g2, g3), strict=True):
        assert all(sp.simplify(a - b) == 0 for a, b in zip(ours, paper, strict=True))


def test_body_form_growth_is_3_6_everywhere_with_the_hand_derived_determinant():
    """det(X1, X2, X3, [X1,X2], [X2,X3], [X1,X3]) = −(3√3/2) r²/l⁶ at every point."""
    sys = get_model("trident-snake", {"r": R_TEST, "l": L_TEST})
    c = sys.coordinates
    g = sys.specialized_fields
    frame = [*g, bracket(g[0], g[1], c), bracket(g[1], g[2], c), bracket(g[0], g[2], c)]
    det_at = numeric(sp.Matrix(frame).T, c)
    expected = -1.5 * math.sqrt(3) * float(R_TEST) ** 2 / float(L_TEST) ** 6
    for q in random_configs(25):
        assert np.linalg.det(det_at(q)) == pytest.approx(expected, rel=1e-10)


def test_body_form_brackets_at_origin_versus_the_papers_list():
    """The paper prints g4 = [g1,g2], g5 = [g2,g3], g6 = [g1,g3] at 0 (eq. liebrackets).

    For the body form (r = l = 1) the φ-parts agree with the print, and the
    brackets also move the root: g5 has +∂x, g6 has −∂y (the paper's figures
    say the root moves along x for g5 and along y for g6).
    """
    sys = get_model("trident-snake")
    c = sys.coordinates
    g = sys.specialized_fields
    at0 = {s: 0 for s in c}
    s3 = sp.sqrt(3)
    b12 = [sp.nsimplify(e.subs(at0)) for e in bracket(g[0], g[1], c)]
    b23 = [sp.nsimplify(e.subs(at0)) for e in bracket(g[1], g[2], c)]
    b13 = [sp.nsimplify(e.subs(at0)) for e in bracket(g[0], g[2], c)]
    assert b12 == [0, 0, 0, 1, 1, 1]
    assert b23 == [1, 0, 0, 0, s3, -s3]
    assert b13 == [0, -1, 0, 2, -1, -1]


# --- the paper's simplified form -----------------------------------------------------------


def test_paper_form_is_eq_vf_as_printed():
    sys = get_model("trident-snake-paper")
    *_, x4, x5, x6 = sys.coordinates
    t = 2 * sp.pi / 3
    g1 = (1, 0, 0, sp.sin(x4 - t), sp.sin(x5), sp.sin(x6 + t))
    g2 = (0, 1, 0, -sp.cos(x4 - t), -sp.cos(x5), -sp.cos(x6 + t))
    g3 = (0, 0, 1, -(1 + sp.cos(x4)), -(1 + sp.cos(x5)), -(1 + sp.cos(x6)))
    for ours, paper in zip(sys.fields, (g1, g2, g3), strict=True):
        assert all(sp.simplify(a - b) == 0 for a, b in zip(ours, paper, strict=True))


def test_paper_form_violates_no_slip_where_and_by_how_much():
    """Read with its own offsets c = (−2π/3, 0, 2π/3): exact on θ = 0 only.

    Lateral velocity of wheel i along g1: sin β_i − sin(θ + β_i), along g2:
    cos(θ + β_i) − cos β_i (β_i = c_i + φ_i); g3 never slips.  Per wheel the
    (g1, g2) pair has Euclidean size 2|sin(θ/2)|.  Read with the Section 4
    placement (0, 2π/3, 4π/3) the size is 2|sin(θ/2 + π/3)|: √3 at the origin.
    """
    sys = get_model("trident-snake-paper")
    c = sys.coordinates
    for offsets, shift in ((PAPER_LEG_ANGLES, 0.0), (BODY_LEG_ANGLES, 2 * math.pi / 3)):
        res = numeric(lateral_velocity_exprs(sys, offsets, 1, 1), c)
        qs = np.vstack([np.zeros(6), random_configs(30)])
        for q in qs:
            v = res(q)  # v[a, i]: field a, wheel i
            assert np.allclose(v[2], 0.0, atol=1e-12)  # g3 rolls
            size = np.hypot(v[0], v[1])
            assert np.allclose(size, 2 * abs(math.sin((q[2] + shift) / 2)), atol=1e-12)
            if shift == 0.0:
                beta = q[3:6] + np.array([float(a) for a in PAPER_LEG_ANGLES])
                assert np.allclose(v[0], np.sin(beta) - np.sin(q[2] + beta), atol=1e-12)
                assert np.allclose(v[1], np.cos(q[2] + beta) - np.cos(beta), atol=1e-12)
        origin = res(np.zeros(6))
        if shift == 0.0:
            assert np.allclose(origin, 0.0, atol=1e-15)
        else:
            assert np.allclose(np.hypot(origin[0], origin[1]), math.sqrt(3), atol=1e-12)


def test_paper_form_is_not_the_body_form():
    """Same fields at θ = 0 up to the offsets, but different brackets."""
    paper = get_model("trident-snake-paper")
    cp = paper.coordinates
    g = paper.fields
    at0 = {s: 0 for s in cp}
    s3 = sp.sqrt(3)
    b23 = [sp.nsimplify(e.subs(at0)) for e in bracket(g[1], g[2], cp)]
    b13 = [sp.nsimplify(e.subs(at0)) for e in bracket(g[0], g[2], cp)]
    # no ∂x1, ∂x2 parts, and the φ-parts are those of offsets (−2π/3, 0, 2π/3):
    assert b23 == [0, 0, 0, -s3, 0, s3]
    assert b13 == [0, 0, 0, -1, 2, -1]


def test_paper_singular_set_matches_the_frame_determinant():
    from nilpotent.models.trident import paper_singular_determinant, paper_singularity

    sys = get_model("trident-snake-paper")
    c = sys.coordinates
    g = sys.fields
    frame = [*g, bracket(g[0], g[1], c), bracket(g[1], g[2], c), bracket(g[0], g[2], c)]
    det_at = numeric(sp.Matrix(frame).T, c)
    qs = random_configs(20)
    ours = paper_singular_determinant(qs)
    assert ours.shape == (20,)
    for q, d in zip(qs, ours, strict=True):
        assert d == pytest.approx(np.linalg.det(det_at(q)), abs=1e-10)
    # a constructed singular point: wheel 1 folded onto the centre (x4 = π) and the
    # other two wheels on one line through it: x6 = x5 + 2(c2 − c3) = x5 − 4π/3
    q = np.array([0.3, -1.0, 0.7, math.pi, 0.3, 0.3 - 4 * math.pi / 3])
    assert abs(np.linalg.det(det_at(q))) < 1e-12
    sing = paper_singularity(q)
    assert sing.singular and "collinear" in sing.description
    p = sing.wheel_points
    assert abs(np.linalg.det(np.column_stack([p[1] - p[0], p[2] - p[0]]))) < 1e-12
    assert not paper_singularity(np.zeros(6)).singular


# --- the joint-velocity form ----------------------------------------------------------------


def test_joint_form_rolls_without_side_slip_at_random_points():
    sys = get_model("trident-snake-joints", {"r": R_TEST, "l": L_TEST})
    res = numeric(lateral_velocity_exprs(sys, BODY_LEG_ANGLES, R_TEST, L_TEST), sys.coordinates)
    for q in random_configs(40):
        assert np.allclose(res(q), 0.0, atol=1e-12)


def test_joint_form_inputs_are_the_joint_rates_and_span_the_body_distribution():
    joints = get_model("trident-snake-joints", {"r": R_TEST, "l": L_TEST})
    body = get_model("trident-snake", {"r": R_TEST, "l": L_TEST})
    for i, f in enumerate(joints.fields):
        assert f[3:] == tuple(sp.Integer(int(i == j)) for j in range(3))
    fj = numeric(sp.Matrix(joints.specialized_fields).T, joints.coordinates)
    fb = numeric(sp.Matrix(body.specialized_fields).T, body.coordinates)
    for q in random_configs(20):
        assert np.linalg.matrix_rank(np.hstack([fj(q), fb(q)]), tol=1e-9) == 3


def _phi_through(point, alpha, r, l):
    """Joint angles φ with the axle of the leg at ``alpha`` (θ = 0, body at 0) through ``point``."""
    from scipy.optimize import brentq

    def g(phi):
        psi = alpha + phi
        e = np.array([math.cos(psi), math.sin(psi)])
        w = r * np.array([math.cos(alpha), math.sin(alpha)]) + l * e
        return float(e @ (np.asarray(point) - w))

    grid = np.linspace(-math.pi, math.pi, 721)
    vals = [g(p) for p in grid]
    for a, b, va, vb in zip(grid[:-1], grid[1:], vals[:-1], vals[1:], strict=True):
        if va * vb < 0:
            return brentq(g, a, b, xtol=1e-15)
    raise AssertionError("no root")


def test_joint_singularity_when_axles_are_concurrent_or_parallel():
    from nilpotent.models.trident import (
        TridentGeometry,
        joint_determinant,
        joint_singularity,
    )

    r, l = float(R_TEST), float(L_TEST)
    geom = TridentGeometry(r, l)
    alphas = [float(a) for a in BODY_LEG_ANGLES]
    # concurrent: every axle through P
    target = np.array([2.5, 1.5])  # farther than l from every vertex
    q = np.array([0.0, 0.0, 0.0, *(_phi_through(target, a, r, l) for a in alphas)])
    # the test's own 3×3 matrix of the constraints in (ẋ, ẏ, θ̇)
    psi = np.array(alphas) + q[3:]
    m = np.column_stack([-np.sin(psi), np.cos(psi), r * np.cos(q[3:]) + l])
    assert abs(np.linalg.det(m)) < 1e-12
    assert abs(joint_determinant(q, geom)) < 1e-12
    sing = joint_singularity(q, geom)
    assert sing.singular and sing.kind == "concurrent"
    assert np.allclose(sing.point, target, atol=1e-9)
    # the fields blow up next to it
    sys = get_model("trident-snake-joints", {"r": R_TEST, "l": L_TEST})
    fj = numeric(sp.Matrix(sys.specialized_fields).T, sys.coordinates)
    near = q + np.array([0, 0, 0, 1e-7, 0, 0])
    assert np.abs(fj(near)).max() > 1e4
    # parallel: all legs along one direction β
    beta = 0.9
    q = np.array([1.0, 2.0, 0.3, *(beta - 0.3 - a for a in alphas)])
    sing = joint_singularity(q, geom)
    assert sing.singular and sing.kind == "parallel" and sing.point is None
    # regular at the rest configuration, with D = (3√3/2)(r + l)
    sing = joint_singularity(np.zeros(6), geom)
    assert not sing.singular and sing.kind == "regular"
    assert sing.determinant == pytest.approx(1.5 * math.sqrt(3) * (r + l), rel=1e-12)


def test_joint_determinant_matches_the_matrix_at_random_points():
    from nilpotent.models.trident import TridentGeometry, joint_determinant

    r, l = float(R_TEST), float(L_TEST)
    qs = random_configs(50)
    psi = qs[:, 2:3] + np.array([float(a) for a in BODY_LEG_ANGLES]) + qs[:, 3:]
    m = np.stack([-np.sin(psi), np.cos(psi), r * np.cos(qs[:, 3:]) + l], axis=-1)
    assert np.allclose(joint_determinant(qs, TridentGeometry(r, l)), np.linalg.det(m), atol=1e-12)


def test_constraint_residuals_agree_with_the_derivation():
    """Body and joint forms: identically 0; paper form: the closed forms of the docs."""
    from nilpotent.models.trident import constraint_residuals

    body = constraint_residuals(get_model("trident-snake", {"r": R_TEST, "l": L_TEST}))
    assert all(sp.expand(sp.expand_trig(e).rewrite(sp.exp)) == 0 for row in body for e in row)
    paper = get_model("trident-snake-paper")
    res = constraint_residuals(paper)
    x3 = paper.coordinates[2]
    for i, (c, phi) in enumerate(zip(PAPER_LEG_ANGLES, paper.coordinates[3:], strict=True)):
        beta = c + phi
        assert sp.simplify(res[0][i] - (sp.sin(beta) - sp.sin(x3 + beta))) == 0
        assert sp.simplify(res[1][i] - (sp.cos(x3 + beta) - sp.cos(beta))) == 0
        assert res[2][i] == 0
    joints = get_model("trident-snake-joints", {"r": R_TEST, "l": L_TEST})
    val = numeric(constraint_residuals(joints), joints.coordinates)
    for q in random_configs(10):
        assert np.allclose(val(q), 0.0, atol=1e-12)
