"""The paper's case (docs/paper-case.md): the trident snake at 0, in the paper's
simplified form (eq. vf, ``trident-snake-paper``) and in body-velocity form
(``trident-snake``).  The paper's printed results are literature values here;
every computed value is re-derived with plain sympy."""

from __future__ import annotations

import dataclasses

import pytest
import sympy as sp

from nilpotent.core.coordinates.approximation import approximate, certify
from nilpotent.models import get_model
from polynomial_systems import (
    function_order,
    growth_vector_at,
    right_normed_brackets,
    sympy_bracket,
)

R3 = sp.sqrt(3)
H = sp.Rational(1, 2)

#: The paper's matrix of Section 5, printed as y = M x.
PAPER_M = sp.Matrix(
    [
        [1, 0, 0, 0, 0, 0],
        [0, 1, 0, 0, 0, 0],
        [0, 0, 1, 0, 0, 0],
        [R3 / 2, H, -2, 1, -1, R3],
        [0, -1, -2, 1, 2, 0],
        [-R3 / 2, H, -2, 1, -1, -R3],
    ]
)


def paper_hat_y(y):
    """The paper's ĝ1, ĝ2, ĝ3 in its coordinates y (Section 6)."""
    y1, y2, y3 = y[:3]
    return (
        (1, 0, 0, -y2 / 2, -y2 / 2 - y3, -y1 / 2),
        (0, 1, 0, y1 / 2, -y1 / 2, y2 / 2 - y3),
        (0, 0, 1, 0, 0, 0),
    )


def paper_hat_x(x):
    """The paper's ĝ1, ĝ2, ĝ3 in x-coordinates (Section 7)."""
    x1, x2, x3 = x[:3]
    return (
        (
            1,
            0,
            0,
            -(x2 + x3),
            -(R3 * x1 / 4 + x2 / 4 - x3 / 2 - R3 / 2),
            R3 * x1 / 2 - x2 / 4 + x3 / 2 - R3 / 2,
        ),
        (
            0,
            1,
            0,
            -1,
            3 * x1 / 4 + R3 * x2 / 4 - R3 * x3 / 2 + H,
            3 * x1 / 4 - R3 * x2 / 4 + R3 * x3 / 2 + H,
        ),
        (0, 0, 1, -2, -2, -2),
    )


@pytest.fixture(scope="module")
def paper():
    return get_model("trident-snake-paper")


@pytest.fixture(scope="module")
def paper_approx(paper):
    return approximate(paper)


def at0(sys, v):
    return [
        sp.nsimplify(sp.simplify(sp.S(e).xreplace(dict.fromkeys(sys.coordinates, 0)))) for e in v
    ]


def test_the_fields_are_the_papers_eq_vf(paper):
    _x1, _x2, _x3, x4, x5, x6 = paper.coordinates
    g = paper.specialized_fields
    pi = sp.pi
    expected = (
        (1, 0, 0, sp.sin(x4 - 2 * pi / 3), sp.sin(x5), sp.sin(x6 + 2 * pi / 3)),
        (0, 1, 0, -sp.cos(x4 - 2 * pi / 3), -sp.cos(x5), -sp.cos(x6 + 2 * pi / 3)),
        (0, 0, 1, -(1 + sp.cos(x4)), -(1 + sp.cos(x5)), -(1 + sp.cos(x6))),
    )
    for f, e in zip(g, expected, strict=True):
        assert [sp.simplify(a - b) for a, b in zip(f, e, strict=True)] == [0] * 6


def test_growth_3_6_both_forms():
    for name in ("trident-snake-paper", "trident-snake"):
        s = get_model(name)
        a = approximate(s)
        assert a.filtration.growth_vector == (3, 6)
        assert growth_vector_at(s.specialized_fields, s.coordinates, (0,) * 6, 3) == (3, 6)
        assert a.certificate.ok


def test_brackets_at_zero_against_the_printed_ones(paper):
    """Eq. (liebrackets): g4 = [g1,g2] is right; g5 = [g2,g3] and g6 = [g1,g3] are not."""
    g = paper.specialized_fields
    x = paper.coordinates
    g4 = at0(paper, sympy_bracket(g[0], g[1], x))
    g5 = at0(paper, sympy_bracket(g[1], g[2], x))
    g6 = at0(paper, sympy_bracket(g[0], g[2], x))
    assert g4 == [0, 0, 0, 1, 1, 1]  # printed: ∂4 + ∂5 + ∂6
    assert g5 == [0, 0, 0, -R3, 0, R3]  # printed: √3∂5 − √3∂6
    assert g6 == [0, 0, 0, -1, 2, -1]  # printed: 2∂4 − ∂5 − ∂6
    # the printed vectors are the computed ones with the φ-components relabelled (4,5,6) → (5,6,4)
    assert [g5[4], g5[5], g5[3]] == [0, R3, -R3]
    assert [g6[4], g6[5], g6[3]] == [2, -1, -1]


def test_privileged_coordinates_and_the_papers_matrix(paper, paper_approx):
    c = paper_approx.coordinates
    assert c.method == "linear"
    assert [sp.simplify(e) for e in c.frame_matrix * c.linear_part - sp.eye(6)] == [0] * 36
    # the paper's M is the frame matrix with the x4 and x6 rows exchanged, not its inverse
    B = sp.Matrix(c.frame_matrix)
    B.row_swap(3, 5)
    assert sp.simplify(PAPER_M - B) == sp.zeros(6)
    assert sp.simplify(PAPER_M * B) != sp.eye(6)
    # the paper's y4, y5, y6 = rows of M x have order 1 (not 2): not privileged
    ypaper = PAPER_M * sp.Matrix(paper.coordinates)
    orders = [
        function_order(paper.specialized_fields, paper.coordinates, e, (0,) * 6, 3) for e in ypaper
    ]
    assert orders == [1, 1, 1, 1, 1, 1]
    # ours are privileged (sympy chains)
    ours = [
        function_order(paper.specialized_fields, paper.coordinates, e, (0,) * 6, 3)
        for e in c.forward
    ]
    assert ours == [1, 1, 1, 2, 2, 2]


def test_approximation_in_y_is_not_the_papers(paper_approx):
    a = paper_approx
    y = a.names
    printed = paper_hat_y(y)
    assert [list(f) for f in a.fields] != [list(f) for f in printed]
    assert a.fields[2] == (0, 0, 1, 0, 0, 0) == printed[2]
    # the paper's ĝ put into our (privileged, same frame order) coordinates fail the certificate
    bad = certify(dataclasses.replace(a, fields=tuple(tuple(sp.S(e) for e in f) for f in printed)))
    assert not bad.remainder_order_ok and bad.homogeneous and not bad.ok


def test_the_papers_hat_g_is_the_body_form_approximation():
    """The printed ĝ are the approximation of the body-velocity form (same frame order)."""
    a = approximate(get_model("trident-snake"))
    assert a.filtration.frame_names == ("X1", "X2", "X3", "[X1,X2]", "[X1,X3]", "[X2,X3]")
    printed = paper_hat_y(a.names)
    assert [
        [sp.expand(u - sp.S(v)) for u, v in zip(f, p, strict=True)]
        for f, p in zip(a.fields, printed, strict=True)
    ] == [[0] * 6] * 3


def test_step_is_2_not_1(paper_approx):
    """Not step 1: brackets of length 2 are nonzero constants, those of length 3 vanish."""
    a = paper_approx
    assert a.certificate.nilpotent_step == 2
    two = right_normed_brackets(a.fields, a.names, 2)
    assert two and all(not sp.Matrix(b).free_symbols for b in two)
    assert right_normed_brackets(a.fields, a.names, 3) == []
    # the paper's own ĝ also have step 2: [ĝ1,ĝ2] = ∂y4, [ĝ1,ĝ3] = ∂y5, [ĝ2,ĝ3] = ∂y6
    y = a.names
    P = paper_hat_y(y)
    e = [tuple(int(k == j) for k in range(6)) for j in range(6)]
    assert sympy_bracket(P[0], P[1], y) == e[3]
    assert sympy_bracket(P[0], P[2], y) == e[4]
    assert sympy_bracket(P[1], P[2], y) == e[5]


def test_approximation_in_x(paper, paper_approx):
    """Ours: X̂_i(0) = g_i(0) and [X̂_i,X̂_j](0) = [g_i,g_j](0); the printed x-form fails both."""
    a = paper_approx
    x = paper.coordinates
    g = paper.specialized_fields
    for fx, f in zip(a.fields_x, g, strict=True):
        assert at0(paper, fx) == at0(paper, f)
    for i, j in ((0, 1), (0, 2), (1, 2)):
        assert at0(paper, sympy_bracket(a.fields_x[i], a.fields_x[j], x)) == at0(
            paper, sympy_bracket(g[i], g[j], x)
        )
    # pulled back with y(x), ours is exactly the y-form (the push-forward used the Jacobian)
    J = a.coordinates.jacobian()
    sub = dict(zip(x, a.coordinates.inverse, strict=True))
    for fx, fy in zip(a.fields_x, a.fields, strict=True):
        assert [sp.expand(e) for e in (J * sp.Matrix(fx)).xreplace(sub)] == [
            sp.expand(e) for e in fy
        ]
    printed = [tuple(sp.S(e) for e in f) for f in paper_hat_x(x)]
    assert at0(paper, printed[0]) != at0(
        paper, g[0]
    )  # [1,0,0,0,√3/2,−√3/2] vs [1,0,0,−√3/2,0,√3/2]
    assert at0(paper, printed[1]) != at0(paper, g[1])
    assert at0(paper, printed[2]) == at0(paper, g[2])
    # the printed ĝ6 = −∂x3 + ½∂x5 + ½∂x6 cannot be a bracket: every x3-component is constant
    assert at0(paper, sympy_bracket(printed[1], printed[2], x)) == [0, 0, 0, 0, R3 / 2, -R3 / 2]
    assert at0(paper, sympy_bracket(printed[0], printed[2], x)) == [0, 0, 0, 1, -H, -H]


def test_body_form_brackets_and_approximation():
    s = get_model("trident-snake")
    a = approximate(s)
    x = s.coordinates
    g = s.specialized_fields
    assert at0(s, sympy_bracket(g[0], g[1], x)) == [0, 0, 0, 1, 1, 1]
    # the paper's printed g5, g6 are the φ-parts of these (∂x, ∂y parts dropped)
    assert at0(s, sympy_bracket(g[1], g[2], x)) == [1, 0, 0, 0, R3, -R3]
    assert at0(s, sympy_bracket(g[0], g[2], x)) == [0, -1, 0, 2, -1, -1]
    for i, j in ((0, 1), (0, 2), (1, 2)):
        assert at0(s, sympy_bracket(a.fields_x[i], a.fields_x[j], x)) == at0(
            s, sympy_bracket(g[i], g[j], x)
        )
    assert a.certificate.nilpotent_step == 2
