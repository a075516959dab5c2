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
from nilpotent.models import get_model
from nilpotent.report import AUDIT_SCHEMA, read_paper, run_audit
from nilpotent.report.audit import CHECKS
from nilpotent.report.paper import paper_source
from polynomial_systems import growth_vector_at

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


# --- verdicts derived here from the paper's printed objects (no list of expected verdicts) ---
def _verdict(same: bool) -> str:
    return "agrees" if same else "differs"


def _plain_bracket(x, y, coords) -> list:
    """``[X, Y] = DY·X − DX·Y`` with plain sympy."""
    jx, jy = sp.Matrix(x).jacobian(coords), sp.Matrix(y).jacobian(coords)
    return list(jy * sp.Matrix(x) - jx * sp.Matrix(y))


def _equal(a, b) -> bool:
    if len(a) != len(b):
        return False
    return all(sp.simplify(sp.S(u) - sp.S(v)) == 0 for u, v in zip(a, b, strict=True))


def _vf():
    return get_model("trident-snake-paper").specialized()


@pytest.mark.parametrize("k", [4, 5, 6])
def test_printed_bracket_verdict_follows_the_bracket_by_plain_sympy(audit, k: int) -> None:
    paper = read_paper()
    vf = _vf()
    i, j = paper.bracket_labels_sec4[k]
    origin = dict.fromkeys(vf.coordinates, 0)
    f = vf.specialized_fields
    ours = [sp.simplify(v.subs(origin)) for v in _plain_bracket(f[i - 1], f[j - 1], vf.coordinates)]
    (printed,) = [b for b in paper.bracket_values if b.name == f"g{k}"]
    assert audit.entry(f"sec4-bracket-g{k}").verdict == _verdict(_equal(printed.components, ours))


@pytest.mark.parametrize("k", [1, 2, 3])
def test_section4_field_verdict_follows_the_no_slip_model(audit, k: int) -> None:
    paper = read_paper()
    body = get_model("trident-snake", {"r": 1, "l": 1}).specialized()
    rename = dict(zip(body.coordinates, paper.section4_fields[k - 1].coordinates, strict=True))
    model = [sp.S(v).xreplace(rename) for v in body.specialized_fields[k - 1]]
    same = _equal(paper.section4_fields[k - 1].components, model)
    assert audit.entry(f"sec4-field-g{k}").verdict == _verdict(same)


def test_growth_and_weight_verdicts_follow_the_growth_vector_by_plain_sympy(audit) -> None:
    paper = read_paper()
    for spec in ("trident-snake", "trident-snake-paper"):
        sys = get_model(spec).specialized()
        growth = growth_vector_at(sys.specialized_fields, sys.coordinates, sys.origin(), 4)
        assert audit.entry("sec1-growth-vector").verdict == _verdict(growth == paper.growth_claim)
    weights = tuple(
        k + 1
        for k, (lo, hi) in enumerate(zip((0, *growth), growth, strict=False))
        for _ in range(hi - lo)
    )
    assert audit.entry("sec6-weights").verdict == _verdict(weights == tuple(paper.weights))


def test_step_verdict_follows_the_printed_approximations_brackets(audit) -> None:
    paper = read_paper()
    y = paper.approximation_y[0].coordinates
    fields = [f.components for f in paper.approximation_y]
    length2 = [_plain_bracket(a, b, y) for a in fields for b in fields]
    length3 = [_plain_bracket(a, b, y) for a in fields for b in length2]
    nonzero = [any(sp.simplify(v) != 0 for v in b) for b in (*length2, *length3)]
    step = 3 if any(nonzero[len(length2) :]) else (2 if any(nonzero[: len(length2)]) else 1)
    assert audit.entry("sec6-step").verdict == _verdict(step == paper.step_claim)


def test_privileged_verdict_follows_the_orders_of_the_linear_coordinates(audit) -> None:
    """Linear ``y = M x`` at 0: ``ord(y_j) = 1`` unless row j kills g1(0), g2(0), g3(0).

    The weights are (1, 1, 1, 2, 2, 2) and the step is 2, so ``y`` is privileged
    exactly when rows 4–6 of ``M`` vanish on the distribution at 0 and ``M`` is
    invertible.
    """
    paper = read_paper()
    vf = _vf()
    m = sp.Matrix(paper.privileged_matrix)
    origin = dict.fromkeys(vf.coordinates, 0)
    g0 = sp.Matrix([[sp.S(v).subs(origin) for v in f] for f in vf.specialized_fields]).T
    rows = sp.simplify(m[3:, :] * g0)
    privileged = rows == sp.zeros(3, 3) and sp.simplify(m.det()) != 0
    assert audit.entry("sec5-privileged").verdict == _verdict(privileged)


@pytest.mark.parametrize("position", [0, 1, 2])
def test_periodic_input_verdict_follows_the_convention(audit, position: int) -> None:
    """``u_i = −Aω sin ωt, u_j = Aω cos ωt`` realises ``[g_i, g_j]`` (``docs/conventions.md``)."""
    paper = read_paper()
    inp = paper.periodic_inputs[position]
    t, amp, omega = sp.symbols("t A omega")
    sin_part = [
        i + 1
        for i, c in enumerate(inp.components)
        if sp.simplify(
            sp.S(c).subs({"t": t, "A": amp, "omega": omega}) + amp * omega * sp.sin(omega * t)
        )
        == 0
    ]
    cos_part = [
        j + 1
        for j, c in enumerate(inp.components)
        if sp.simplify(
            sp.S(c).subs({"t": t, "A": amp, "omega": omega}) - amp * omega * sp.cos(omega * t)
        )
        == 0
    ]
    target = paper.bracket_labels_sec7[paper.periodic_targets[position]]
    realised = (sin_part[0], cos_part[0]) if sin_part and cos_part else None
    entry = audit.entry(f"sec7-input-{inp.name.replace('_', '')}")
    assert entry.verdict == _verdict(realised == target)


def test_every_check_group_yields_entries_of_its_own(audit) -> None:
    ids_by_group = {name: [e.id for e in run_audit(only=[name]).entries] for name, _ in CHECKS}
    assert all(ids_by_group.values())
    flat = [i for ids in ids_by_group.values() for i in ids]
    assert flat == [e.id for e in audit.entries]  # the full audit is the groups in order


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
