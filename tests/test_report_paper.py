"""Reading the paper: the parsed values against the paper's text typed in by hand."""

from __future__ import annotations

import pytest
import sympy as sp

from nilpotent.errors import ExpressionError
from nilpotent.report.paper import X, Y, paper_source, read_paper

r3 = sp.sqrt(3)


@pytest.fixture(scope="module")
def paper():
    return read_paper()


def same(a, b) -> bool:
    return all(sp.simplify(sp.S(u) - sp.S(v)) == 0 for u, v in zip(a, b, strict=True))


def test_section4_fields(paper) -> None:
    _x, _y, th, p1, p2, p3 = X
    g1 = (
        sp.cos(th),
        sp.sin(th),
        0,
        sp.sin(p1),
        sp.sin(p2 + 2 * sp.pi / 3),
        sp.sin(p3 + 4 * sp.pi / 3),
    )
    g3 = (0, 0, 1, -(1 + sp.cos(p1)), -(1 + sp.cos(p2)), -(1 + sp.cos(p3)))
    assert [f.name for f in paper.section4_fields] == ["g1", "g2", "g3"]
    assert same(paper.section4_fields[0].components, g1)
    assert same(paper.section4_fields[2].components, g3)
    assert paper.section4_fields[0].section == "4"


def test_vf_and_brackets(paper) -> None:
    x4, x5, x6 = X[3:]
    g2 = (0, 1, 0, -sp.cos(x4 - 2 * sp.pi / 3), -sp.cos(x5), -sp.cos(x6 + 2 * sp.pi / 3))
    assert same(paper.vf_fields[1].components, g2)
    assert paper.bracket_labels_sec4 == {4: (1, 2), 5: (2, 3), 6: (1, 3)}
    assert same(paper.bracket_values[1].components, (0, 0, 0, 0, r3, -r3))
    assert same(paper.bracket_values[2].components, (0, 0, 0, 2, -1, -1))


def test_matrix_and_weights(paper) -> None:
    m = paper.privileged_matrix
    assert m.shape == (6, 6)
    assert list(m.row(3)) == [r3 / 2, sp.Rational(1, 2), -2, 1, -1, r3]
    assert list(m.row(5)) == [-r3 / 2, sp.Rational(1, 2), -2, 1, -1, -r3]
    assert paper.weights == (1, 1, 1, 2, 2, 2)


def test_section6_and_7(paper) -> None:
    y1, y2, y3 = Y[:3]
    g1 = (1, 0, 0, -y2 / 2, -y2 / 2 - y3, -y1 / 2)
    assert same(paper.approximation_y[0].components, g1)
    assert [f.name for f in paper.approximation_brackets_y] == ["ĝ4", "ĝ5", "ĝ6"]
    assert len(paper.approximation_x) == 6
    x1, x2, x3 = X[:3]
    g1x = (
        1,
        0,
        0,
        -(x2 + x3),
        -(r3 * x1 / 4 + x2 / 4 - x3 / 2 - r3 / 2),
        r3 * x1 / 2 - x2 / 4 + x3 / 2 - r3 / 2,
    )  # the continued line is joined
    assert same(paper.approximation_x[0].components, g1x)
    assert paper.bracket_labels_sec7 == {4: (1, 2), 5: (1, 3), 6: (2, 3)}
    assert paper.periodic_targets == (4, 5, 6)
    assert [p.label for p in paper.periodic_inputs] == [
        "periodic_input4",
        "periodic_input6",
        "periodic_input5",
    ]


def test_claims(paper) -> None:
    assert paper.growth_claim == (3, 6)
    assert paper.step_claim == 1
    claims = {c.bracket: c for c in paper.motion_claims}
    assert claims[4].root == "stays" and claims[4].ratios == (1, 1, 1)
    assert claims[5].root == "x" and claims[5].ratios == (1, 0, -1)
    assert claims[6].root == "y" and claims[6].ratios == (-2, 1, 1)
    ex = {(c.field, c.coordinate): c.value for c in paper.component_examples}
    assert ex[1, 4] == sp.sin(X[2] + X[5])


def test_a_changed_source_is_read_as_changed() -> None:
    src = paper_source().replace(
        r"g_5&= \sqrt 3\partial x_5-\sqrt 3\partial x_6",
        r"g_5&= -\sqrt 3\partial x_4+\sqrt 3\partial x_6",
    )
    assert src != paper_source()
    changed = read_paper(src)
    assert same(changed.bracket_values[1].components, (0, 0, 0, -r3, 0, r3))


def test_a_missing_formula_is_an_error() -> None:
    src = paper_source().replace(r"\label{liebrackets}", r"\label{other}")
    with pytest.raises(ExpressionError, match="liebrackets"):
        read_paper(src)
