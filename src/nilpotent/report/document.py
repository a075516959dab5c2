"""The content of the reproduction page: what is said, in which order, with which numbers.

:func:`build_page` turns the results of :mod:`nilpotent.report.pipeline` into
the HTML of ``index.html`` with the building blocks of
:mod:`nilpotent.report.page`.  Every number shown is also written under
``data/`` by the pipeline.  Every field, coordinate change, bracket and
matrix is typeset (MathML from the LaTeX of :mod:`nilpotent.typeset`, the
LaTeX kept for copying); the audit shows the paper's own LaTeX typeset the same
way where it is a formula, and its computed side in the expression grammar.
"""

from __future__ import annotations

import html
import re
from collections.abc import Sequence
from typing import Any

import sympy as sp

from nilpotent.core.model.expressions import parse_expression
from nilpotent.errors import NilpotentError
from nilpotent.models.trident import BODY_LEG_ANGLES, PAPER_LEG_ANGLES
from nilpotent.report.audit import Audit
from nilpotent.report.latexmath import PARTIAL_PREFIX
from nilpotent.report.page import animation, code, figure, formula, page, table
from nilpotent.report.reproduction_data import PageFigures, ReproductionData
from nilpotent.typeset import expr_latex, field_latex, matrix_latex, word_latex

__all__ = ["build_page"]


def _angles_latex(values: Any) -> str:
    return r"\left(" + ", ".join(expr_latex(v) for v in values) + r"\right)"


def _fig(stem: str, caption: str) -> str:
    return figure(f"figures/{stem}.png", caption, links=(("SVG", f"figures/{stem}.svg"),))


def _fields_table(fields, coords, name: str = "X") -> str:
    """The fields ``name_i = Σ_j a_ij ∂_{x_j}``, typeset; ``name`` is LaTeX (``\\hat X``)."""
    rows = [
        (formula(f"{name}_{{{i}}}"), formula(field_latex(f, coords)))
        for i, f in enumerate(fields, start=1)
    ]
    return table(("field", "components"), rows, raw_columns=(0, 1), widths=("8%", "92%"))


def _tuple(values: Any) -> str:
    return formula(r"\left(" + ", ".join(expr_latex(v) for v in values) + r"\right)")


_REGULARITY = {True: "regular point", False: "singular point"}


def _analysis_block(label: str, system, filt) -> str:

    rows = [
        (
            j + 1,
            filt.weights[j],
            formula(f"Y_{{{j + 1}}} = " + word_latex(w)),
            formula(field_latex(v, system.coordinates)),
        )
        for j, (w, v) in enumerate(zip(filt.frame, filt.frame_values, strict=True))
    ]
    return (
        f"<h3>{label}</h3><p>growth vector {_tuple(filt.growth_vector)}, weights "
        f"{_tuple(filt.weights)}, step {filt.step}, "
        f"{_REGULARITY.get(filt.regular, 'regularity undetermined')}; adapted frame at 0:</p>"
        + table(
            ("j", "weight", "word", "value at 0"),
            rows,
            cell_classes=("num", "num", "", ""),
            raw_columns=(2, 3),
            widths=("4%", "7%", "22%", "67%"),
        )
    )


def _privileged_block(label: str, system, approx) -> str:
    coords = approx.coordinates
    rows = [
        (formula(sp.latex(y)), w, formula(f"{sp.latex(y)} = {expr_latex(e)}"), o)
        for y, w, e, o in zip(
            coords.names, approx.weights, coords.forward, coords.orders, strict=True
        )
    ]
    cert = approx.certificate
    matrix = ""
    if coords.linear_part is not None:
        matrix = (
            "<p>The linear part, the matrix inverse of the frame at 0 "
            f"(columns {formula('Y_j(0)')}), so that {formula('z = A(x - p)')}:</p>"
            + formula(rf"A = B^{{-1}} = {matrix_latex(coords.linear_part)}", display=True)
        )
    return (
        f"<h3>{label}</h3><p>method {code(coords.method)} (linear adapted: "
        + formula(r"\partial_{y_j}")
        + f" at 0 is the frame's {formula('Y_j(0)')}); "
        "the orders are computed, not assumed.</p>"
        + table(
            (
                "y_j",
                "weight w_j",
                "y_j as a function of " + ", ".join(system.coordinate_names),
                "computed ord_0(y_j)",
            ),
            rows,
            cell_classes=("", "num", "", "num"),
            raw_columns=(0, 2),
            widths=("6%", "9%", "70%", "15%"),
        )
        + matrix
        + "<p>Nilpotent approximation in y (terms of weighted degree "
        f"{formula('w_j - 1')}):</p>"
        + _fields_table(approx.fields, coords.names, r"\hat X")
        + "<p>The same fields in the model coordinates:</p>"
        + _fields_table(approx.fields_x, system.coordinates, r"\hat X")
        + f"<p>Certificate: homogeneous {cert.homogeneous}, nilpotent of step "
        f"{cert.nilpotent_step}, growth vector of "
        + formula(r"\hat X")
        + f" at 0 {_tuple(cert.growth_vector_at_0)}, "
        + formula(r"X - \hat X")
        + " of order "
        + formula(r"\ge 0")
        + f": {cert.remainder_order_ok}.</p>"
    )


def _audit_note(audit: Audit, *ids: str) -> str:
    """What the audit found on these entries (verdict and explanation), as a note."""
    items = []
    for entry_id in ids:
        e = audit.entry(entry_id)
        items.append(
            f"<li>{code(e.id)} ({html.escape(e.verdict)}): {html.escape(e.statement)} — "
            f"{html.escape(e.explanation)}</li>"
        )
    return f'<div class="note">Audit:<ul>{"".join(items)}</ul></div>'


_PROSE = re.compile(r"[A-Za-z]{4,}")
_INLINE = re.compile(r"\$([^$]+)\$")
_REF = re.compile(r"\\ref\{([^}]*)\}")

WRAP_WIDTH = 44
"""Characters of LaTeX after which a formula of the audit table may break (between
top-level terms), so that it wraps in its column instead of being cut."""


def split_latex(latex: str, width: int = WRAP_WIDTH) -> list[str]:
    """``latex`` cut before top-level ``+``, ``-`` or ``=`` signs into pieces of about
    ``width`` characters (never inside braces, parentheses or brackets), so that each
    piece typesets on its own and the formula wraps."""
    pieces: list[str] = []
    depth, start = 0, 0
    for k, ch in enumerate(latex):
        if ch in "{([":
            depth += 1
        elif ch in "})]":
            depth = max(depth - 1, 0)
        elif (ch in "+-=" and depth == 0 and k - start >= width
              and latex[:k].rstrip()[-1:] not in ("", "{", "(", "^", "_", "=", "+", "-", "\\")):
            pieces.append(latex[start:k])
            start = k
    pieces.append(latex[start:])
    return [p for p in pieces if p.strip()]


def wrapped_formula(latex: str) -> str:
    """A typeset formula (:func:`~nilpotent.report.page.formula`) that wraps: a long one
    is typeset as several MathML pieces (:func:`split_latex`) in one ``.formula``
    element that keeps the whole LaTeX for copying."""
    pieces = split_latex(latex)
    if len(pieces) < 2:
        return formula(latex)
    from nilpotent.typeset import COPY_HANDLER, mathml

    try:
        body = "".join(mathml(p) for p in pieces)
    except Exception:  # latex2mathml cannot read a piece: the whole, as formula() does
        return formula(latex)
    return (
        f'<span class="formula wrapped" data-latex="{html.escape(latex, quote=True)}">'
        f"{body}"
        f'<button type="button" class="copy-latex" title="copy LaTeX" '
        f'onclick="{html.escape(COPY_HANDLER, quote=True)}">TeX</button></span>'
    )


def _prose_html(text: str) -> str:
    """A sentence of the paper with its ``$...$`` formulas typeset, ``\\ref{label}``
    shown as the label and ``--`` as a dash: no raw LaTeX beside the MathML."""
    text = _REF.sub(lambda m: m.group(1), text).replace("--", "–")
    out, last = [], 0
    for m in _INLINE.finditer(text):
        out.append(html.escape(text[last:m.start()]))
        try:
            out.append(formula(m.group(1).strip()))
        except Exception:  # pragma: no cover - formula() falls back to <code> itself
            out.append(html.escape(m.group(0)))
        last = m.end()
    out.append(html.escape(text[last:]))
    return "".join(out)


def _paper_cell(text: str) -> str:
    """The paper's side of an audit entry: typeset when it is a LaTeX formula, else text
    with its inline ``$...$`` formulas typeset.

    A formula is text without ``$`` whose letters outside LaTeX commands form no
    word of four letters or more (``g_5 = \\sqrt 3\\partial x_5``, not a sentence).
    """
    if "$" not in text and not _PROSE.search(re.sub(r"\\[A-Za-z]+", " ", text)):
        try:
            return wrapped_formula(text)
        except Exception:  # latex2mathml cannot read it: show the source as printed
            pass
    return _prose_html(text)


def _computed_cell(text: str, coordinates: Sequence[sp.Symbol]) -> str:
    """The computed side of an audit entry: typeset when it is one field or expression.

    The audit prints fields in the expression grammar with ``∂x4`` for the
    coordinate field; such text is read back with the safe grammar (``∂v`` as a
    placeholder symbol) and typeset; any other text (a sentence, a list) stays text.
    """
    names: dict[str, sp.Basic] = {str(x): x for x in coordinates}
    partials = {x: sp.Symbol(PARTIAL_PREFIX + str(x)) for x in coordinates}
    names.update({str(d): d for d in partials.values()})
    try:
        expr = sp.expand(parse_expression(text.replace("∂", PARTIAL_PREFIX), names))
    except NilpotentError:
        return html.escape(text)
    components = [expr.coeff(d) for d in partials.values()]
    rest = sp.expand(expr - sum(c * d for c, d in zip(components, partials.values(), strict=True)))
    if any(rest.has(d) or any(c.has(d) for c in components) for d in partials.values()):
        return html.escape(text)  # not linear in the coordinate fields: keep the text
    if all(c == 0 for c in components):
        return wrapped_formula(expr_latex(expr))
    return wrapped_formula(field_latex(components, list(partials)))


def _audit_table(audit: Audit, coordinates: Sequence[sp.Symbol]) -> str:
    rows = [
        (
            e.id,
            e.section,
            e.statement,
            _paper_cell(e.paper),
            _computed_cell(e.computed, coordinates),
            e.verdict,
            e.explanation,
        )
        for e in audit.entries
    ]
    return table(
        ("id", "§", "statement", "paper (as printed)", "computed", "verdict", "explanation"),
        rows,
        row_classes=[e.verdict for e in audit.entries],
        cell_classes=("mono", "num", "", "", "", "verdict", ""),
        raw_columns=(3, 4),
        widths=("10%", "3%", "20%", "22%", "20%", "6%", "19%"),
        css_class="audit",
    )


def build_page(data: ReproductionData, figures: PageFigures) -> str:
    """The HTML of ``index.html`` (see :mod:`nilpotent.report.pipeline`)."""
    paper, audit, settings, quick = data.paper, data.audit, data.settings, data.quick
    systems, filtrations, approximations = data.systems, data.filtrations, data.approximations
    motions, brackets, studies, s4_names = data.motions, data.brackets, data.studies, data.s4_names
    fig_motion, fig_compare = figures.motion, figures.comparison
    anim_files, scaling_stems = figures.animations, figures.amplitude
    body, vf = systems["body"], systems["vf"]
    names_y = [y for a in approximations.values() for y in a.names]
    coordinates = list(dict.fromkeys([*body.coordinates, *vf.coordinates, *names_y]))
    pairs = ((1, 2), (2, 3), (1, 3))
    n_diff = len(audit.differing)
    summary = (
        '<div class="summary">'
        f'<div class="card"><b>{len(audit.entries)}</b>statements checked</div>'
        f'<div class="card"><b>{len(audit.agreeing)}</b>agree</div>'
        f'<div class="card"><b>{n_diff}</b>differ</div>'
        f'<div class="card"><b>{filtrations["body"].growth_vector}</b>growth vector</div>'
        f'<div class="card"><b>{approximations["vf"].certificate.nilpotent_step}</b>'
        f"nilpotency step (paper: {paper.step_claim})</div></div>"
        '<p class="note">Everything on this page was computed when it was generated '
        f"({'quick' if quick else 'full'} settings), from the built-in models "
        f"{code('trident-snake')} (the paper's Section 4, r = l = 1) and "
        f"{code('trident-snake-paper')} (its eq. vf), and from the paper's LaTeX source, "
        "parsed at run time. The numbers are in "
        '<a href="data/">data/</a> and <a href="audit.json">audit.json</a>. Lengths are in '
        "units of the body's circumradius r; angles in radians; the bracket is "
        "[X,Y] = DY·X − DX·Y.</p>"
    )
    differing = "".join(
        f"<li>{code(e.id)}: {html.escape(e.explanation)}</li>" for e in audit.differing
    )

    model = (
        "<p>Configuration q = (x, y, θ, φ1, φ2, φ3) = (x1, …, x6): body centre, heading, "
        "joint angles. The no-side-slip constraint of wheel i, with "
        + formula(r"\psi_i = \theta + \alpha_i + \phi_i")
        + ", is</p>"
        + formula(
            r"-\sin\psi_i\,\dot x + \cos\psi_i\,\dot y + (r\cos\phi_i + l)\,\dot\theta"
            r" + l\,\dot\phi_i = 0",
            display=True,
        )
        + "<p>With body-velocity inputs it gives the fields of the paper's Section 4 "
        "(legs at "
        + formula(r"\alpha = " + _angles_latex(BODY_LEG_ANGLES))
        + "):</p>"
        + _fields_table(body.specialized_fields, body.coordinates, "g")
        + "<p>The paper then works with its simplified eq. vf (the rotation "
        + formula(r"R_\theta")
        + " dropped, legs read at "
        + formula(_angles_latex(PAPER_LEG_ANGLES))
        + "):</p>"
        + _fields_table(vf.specialized_fields, vf.coordinates, "g")
        + _audit_note(audit, "sec4-vf-same-system", "sec4-vf-g1")
    )

    bracket_rows = []
    for pair in pairs:
        k = s4_names[pair]
        bracket_rows.append(
            (
                formula(f"[g_{{{pair[0]}}}, g_{{{pair[1]}}}]"),
                formula(f"g_{{{k}}}"),
                formula(field_latex(brackets["body", pair], body.coordinates)),
                formula(field_latex(brackets["vf", pair], vf.coordinates)),
            )
        )
    brackets_html = (
        table(
            ("bracket", "name (Section 4)", "Section 4 fields, at 0", "eq. vf, at 0"),
            bracket_rows,
            raw_columns=(0, 1, 2, 3),
        )
        + _analysis_block("Section 4 fields", body, filtrations["body"])
        + _analysis_block("eq. vf", vf, filtrations["vf"])
    )

    privileged = (
        _audit_note(audit, "sec5-matrix-condition", "sec5-privileged", "sec6-first-order")
        + "<p>The coordinates below are computed by the library, with their orders as a "
        "certificate.</p>"
        + _privileged_block("eq. vf (the paper's form)", vf, approximations["vf"])
        + _privileged_block("Section 4 fields (the robot)", body, approximations["body"])
    )

    motion_html = [
        "<p>One period of the periodic input "
        + formula(r"u_i = -A\sin t,\ u_j = A\cos t")
        + " moves the robot by "
        + formula(r"\pi A^2 [g_i, g_j](0) + O(A^3)")
        + ". Trajectories of the body centre, "
        "the three vertices and the three wheels; robot at the start (dotted, faded) and "
        "at the end.</p>"
    ]
    rows = []
    for n, pair in enumerate(pairs):
        k = s4_names[pair]
        motion_html.append(
            _fig(fig_motion[pair], f"Fig. {n + 2}: realization of g{k} = [g{pair[0]},g{pair[1]}]")
        )
        m = motions["body", pair]
        disp = m.original[-1] - m.original[0]
        rows.append(
            (
                formula(f"[g_{{{pair[0]}}}, g_{{{pair[1]}}}]"),
                ", ".join(f"{v:+.4f}" for v in disp),
                ", ".join(f"{v - m.original[0][j]:+.4f}" for j, v in enumerate(m.prediction)),
                f"{m.endpoint_error:.3g}",
            )
        )
    motion_html.append(
        table(
            ("bracket", "q(T) − q(0), original", "πA²[g_i,g_j](0)", "|end original − end approx.|"),
            rows,
            cell_classes=("", "mono", "mono", "num"),
            raw_columns=(0,),
        )
    )

    compare_html = [
        "<p>As in the paper's Figs 5–7: the same inputs applied to eq. vf "
        "(solid) and to its nilpotent approximation in the model coordinates "
        "(dashed, drawn above); the wheels' trajectories show the accuracy in the plane. Below, "
        "the same for the Section 4 robot, with animations.</p>"
    ]
    for n, pair in enumerate(pairs):
        k = s4_names[pair]
        compare_html.append(
            _fig(
                fig_compare["vf", pair],
                f"Fig. {n + 5}: comparison of g{k} = [g{pair[0]},g{pair[1]}] motions, eq. vf",
            )
        )
    compare_html.append("<h3>The robot (Section 4 fields) and its approximation</h3>")
    for pair in pairs:
        k = s4_names[pair]
        compare_html.append(
            _fig(
                fig_compare["body", pair],
                f"[g{pair[0]},g{pair[1]}] (g{k}): Section 4 robot, original "
                "(solid) vs approximation (dashed)",
            )
        )
        files = anim_files[pair]
        compare_html.append(
            animation(
                f"figures/{files.gif.name}",
                f"figures/{files.html.name}",
                f"Animation: [g{pair[0]},g{pair[1]}] motion, original (left) and nilpotent "
                f"approximation (right), {files.frames} frames",
                mp4=f"figures/{files.mp4.name}" if files.mp4 is not None else None,
            )
        )

    slope_rows = []
    for (key, pair), st in studies.items():
        cells = [systems[key].name, f"[X{pair[0]},X{pair[1]}]"]
        for w in sorted(st.errors):
            s = st.slopes[w]
            cells.append(
                "exact (below noise floor)"
                if s is None
                else f"{s:.2f} (theory ≥ {st.expected_slopes[w]})"
            )
        slope_rows.append(cells)
    amps = ", ".join(f"{a:.3g}" for a in settings.amplitudes)
    study = (
        f"<p>Amplitudes A = {amps}; one period of the periodic input; error between the "
        "original system (mapped to the privileged coordinates y) and the approximation "
        "(integrated in y), largest over the period and over the coordinates of each weight "
        "(nilpotent.scaling). Theory (first-order approximation): O(A^(w+1)) "
        "for coordinates of weight w. Slopes are least-squares fits on log–log axes.</p>"
        + _fig(scaling_stems["vf"], "Error against amplitude, eq. vf")
        + _fig(scaling_stems["body"], "Error against amplitude, Section 4 robot")
        + table(
            ("model", "bracket", "slope weight 1", "slope weight 2"),
            slope_rows,
            cell_classes=("mono", "mono", "num", "num"),
        )
    )

    singular = (
        "<p>eq. vf is regular at the origin, but its frame (g1, g2, g3 and the three "
        "brackets) loses rank where the wheels' body-frame positions are collinear; the "
        "determinant depends on x4, x5, x6 only.</p>"
        + _fig(
            figures.singular_set,
            "Singular set of eq. vf in the (x4, x5) plane for four values of x6",
        )
    )

    audit_html = (
        f"<p>{len(audit.entries)} statements, {len(audit.agreeing)} agree, {n_diff} differ. "
        "Each verdict was decided by computation when this page was generated (exact "
        "comparison of expressions; simulations only for which bracket a periodic input "
        "realises). The paper's values are parsed from its LaTeX source.</p>"
        f"<p>What differs:</p><ul>{differing}</ul>" + _audit_table(audit, coordinates)
    )

    files = (
        "<ul>"
        '<li><a href="audit.json">audit.json</a> (schema nilpotent/audit@1)</li>'
        '<li><a href="data/models.json">data/models.json</a>: fields, growth, frame, '
        "privileged coordinates, approximations, certificates</li>"
        '<li><a href="data/motions.json">data/motions.json</a> and '
        "data/motion_*.csv: sampled trajectories</li>"
        '<li><a href="data/slopes.json">data/slopes.json</a> and data/amplitude_*.csv: '
        "the error study</li>"
        '<li><a href="data/audit.csv">data/audit.csv</a></li>'
        "</ul>"
    )

    sections = [
        ("summary", "Summary", summary),
        ("model", "The trident snake model", model),
        ("brackets", "Brackets and growth vector", brackets_html),
        ("privileged", "Privileged coordinates and nilpotent approximation", privileged),
        ("motions", "Bracket motions (Figs 2–4)", "".join(motion_html)),
        ("comparison", "Original and approximation (Figs 5–7), animations", "".join(compare_html)),
        ("amplitude", "Error against amplitude", study),
        ("singular", "Singular set of eq. vf", singular),
        ("audit", "Audit of the paper", audit_html),
        ("files", "Data files", files),
    ]
    return page(
        "Nilpotent approximation of the trident snake, reproduced",
        "Hrdina, Návrat, Vašík: Nilpotent approximation of a trident snake robot controlling "
        "distribution — recomputed with nilpotent, every statement audited.",
        sections,
    )
