"""Section 6 of the paper: weights, the nilpotent approximation, its form, step and brackets."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import sympy as sp

from nilpotent.core.lie.brackets import bracket
from nilpotent.core.model.expressions import as_expr
from nilpotent.report.audit.compare import (
    fmt,
    format_field,
    matrix_text,
    printed_field,
    push_forward,
    same_exprs,
    vanishes_identically,
)
from nilpotent.report.audit.computed import Computed
from nilpotent.report.audit.entries import AuditEntry, make_entry
from nilpotent.report.paper import PaperContent, X, Y


def _bracket_y(a: Sequence[sp.Expr], b: Sequence[sp.Expr]) -> tuple[sp.Expr, ...]:
    return bracket(a, b, Y)


def check_weights(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    ours = c.vf_filtration.weights
    yield make_entry(
        "sec6-weights",
        "6",
        f"The coordinate weights are {tuple(paper.weights)}.",
        paper.weights_text,
        str(ours),
        tuple(ours) == tuple(paper.weights),
        "weights of the filtration at 0 (analyze)",
    )


def check_approximation(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    approx = c.approximation
    ours_y = approx.fields
    names = approx.coordinates.names
    for k, printed in enumerate(paper.approximation_y):
        trunc = c.paper_y_truncation[k]
        low = c.paper_y_low_terms[k]
        ok = same_exprs(printed.components, trunc)
        ours_k = [
            as_expr(v).subs(dict(zip(approx.coordinates.names, Y, strict=True))) for v in ours_y[k]
        ]
        if ok:
            why = f"equals the terms of weighted degree w_j − 1 of g{k + 1} in y = M x"
            if same_exprs(printed.components, ours_k):
                why += f" and approximate()'s X̂{k + 1}"
        else:
            why = (
                f"the weighted truncation of g{k + 1} in the paper's y = M x is "
                f"{format_field(trunc, Y)}"
            )
        if any(not vanishes_identically(v) for v in low):
            why += (
                f"; g{k + 1} also has terms of lower weighted degree in y "
                f"({format_field(low, Y)}), so y is not privileged"
            )
        yield make_entry(
            f"sec6-approx-g{k + 1}",
            printed.section,
            f"ĝ{k + 1} (Section 6) is g{k + 1}^(−1), the part of weighted degree −1 of g{k + 1} "
            "written in the coordinates y = M x of Section 5.",
            printed_field(printed),
            format_field(trunc, Y),
            ok,
            why,
        )
    # Is the printed family a nilpotent approximation in *some* privileged coordinates?
    # Both families have weight-1 components e_i, weight-2 components linear in y1..y3.
    # Nilpotent approximations in two privileged coordinate systems differ by a graded change
    # y'_{4..6} = L y_{4..6} + q(y1, y2, y3) (q quadratic), under which the weight-2 parts
    # become L·(ours) + grad q and the (constant) brackets L·(ours).  So L is fixed by the
    # brackets, and the printed family is such an approximation iff printed − L·ours is, in
    # each weight-2 component, the gradient of a quadratic (symmetric Jacobian).
    sub = list(zip(names, Y, strict=True))
    ours_in_y = [[as_expr(v).subs(sub) for v in f] for f in ours_y]
    printed_y = [f.components for f in paper.approximation_y]
    pairs = ((1, 2), (1, 3), (2, 3))

    def bracket_matrix(fields: Sequence[Sequence[sp.Expr]]) -> sp.Matrix:
        cols = [_bracket_y(fields[i - 1], fields[j - 1]) for i, j in pairs]
        return sp.Matrix([[sp.expand(col[r]) for col in cols] for r in range(3, 6)])

    b_printed, b_ours = bracket_matrix(printed_y), bracket_matrix(ours_in_y)
    ok = (
        all(same_exprs(printed_y[k][:3], ours_in_y[k][:3]) for k in range(3))
        and not (b_printed.free_symbols | b_ours.free_symbols)
        and b_ours.det() != 0
        and b_printed.det() != 0
    )
    change = sp.zeros(3, 3)
    if ok:
        change = (b_printed * b_ours.inv()).applyfunc(sp.simplify)
        rest = [
            sp.Matrix(printed_y[k][3:]) - change * sp.Matrix(ours_in_y[k][3:]) for k in range(3)
        ]
        ok = all(
            vanishes_identically(sp.diff(rest[a][r], Y[b]) - sp.diff(rest[b][r], Y[a]))
            for r in range(3)
            for a in range(3)
            for b in range(3)
        )
    yield make_entry(
        "sec6-approx-family",
        "6",
        "(ĝ1, ĝ2, ĝ3) is a nilpotent approximation of (g1, g2, g3) at 0 in some privileged "
        "coordinates (whatever y is).",
        "; ".join(printed_field(f) for f in paper.approximation_y),
        "approximate(): "
        + "; ".join(f"X̂{k + 1} = {format_field(f, names)}" for k, f in enumerate(ours_y)),
        ok,
        (
            "the printed fields equal approximate()'s after the graded change of coordinates "
            f"(y4, y5, y6) → {matrix_text(change)}·(y4, y5, y6) + quadratics in y1, y2, y3: "
            "a nilpotent approximation, in other privileged coordinates"
        )
        if ok
        else "no homogeneous change of coordinates maps approximate()'s fields to the printed ones",
    )


def _is_form(expr: sp.Expr, degree: int) -> bool:
    """Whether ``expr`` is a homogeneous polynomial of ``degree`` in y1, y2, y3 only."""
    e = sp.expand(as_expr(expr))
    if e == 0:
        return True
    if e.free_symbols - set(Y[:3]):
        return False
    poly = sp.Poly(e, *Y[:3])
    return all(sum(m) == degree for m in poly.monoms())


def check_homogeneous_form(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    w = paper.weights
    bad = [
        f"{f.name}: {fmt(v)} along ∂y{j + 1}"
        for f in paper.approximation_y
        for j, v in enumerate(f.components)
        if not _is_form(v, w[j] - 1)
    ]
    yield make_entry(
        "sec6-homogeneous-form",
        paper.homogeneous_text.section,
        "In (ĝ1, ĝ2, ĝ3) the ∂y1..∂y3 components are constants and the ∂y4..∂y6 components "
        "are linear forms in y1, y2, y3 (homogeneous of degree −1).",
        paper.homogeneous_text.text,
        "components of the printed ĝ: " + ("all of that form" if not bad else "; ".join(bad)),
        not bad,
        "checked on the printed Section 6 fields (weights (1,1,1,2,2,2))"
        if not bad
        else "some components are not of weighted degree w_j − 1",
    )


def check_first_order(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    """Read in the paper's y = M x, is the printed ĝ a first-order approximation of vf?"""
    m = sp.Matrix(paper.privileged_matrix)
    forward = dict(zip(Y, list(m * sp.Matrix(X)), strict=True))
    hat_x = push_forward([f.components for f in paper.approximation_y], m.inv(), Y, forward)
    fields = c.vf.specialized_fields
    printed = [
        c.field_order([g - h for g, h in zip(fields[i], hat_x[i], strict=True)]) for i in range(3)
    ]
    ours = [
        c.field_order([g - h for g, h in zip(fields[i], c.approximation.fields_x[i], strict=True)])
        for i in range(3)
    ]
    ok = all(o >= 0 for o in printed)
    yield make_entry(
        "sec6-first-order",
        paper.step_text.section,
        "Read in the coordinates y = M x of Section 5, the printed (ĝ1, ĝ2, ĝ3) is a first-order "
        "approximation of (g1, g2, g3) at 0: every gi − ĝi has order ≥ 0.",
        paper.step_text.text,
        "ord_0(gi − ĝi) = "
        + ", ".join(str(o) for o in printed)
        + "; for approximate()'s X̂i: "
        + ", ".join(str(o) for o in ours),
        ok,
        "orders computed in approximate()'s privileged coordinates (the mathematics page of "
        "the documentation, §3)"
        + (
            ""
            if ok
            else ": the printed fields, read in the paper's y, are not a first-order "
            "approximation (the remainders are of negative order)"
        ),
    )


def check_step(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    fields = [f.components for f in paper.approximation_y]
    length2 = [_bracket_y(fields[i], fields[j]) for i, j in ((0, 1), (0, 2), (1, 2))]
    nonzero2 = any(not all(vanishes_identically(v) for v in b) for b in length2)
    length3 = [_bracket_y(fields[a], b) for a in range(3) for b in length2]
    zero3 = all(all(vanishes_identically(v) for v in b) for b in length3)
    step = 1 if not nonzero2 else (2 if zero3 else 3)
    cert = c.approximation.certificate.nilpotent_step
    yield make_entry(
        "sec6-step",
        paper.step_text.section,
        f"(ĝ1, ĝ2, ĝ3) generates a nilpotent Lie algebra of step r = {paper.step_claim}: all "
        f"brackets of length greater than {paper.step_claim} vanish.",
        paper.step_text.text,
        f"printed ĝ: brackets of length 2 {'nonzero' if nonzero2 else 'zero'}, of length 3 "
        f"{'zero' if zero3 else 'nonzero'} → step {step}; approximate(): step {cert}",
        step == paper.step_claim and cert == paper.step_claim,
        f"e.g. [ĝ1,ĝ2] = {format_field(length2[0], Y)} ≠ 0; the step is the filtration's "
        f"r = {len(paper.growth_claim)}"
        if step != paper.step_claim
        else "computed",
    )


def check_hat_brackets(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    """Section 6's ĝ4..ĝ6, read with Section 7's naming, where the hatted names are defined.

    The clash with Section 4's naming of g5, g6 is its own entry
    (``sec4-sec7-bracket-names``), so it is not counted twice here.
    """
    fields = [f.components for f in paper.approximation_y]
    labels = paper.bracket_labels_sec7
    for printed in paper.approximation_brackets_y:
        k = int(printed.name[1:])
        i, j = labels[k]
        ours = _bracket_y(fields[i - 1], fields[j - 1])
        ok = same_exprs(printed.components, ours)
        other = [
            kk
            for kk, (a, b) in paper.bracket_labels_sec4.items()
            if same_exprs(printed.components, _bracket_y(fields[a - 1], fields[b - 1]))
        ]
        why = f"[ĝ{i},ĝ{j}] of the printed ĝ (Section 7 defines ĝ{k} = [ĝ{i},ĝ{j}])"
        if not ok and other:
            a, b = paper.bracket_labels_sec4[other[0]]
            why = (
                f"[ĝ{i},ĝ{j}] = {format_field(ours, Y)}; the printed value is [ĝ{a},ĝ{b}], "
                "Section 4's naming"
            )
        yield make_entry(
            f"sec6-bracket-g{k}",
            printed.section,
            f"ĝ{k} = [ĝ{i},ĝ{j}] (Section 7's naming) equals "
            f"{format_field(printed.components, Y)}.",
            printed_field(printed),
            format_field(ours, Y),
            ok,
            why,
        )


def check_labels(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    s4, s7 = paper.bracket_labels_sec4, paper.bracket_labels_sec7

    def show(lab: dict[int, tuple[int, int]], hat: str) -> str:
        return ", ".join(f"{hat}{k} = [{hat}{i},{hat}{j}]" for k, (i, j) in sorted(lab.items()))

    ok = s4 == s7
    swapped = [k for k in s4 if s4.get(k) != s7.get(k)]
    yield make_entry(
        "sec4-sec7-bracket-names",
        "7",
        "The brackets are named consistently: Section 4's g4, g5, g6 and Section 7's "
        "ĝ4, ĝ5, ĝ6 are the same brackets.",
        f"Section 4: {show(s4, 'g')}; Section 7: {show(s7, 'ĝ')}",
        "the same name for the same bracket in both sections"
        if ok
        else f"names {', '.join(f'g{k}' for k in swapped)} denote different brackets",
        ok,
        "consistent" if ok else "g5 and g6 are swapped between Section 4 and Section 7",
    )
