"""Section 7 of the paper: the approximation in ``x``, bracket motions, periodic inputs."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import sympy as sp

from nilpotent.core.lie.brackets import bracket
from nilpotent.core.model.expressions import as_expr
from nilpotent.report.audit.compare import (
    fmt_rate,
    format_field,
    printed_field,
    push_forward,
    same_exprs,
    vanishes_identically,
)
from nilpotent.report.audit.computed import Computed
from nilpotent.report.audit.entries import AuditEntry, make_entry
from nilpotent.report.paper import OMEGA, A, PaperContent, T, X, Y


def check_approximation_x(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    m = sp.Matrix(paper.privileged_matrix)
    minv = m.inv()
    forward = dict(zip(Y, list(m * sp.Matrix(X)), strict=True))
    printed_y = [f.components for f in paper.approximation_y] + [
        f.components for f in paper.approximation_brackets_y
    ]
    own = push_forward(printed_y, minv, Y, forward)
    approx = c.approximation
    ours_x = list(approx.fields_x)
    labels = paper.bracket_labels_sec7
    for k in (4, 5, 6):
        i, j = labels[k]
        ours_x.append(c.bracket_at_origin(c.vf, i, j))
    for k, printed in enumerate(paper.approximation_x):
        own_ok = same_exprs(printed.components, own[k])
        ours_ok = same_exprs(printed.components, ours_x[k])
        ok = own_ok or ours_ok
        name = f"ĝ{k + 1}"
        what = (
            "the correct approximation's field"
            if k < 3
            else f"the bracket [g{labels[k + 1][0]},g{labels[k + 1][1]}](0)"
        )
        if own_ok and ours_ok:
            why = "equals both the pushforward of Section 6 by M⁻¹ and " + what
        elif own_ok:
            why = "equals the pushforward of the Section 6 field by the paper's M⁻¹"
        elif ours_ok:
            why = (
                f"equals {what} (approximate()), but not the pushforward of Section 6's "
                f"{name} by the paper's M⁻¹ ({format_field(own[k], X)})"
            )
        else:
            why = (
                f"neither the pushforward of Section 6's {name} by M⁻¹ "
                f"({format_field(own[k], X)}) nor {what} ({format_field(ours_x[k], X)})"
            )
        yield make_entry(
            f"sec7-approx-x-g{k + 1}",
            printed.section,
            f"{name} written in the coordinates x1..x6 (Section 7).",
            printed_field(printed),
            format_field(ours_x[k], X),
            ok,
            why,
        )


def check_motions_coincide(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    labels = paper.bracket_labels_sec7
    printed_hat = {
        int(f.name[1:]): f.components for f in paper.approximation_x if int(f.name[1:]) >= 4
    }
    printed_orig = {int(f.name[1:]): f.components for f in paper.bracket_values}
    # With the paper's own printed values (Section 7's ĝk vs the bracket it names).
    mismatched = []
    for k, (i, j) in sorted(labels.items()):
        s4_name = next(kk for kk, p in paper.bracket_labels_sec4.items() if p == (i, j))
        if not same_exprs(printed_hat[k], printed_orig[s4_name]):
            mismatched.append(
                f"ĝ{k} = [ĝ{i},ĝ{j}] is printed {format_field(printed_hat[k], X)} "
                f"but g{s4_name} = [g{i},g{j}] is {format_field(printed_orig[s4_name], X)}"
            )
    yield make_entry(
        "sec7-motions-coincide-printed",
        paper.brackets_coincide_text.section,
        "With the printed values, the bracket fields ĝ4, ĝ5, ĝ6 (Section 7) equal the original "
        "brackets g4, g5, g6 at 0 (eq. liebrackets).",
        paper.brackets_coincide_text.text,
        "; ".join(mismatched) if mismatched else "all three printed pairs equal",
        not mismatched,
        "the paper's own Section 7 values contradict its claim"
        if mismatched
        else "the printed values agree",
    )
    # The claim as mathematics: brackets of the approximation at 0 = brackets of g at 0.
    approx = c.approximation
    names = approx.coordinates.names
    jac = sp.Matrix([[sp.diff(xf, yv) for yv in names] for xf in approx.coordinates.inverse])
    at0 = [(yv, 0) for yv in names]
    rows = []
    ok = True
    for i, j in ((1, 2), (1, 3), (2, 3)):
        hat = bracket(approx.fields[i - 1], approx.fields[j - 1], names)
        hat_x = jac.subs(at0) * sp.Matrix([as_expr(v).subs(at0) for v in hat])
        orig = c.bracket_at_origin(c.vf, i, j)
        same = same_exprs(list(hat_x), orig)
        ok = ok and same
        rows.append(f"[X̂{i},X̂{j}](0) = {format_field([sp.simplify(v) for v in hat_x], X)}")
    yield make_entry(
        "sec7-motions-coincide",
        paper.brackets_coincide_text.section,
        "The Lie bracket motions of the nilpotent approximation at 0 coincide with the original "
        "ones: [ĝi,ĝj](0) = [gi,gj](0).",
        paper.brackets_coincide_text.text,
        "; ".join(rows),
        ok,
        "holds for the approximation approximate() builds (brackets pushed to x at 0)"
        if ok
        else "the brackets of approximate()'s fields differ from the original ones at 0",
    )


def _input_pair(components: Sequence[sp.Expr]) -> tuple[int, int] | None:
    sin_part = -A * OMEGA * sp.sin(OMEGA * T)
    cos_part = A * OMEGA * sp.cos(OMEGA * T)
    i = [k for k, v in enumerate(components) if vanishes_identically(v - sin_part)]
    j = [k for k, v in enumerate(components) if vanishes_identically(v - cos_part)]
    zero = [k for k, v in enumerate(components) if vanishes_identically(v)]
    if len(i) == 1 and len(j) == 1 and len(zero) == len(components) - 2:
        return i[0] + 1, j[0] + 1
    return None


def check_inputs(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    labels7 = paper.bracket_labels_sec7
    for inp, target in zip(paper.periodic_inputs, paper.periodic_targets, strict=True):
        pair = _input_pair(inp.components)
        if pair is None:
            yield make_entry(
                f"sec7-input-{inp.name.replace('_', '')}",
                "7",
                f"{inp.name} is a periodic bracket input.",
                f"{inp.name}(t) = {inp.latex}",
                "not of the form (−Aω sin ωt, Aω cos ωt) on two inputs",
                False,
                "unrecognised input",
            )
            continue
        i, j = pair
        realised = next((k for k, p in labels7.items() if p == (i, j)), None)
        rate = c.displacement_rate(c.vf, i, j)
        expected = c.bracket_at_origin(c.vf, i, j)
        sim_ok = max(abs(r - float(v)) for r, v in zip(rate, expected, strict=True)) < 1e-3
        target_pair = labels7[target]
        ok = (i, j) == target_pair and sim_ok
        label_k = inp.label.rsplit("input", 1)[-1]
        why = (
            f"u{i} = −Aω sin ωt, u{j} = Aω cos ωt moves the state by πA²[g{i},g{j}](0) "
            f"(simulated Δx/(πA²) → {fmt_rate(rate)})"
        )
        if (i, j) != target_pair:
            why += (
                f": it realises ĝ{realised} = [ĝ{i},ĝ{j}], not ĝ{target} = "
                f"[ĝ{target_pair[0]},ĝ{target_pair[1]}]"
            )
            if label_k == str(realised):
                why += f" (its equation label {inp.label} names the right bracket)"
        yield make_entry(
            f"sec7-input-{inp.name.replace('_', '')}",
            "7",
            f"The periodic input {inp.name} (listed for ĝ{target} = "
            f"[ĝ{target_pair[0]},ĝ{target_pair[1]}], 'respectively'; label {inp.label}) "
            f"realises ĝ{target}.",
            f"{inp.name}(t) = {inp.latex}",
            f"realises [g{i},g{j}] = ĝ{realised} (Section 7's naming)",
            ok,
            why,
        )
