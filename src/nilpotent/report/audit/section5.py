"""Section 5 of the paper: the frame's components at 0 and the coordinates ``y = M x``."""

from __future__ import annotations

from collections.abc import Iterable

import sympy as sp

from nilpotent.core.model.expressions import as_expr
from nilpotent.report.audit.compare import (
    at_origin,
    fmt,
    fmt_vec,
    matrix_text,
    printed_matrix,
    vanishes_identically,
)
from nilpotent.report.audit.computed import Computed
from nilpotent.report.audit.entries import AuditEntry, make_entry
from nilpotent.report.paper import PaperContent, X


def check_components(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    for ex in paper.component_examples:
        ours = c.vf.specialized_fields[ex.field - 1][ex.coordinate - 1]
        ok = vanishes_identically(ex.value - ours)
        yield make_entry(
            f"sec5-component-g{ex.field}-x{ex.coordinate}",
            "5",
            f"Example: the x{ex.coordinate}-component of g{ex.field} (eq. vf) is {fmt(ex.value)}.",
            ex.latex,
            fmt(ours),
            ok,
            "read off eq. vf"
            if ok
            else f"eq. vf gives [g^{ex.coordinate}_{ex.field}]_x = {fmt(ours)}",
        )


def check_privileged(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    m = sp.Matrix(paper.privileged_matrix)
    labels_tried = {
        "Section 4 names": paper.bracket_labels_sec4,
        "Section 7 names": paper.bracket_labels_sec7,
    }
    products = {
        name: (m * c.frame_matrix(lab, c.vf)).applyfunc(sp.simplify)
        for name, lab in labels_tried.items()
    }
    printed = sp.Matrix(
        [
            [at_origin(f, X)[r] for f in c.vf.specialized_fields]
            + [b.components[r] for b in paper.bracket_values]
            for r in range(6)
        ]
    )
    products["printed eq. liebrackets"] = (m * printed).applyfunc(sp.simplify)
    ok_any = [n for n, p in products.items() if p == sp.eye(6)]
    correct = c.frame_matrix(paper.bracket_labels_sec4, c.vf).inv()
    yield make_entry(
        "sec5-matrix-condition",
        "5",
        "The linear map y = M x of Section 5 satisfies ∂/∂y_i|_0 = g_i|_0 for i = 1..6 "
        "(g4, g5, g6 the brackets of eq. liebrackets).",
        "M = " + printed_matrix(paper.privileged_matrix_latex),
        "M must be [g1(0) … g6(0)]⁻¹ = " + matrix_text(correct.applyfunc(sp.simplify)),
        bool(ok_any),
        ("holds with " + ok_any[0])
        if ok_any
        else "M·[g1(0) … g6(0)] ≠ I with either naming of g5, g6 and with the printed bracket "
        "values; row 4 of M·G(0) is " + fmt_vec(list(products["Section 4 names"].row(3))),
    )
    g0 = [at_origin(f, X) for f in c.vf.specialized_fields]
    rows_ok = all(
        vanishes_identically(as_expr(sum(m[r, j] * g[j] for j in range(6))))
        for r in (3, 4, 5)
        for g in g0
    )
    values = [
        [sp.simplify(as_expr(sum(m[r, j] * g[j] for j in range(6)))) for g in g0] for r in (3, 4, 5)
    ]
    yield make_entry(
        "sec5-matrix-weight2-rows",
        "5",
        "Rows 4–6 of M define the weight-2 coordinates: dy4, dy5, dy6 vanish on "
        "g1(0), g2(0), g3(0) (so that y4..y6 have order 2).",
        "rows 4–6 of M: " + "; ".join(fmt_vec(list(m.row(r))) for r in (3, 4, 5)),
        "dy_r(g_i(0)) for r = 4..6: " + "; ".join(fmt_vec(v) for v in values),
        rows_ok,
        "the rows annihilate span{g1, g2, g3}(0)"
        if rows_ok
        else "the rows do not vanish on span{g1, g2, g3}(0): y4, y5, y6 have order 1",
    )
    orders = [c.linear_order(m.row(r)) for r in range(6)]
    ok = tuple(orders) == tuple(paper.weights)
    yield make_entry(
        "sec5-privileged",
        paper.privileged_text.section,
        f"The coordinates y = M x are privileged at 0: ord_0(y_j) = w_j = {tuple(paper.weights)}.",
        paper.privileged_text.text,
        f"ord_0(y_j) = {tuple(orders)} (eq. vf)",
        ok,
        "non-holonomic orders of the linear functions y_j computed from the fields and their "
        "brackets at 0" + ("" if ok else ": y4, y5, y6 are not of order 2, so y is not privileged"),
    )
