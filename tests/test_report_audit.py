"""The audit of the paper: verdicts against hand derivations, and verdicts that follow edits.

Hand derivations used below (bracket ``[X,Y] = DY·X − DX·Y``):

* eq. vf has ``g_a = e_a + Σ_i f_{a,i}(x_{3+i}) ∂x_{3+i}`` with
  ``f_1 = sin β, f_2 = −cos β, f_3 = −(1 + cos φ)``, ``β = c + φ``,
  ``c = (−2π/3, 0, 2π/3)``.  Hence ``[g_a, g_b]`` has only φ-components
  ``f_a f_b' − f_b f_a'``; at φ = 0: ``[g1,g2] = (1, 1, 1)``,
  ``[g2,g3] = 2 sin c = (−√3, 0, √3)``, ``[g1,g3] = 2 cos c = (−1, 2, −1)``.
* The Section 4 fields (body velocities) have ``[g2,g3](0) = ∂x + (0, √3, −√3)``
  and ``[g1,g3](0) = −∂y + (2, −1, −1)`` in the same way, with ``c = (0, 2π/3, 4π/3)``
  and the rotation ``R_θ`` contributing the ∂x, ∂y parts.
* The printed ĝ of Section 6 have ``[ĝ1,ĝ2] = ∂y4 ≠ 0``: the step is 2, not 1.
"""

from __future__ import annotations

import json

import pytest
import sympy as sp

from nilpotent.errors import OptionError
from nilpotent.report import AUDIT_SCHEMA, read_paper, run_audit
from nilpotent.report.audit import CHECKS
from nilpotent.report.paper import paper_source

r3 = sp.sqrt(3)


@pytest.fixture(scope="module")
def audit():
    return run_audit()


def test_schema_and_entries(audit) -> None:
    data = json.loads(json.dumps(audit.to_json()))
    assert data["schema"] == AUDIT_SCHEMA
    keys = {"id", "section", "statement", "paper", "computed", "verdict", "explanation"}
    ids = [e["id"] for e in data["entries"]]
    assert len(ids) == len(set(ids)) >= 30
    for e in data["entries"]:
        assert set(e) == keys
        assert e["verdict"] in ("agrees", "differs")
        assert all(isinstance(e[k], str) and e[k] for k in keys)
    assert data["summary"]["agrees"] + data["summary"]["differs"] == len(ids)


# verdicts that follow from the hand derivations in the module docstring
AGREES = [
    "sec1-growth-vector",
    "sec4-growth-regular",
    "sec4-field-g1",
    "sec4-field-g2",
    "sec4-field-g3",
    "sec4-bracket-g4",
    "fig-figg4-motion",
    "fig-figg6-motion",
    "sec6-weights",
    "sec6-bracket-g4",
    "sec6-bracket-g5",
    "sec6-bracket-g6",
    "sec7-input-v1",
    "sec7-motions-coincide",
    "sec7-approx-x-g3",
    "sec7-approx-x-g4",
    "sec6-homogeneous-form",
    "sec5-component-g1-x1",
]
DIFFERS = [
    "sec4-bracket-g5",
    "sec4-bracket-g6",
    "fig-figg5-motion",
    "sec5-matrix-condition",
    "sec5-privileged",
    "sec6-step",
    "sec4-sec7-bracket-names",
    "sec7-input-v2",
    "sec7-input-v3",
    "sec4-vf-same-system",
    "sec5-component-g1-x4",
    "sec7-motions-coincide-printed",
    "sec6-first-order",
]


@pytest.mark.parametrize("entry_id", AGREES)
def test_agrees(audit, entry_id: str) -> None:
    assert audit.entry(entry_id).verdict == "agrees", audit.entry(entry_id)


@pytest.mark.parametrize("entry_id", DIFFERS)
def test_differs(audit, entry_id: str) -> None:
    assert audit.entry(entry_id).verdict == "differs", audit.entry(entry_id)


def test_computed_brackets_are_the_hand_derived_ones(audit) -> None:
    assert audit.entry("sec4-bracket-g5").computed == "-sqrt(3)*∂x4 + sqrt(3)*∂x6"
    assert audit.entry("sec4-bracket-g6").computed == "-∂x4 + 2*∂x5 - ∂x6"


def _audit_of(source: str, *groups: str):
    return run_audit(read_paper(source), only=groups)


def test_corrected_brackets_are_accepted() -> None:
    src = paper_source()
    src = src.replace(
        r"g_5&= \sqrt 3\partial x_5-\sqrt 3\partial x_6",
        r"g_5&= -\sqrt 3\partial x_4+\sqrt 3\partial x_6",
    )
    src = src.replace(
        r"g_6&= 2\partial x_4-\partial x_5-\partial x_6",
        r"g_6&= -\partial x_4+2\partial x_5-\partial x_6",
    )
    result = _audit_of(src, "eq. liebrackets")
    assert {e.id: e.verdict for e in result.entries} == {
        "sec4-bracket-g4": "agrees",
        "sec4-bracket-g5": "agrees",
        "sec4-bracket-g6": "agrees",
    }


def test_a_wrong_field_is_flagged() -> None:
    src = paper_source().replace(
        r"g_3 &=\partial_\theta-(1+\cos\phi_1)", r"g_3 &=\partial_\theta-(1+\sin\phi_1)"
    )
    result = _audit_of(src, "Section 4 fields")
    assert result.entry("sec4-field-g3").verdict == "differs"
    assert result.entry("sec4-field-g1").verdict == "agrees"


def _latex(v: sp.Expr) -> str:
    return sp.latex(sp.nsimplify(v)).replace(r"\left(", "(").replace(r"\right)", ")")


def _correct_matrix_source() -> str:
    # G(0) by hand: g1(0), g2(0), g3(0), [g1,g2](0), [g2,g3](0), [g1,g3](0) (Section 4 names)
    half = sp.Rational(1, 2)
    cols = [
        (1, 0, 0, -r3 / 2, 0, r3 / 2),
        (0, 1, 0, half, -1, half),
        (0, 0, 1, -2, -2, -2),
        (0, 0, 0, 1, 1, 1),
        (0, 0, 0, -r3, 0, r3),
        (0, 0, 0, -1, 2, -1),
    ]
    m = sp.Matrix(cols).T.inv()
    body = r"\\".join(" & ".join(_latex(m[i, j]) for j in range(6)) for i in range(6))
    src = paper_source()
    start = src.index(r"\begin{pmatrix}" + "\n\t" + r"\phantom{-}1")
    end = src.index(r"\end{pmatrix}", start)
    return src[:start] + r"\begin{pmatrix}\phantom{-}" + body + "\n" + src[end:]


def test_the_correct_matrix_is_accepted() -> None:
    result = _audit_of(_correct_matrix_source(), "privileged coordinates")
    for entry in result.entries:
        assert entry.verdict == "agrees", entry


def test_the_correct_approximation_is_accepted() -> None:
    # The weighted truncation of eq. vf in the coordinates y = G(0)^{-1} x above, derived
    # separately (sympy series of M g(M^{-1} y) in t with y_k -> t^{w_k} y_k):
    src = _correct_matrix_source()
    old1 = (
        r"\hat g_1&=  \partial_{y_1}-\frac{y_2}{2}\partial_{y_4}+(-\frac{y_2}{2}-y_3)"
        r"\partial_{y_5}-\frac{y_1}{2}\partial_{y_6}"
    )
    new1 = (
        r"\hat g_1&=  \partial_{y_1}-\frac{y_2}{2}\partial_{y_4}-\frac{y_1}{4}\partial_{y_5}"
        r"+(-\frac{y_2}{4}-y_3)\partial_{y_6}"
    )
    old2 = (
        r"\hat g_2&= \partial_{y_2}+\frac{y_1}{2}\partial_{y_4}-\frac{y_1}{2}\partial_{y_5}"
        r"+(\frac{y_2}{2}-y_3)\partial_{y_6}"
    )
    new2 = (
        r"\hat g_2&= \partial_{y_2}+\frac{y_1}{2}\partial_{y_4}+(\frac{y_2}{4}-y_3)"
        r"\partial_{y_5}-\frac{y_1}{4}\partial_{y_6}"
    )
    assert old1 in src and old2 in src
    src = src.replace(old1, new1).replace(old2, new2)
    result = _audit_of(src, "nilpotent approximation", "first order")
    for entry in result.entries:
        assert entry.verdict == "agrees", entry


def test_corrected_step_and_pairing_are_accepted() -> None:
    src = paper_source().replace("step $r=1$", "step $r=2$")
    src = src.replace(
        r"\hat g_5=[\hat g_1,\hat g_3], \hat g_6=[\hat g_2,\hat g_3],$ respectively",
        r"\hat g_6=[\hat g_2,\hat g_3], \hat g_5=[\hat g_1,\hat g_3],$ respectively",
    )
    result = _audit_of(src, "nilpotency step", "periodic inputs")
    assert all(e.verdict == "agrees" for e in result.entries), result.entries


def test_unknown_group_is_refused() -> None:
    with pytest.raises(OptionError, match="unknown audit checks"):
        run_audit(only=["no such check"])


def test_every_group_has_a_name() -> None:
    names = [n for n, _ in CHECKS]
    assert len(names) == len(set(names))


def test_a_family_with_wrong_weight_one_part_is_not_an_approximation() -> None:
    src = paper_source().replace(
        r"\hat g_3 &=\partial_{y_3}.", r"\hat g_3 &=\partial_{y_3}+\partial_{y_1}."
    )
    assert src != paper_source()
    result = _audit_of(src, "nilpotent approximation")
    assert result.entry("sec6-approx-family").verdict == "differs"
