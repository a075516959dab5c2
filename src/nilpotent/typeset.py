r"""Typeset results: LaTeX to paste, MathML HTML to read, in notebooks and in the report.

One module builds the mathematics a user reads, so that a notebook, the
``--latex`` output of the CLI and the reproduction page say the same thing the
same way.  Every result is first described as a :class:`Display`, a short list
of blocks:

* :class:`Equations`: rows ``lhs = rhs`` (LaTeX on both sides);
* :class:`Table`: headers and cells, each cell plain text or a :class:`Math`;
* :class:`Text`: a sentence.

A :class:`Display` prints itself two ways: :meth:`Display.latex`, one
``align*`` environment (amsmath) to paste into a paper or give Jupyter as
``text/latex``; and :meth:`Display.html`, HTML whose formulas are MathML
(MathML Core, rendered natively by Chromium, Firefox and Safari; converted with
``latex2mathml``), each carrying its LaTeX source in a ``data-latex``
attribute and a small "copy LaTeX" button.  Nothing is fetched from the
network; the button's handler is an inline attribute.

The ``*_display`` functions describe the results of the library; they read the
objects' attributes and import none of their classes, so the symbolic core can
delegate to this module without importing the numeric layers.  Conventions:
fields as $\sum_j a_j\,\partial_{x_j}$ (components along the coordinate
fields), brackets $[X, Y] = DY\cdot X - DX\cdot Y$.

Examples
--------
>>> import sympy as sp
>>> x, th = sp.symbols("x theta")
>>> field_latex((sp.cos(th), 1), (x, th))
'\\cos{\\left(\\theta \\right)}\\,\\partial_{x} + \\partial_{\\theta}'
>>> word_latex((1, (1, 2)))
'[X_{1}, [X_{1}, X_{2}]]'
"""

from __future__ import annotations

import html
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import sympy as sp
from sympy.core.sympify import _sympify as _strict_sympy

__all__ = [
    "COPY_HANDLER",
    "Display",
    "Equations",
    "Math",
    "Table",
    "Text",
    "approximation_display",
    "certificate_display",
    "comparison_display",
    "expr_latex",
    "field_latex",
    "filtration_display",
    "formula_html",
    "mathml",
    "matrix_latex",
    "plan_display",
    "privileged_display",
    "system_display",
    "word_latex",
]

#: The inline ``onclick`` of the "copy LaTeX" buttons: copies the ``data-latex`` of
#: the enclosing formula to the clipboard (silently nothing where there is none).
COPY_HANDLER = (
    "var c=navigator.clipboard,t=this.parentNode.getAttribute('data-latex');"
    "if(c){c.writeText(t).then(null,function(){});}"
)


# --- LaTeX of the mathematical objects ----------------------------------------------------


def expr_latex(value: sp.Basic | int | float) -> str:
    """LaTeX of one exact or floating-point expression (sympy's printer)."""
    return sp.latex(_strict_sympy(value))


def field_latex(
    components: Sequence[sp.Expr | int | float], coordinates: Sequence[sp.Symbol]
) -> str:
    r"""LaTeX of the vector field $\sum_j a_j\,\partial_{x_j}$ (``0`` for the zero field).

    Parameters
    ----------
    components : sequence of sympy expressions, length n
        ``components[j]`` is the component along ``coordinates[j]``.
    coordinates : sequence of sympy symbols, length n
        The coordinate symbols.
    """
    text = ""
    for a, x in zip(components, coordinates, strict=True):
        a = _strict_sympy(a)
        if a.is_zero:
            continue
        negative = a.could_extract_minus_sign()
        mag = -a if negative else a
        d = rf"\partial_{{{sp.latex(x)}}}"
        if mag == 1:
            term = d
        elif isinstance(mag, sp.Add):
            term = rf"\left({sp.latex(mag)}\right){d}"
        else:
            term = rf"{sp.latex(mag)}\,{d}"
        if text:
            text += (" - " if negative else " + ") + term
        else:
            text = ("-" if negative else "") + term
    return text or "0"


def matrix_latex(rows: Any) -> str:
    """LaTeX ``pmatrix`` of a matrix (a sympy matrix or a sequence of rows)."""
    matrix = sp.Matrix(rows)
    body = r" \\ ".join(
        " & ".join(sp.latex(matrix[i, j]) for j in range(matrix.cols))
        for i in range(matrix.rows)
    )
    return rf"\begin{{pmatrix}} {body} \end{{pmatrix}}"


def word_latex(word: Any, name: str = "X") -> str:
    """LaTeX of a bracket word: ``(1, (1, 2))`` is ``[X_{1}, [X_{1}, X_{2}]]``."""
    if isinstance(word, int):
        return f"{name}_{{{word}}}"
    return f"[{word_latex(word[0], name)}, {word_latex(word[1], name)}]"


def _tuple_latex(values: Iterable[sp.Basic | int | float]) -> str:
    return r"\left(" + ", ".join(expr_latex(v) for v in values) + r"\right)"


def _number_latex(value: float) -> str:
    return sp.latex(sp.Float(float(value), 4)) if value == value else r"\mathrm{NaN}"


def _text_latex(text: str) -> str:
    table = {
        "\\": r"\textbackslash{}", "{": r"\{", "}": r"\}", "_": r"\_", "%": r"\%",
        "&": r"\&", "#": r"\#", "$": r"\$", "^": r"\^{}", "~": r"\~{}",
    }
    return r"\text{" + "".join(table.get(ch, ch) for ch in text) + "}"


# --- MathML -------------------------------------------------------------------------------


def mathml(latex: str, *, display: bool = False) -> str:
    """The MathML ``<math>`` element of a LaTeX formula (``latex2mathml``).

    Parameters
    ----------
    latex : str
        A formula without ``$`` delimiters and without alignment environments.
    display : bool
        Block (``display="block"``) rather than inline layout.
    """
    from latex2mathml.converter import convert

    return convert(latex, display="block" if display else "inline")


def formula_html(latex: str, *, display: bool = False) -> str:
    """A formula as HTML: MathML with its LaTeX in ``data-latex`` and a "copy LaTeX" button.

    The element is ``<span class="formula" data-latex="...">`` holding the
    ``<math>`` element and a ``<button class="copy-latex">``; where
    ``latex2mathml`` cannot read the formula, the LaTeX itself stands in a
    ``<code>`` element instead of the ``<math>``.
    """
    tag = "div" if display else "span"
    try:
        body = mathml(latex, display=display)
    except Exception:  # a construction latex2mathml does not know: show the LaTeX itself
        body = f"<code>{html.escape(latex)}</code>"
    return (
        f'<{tag} class="formula" data-latex="{html.escape(latex, quote=True)}">'
        f"{body}"
        f'<button type="button" class="copy-latex" title="copy LaTeX" '
        f'onclick="{html.escape(COPY_HANDLER, quote=True)}">TeX</button></{tag}>'
    )


# --- the display model --------------------------------------------------------------------


@dataclass(frozen=True)
class Math:
    """A table cell holding a formula (LaTeX, no ``$``)."""

    latex: str


@dataclass(frozen=True)
class Text:
    """A sentence (plain text)."""

    text: str


@dataclass(frozen=True)
class Equations:
    """Rows ``lhs = rhs``; both sides LaTeX."""

    rows: tuple[tuple[str, str], ...]


@dataclass(frozen=True)
class Table:
    """A table: ``headers`` and rows of plain-text or :class:`Math` cells."""

    headers: tuple[str | Math, ...]
    rows: tuple[tuple[str | Math, ...], ...]


Block = Text | Equations | Table


def _cell_latex(cell: str | Math) -> str:
    return cell.latex if isinstance(cell, Math) else _text_latex(str(cell))


def _cell_html(cell: str | Math) -> str:
    return formula_html(cell.latex) if isinstance(cell, Math) else html.escape(str(cell))


@dataclass(frozen=True)
class Display:
    """What a result shows: a title and blocks; printed as LaTeX or as MathML HTML."""

    title: str
    blocks: tuple[Block, ...]

    def latex(self) -> str:
        """One ``align*`` environment: the title, equations aligned at ``=``, tables as arrays."""
        rows = [f"&{_text_latex(self.title)}"]
        for block in self.blocks:
            if isinstance(block, Text):
                rows.append(f"&{_text_latex(block.text)}")
            elif isinstance(block, Equations):
                rows += [f"{lhs} &= {rhs}" for lhs, rhs in block.rows]
            else:
                spec = "l" * len(block.headers)
                head = " & ".join(_cell_latex(h) for h in block.headers)
                body = "".join(
                    r" \\ " + " & ".join(_cell_latex(c) for c in row) for row in block.rows
                )
                rows.append(rf"&\begin{{array}}{{{spec}}} {head} \\ \hline{body[3:]}\end{{array}}")
        return "\\begin{align*}\n" + " \\\\\n".join(rows) + "\n\\end{align*}"

    def html(self, *, heading: bool = True) -> str:
        """HTML: ``<p>`` for text, a two-column layout of equations, ``<table>`` for tables."""
        parts = [f"<p><strong>{html.escape(self.title)}</strong></p>"] if heading else []
        for block in self.blocks:
            if isinstance(block, Text):
                parts.append(f"<p>{html.escape(block.text)}</p>")
            elif isinstance(block, Equations):
                parts.append(
                    '<table class="equations">'
                    + "".join(
                        f"<tr><td>{formula_html(f'{lhs} = {rhs}')}</td></tr>"
                        for lhs, rhs in block.rows
                    )
                    + "</table>"
                )
            else:
                head = "".join(f"<th>{_cell_html(h)}</th>" for h in block.headers)
                body = "".join(
                    "<tr>" + "".join(f"<td>{_cell_html(c)}</td>" for c in row) + "</tr>"
                    for row in block.rows
                )
                parts.append(f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")
        return '<div class="nilpotent-display">' + "".join(parts) + "</div>"


# --- the results --------------------------------------------------------------------------


def _field_rows(
    fields: Sequence[Sequence[sp.Expr]], coordinates: Sequence[sp.Symbol], name: str
) -> tuple[tuple[str, str], ...]:
    return tuple(
        (f"{name}_{{{i}}}", field_latex(f, coordinates)) for i, f in enumerate(fields, start=1)
    )


def system_display(system: Any) -> Display:
    """A :class:`~nilpotent.core.model.ControlSystem`: its fields, coordinates and parameters."""
    blocks: list[Block] = [
        Text(f"coordinates ({', '.join(system.coordinate_names)}); {system.m} fields"),
        Equations(_field_rows(system.fields, system.coordinates, "X")),
    ]
    if system.parameters:
        blocks.append(
            Equations(tuple((sp.latex(sp.Symbol(k)), expr_latex(v)) for k, v in system.parameters))
        )
    if system.description:
        blocks.insert(0, Text(system.description))
    return Display(f"control system {system.name}", tuple(blocks))


def filtration_display(filtration: Any) -> Display:
    """A :class:`~nilpotent.core.analysis.Filtration`: growth, weights, the adapted frame."""
    coords = filtration.system.coordinates
    kind = {True: "regular point", False: "singular point"}.get(
        filtration.regular, "regularity undetermined"
    )
    generating = {
        True: "bracket-generating",
        False: f"not bracket-generating up to length {filtration.max_length}",
    }.get(filtration.bracket_generating, "bracket generation undetermined")
    rows = tuple(
        (str(j), str(w), Math(word_latex(word)), Math(field_latex(value, coords)))
        for j, (w, word, value) in enumerate(
            zip(filtration.weights, filtration.frame, filtration.frame_values, strict=True),
            start=1,
        )
    )
    return Display(
        f"filtration of {filtration.system.name} at {_point_text(filtration.point)}",
        (
            Equations(
                (
                    ("p", _tuple_latex(filtration.point)),
                    ("(n_1, \\dots, n_r)", _tuple_latex(filtration.growth_vector)),
                    ("r", str(filtration.step)),
                )
            ),
            Text(f"{kind}, {generating}; generic growth vector "
                 f"{tuple(filtration.generic_growth_vector)}"),
            Table((Math("j"), Math(r"\text{weight } w_j"), Math(r"\text{word } Y_j"),
                   Math("Y_j(p)")), rows),
        ),
    )


def privileged_display(coordinates: Any) -> Display:
    """:class:`~nilpotent.core.coordinates.PrivilegedCoordinates`: the change, weights, orders."""
    system = coordinates.filtration.system
    rows = tuple(
        (Math(sp.latex(y)), str(w), str(o), Math(expr_latex(e)))
        for y, w, o, e in zip(
            coordinates.names, coordinates.weights, coordinates.orders, coordinates.forward,
            strict=True,
        )
    )
    blocks: list[Block] = [
        Text(f"{coordinates.method} privileged coordinates; the orders are computed"),
        Table((Math("y_j"), Math(r"\text{weight } w_j"), "computed order",
               Math(r"y_j \text{ as a function of } x")), rows),
        Text("inverse" + ("" if coordinates.inverse_exact
                          else f" (truncated at weighted degree {coordinates.inverse_order})")),
        Equations(
            tuple(
                (sp.latex(x), expr_latex(e))
                for x, e in zip(system.coordinates, coordinates.inverse, strict=True)
            )
        ),
    ]
    if coordinates.linear_part is not None:
        blocks.append(Equations((("A = B^{-1}", matrix_latex(coordinates.linear_part)),)))
    return Display(
        f"privileged coordinates of {system.name} at {_point_text(coordinates.point)}",
        tuple(blocks),
    )


def certificate_display(certificate: Any) -> Display:
    """A :class:`~nilpotent.core.coordinates.Certificate`: each computed check and verdict."""

    def verdict(ok: bool) -> str:
        return "passed" if ok else "FAILED"

    c = certificate
    rows = (
        ("orders of y equal the weights", Math(_tuple_latex(c.orders)),
         Math(_tuple_latex(c.weights)), verdict(c.privileged)),
        ("homogeneous of degree -1", "", "", verdict(c.homogeneous)),
        ("nilpotent step", str(c.nilpotent_step), str(c.step), verdict(c.nilpotent_step == c.step)),
        ("growth vector at 0", Math(_tuple_latex(c.growth_vector_at_0)),
         Math(_tuple_latex(c.growth_vector)),
         verdict(tuple(c.growth_vector_at_0) == tuple(c.growth_vector))),
        (Math(r"\mathrm{ord}_p(X_i - \hat X_i)"), Math(_tuple_latex(c.remainder_orders)),
         Math(r"\ge 0"),
         verdict(c.remainder_order_ok)),
        ("push-forward consistent", "", "", verdict(c.pushforward_ok)),
    )
    exact = "every decision exact" if c.exact else "some decisions numerical (floating point)"
    return Display(
        f"certificate: {'all checks passed' if c.ok else 'FAILED'}",
        (Table(("check", "computed", "expected", "verdict"), rows), Text(exact)),
    )


def approximation_display(approx: Any) -> Display:
    """A :class:`~nilpotent.core.coordinates.NilpotentApproximation` with its certificate."""
    coords = approx.coordinates
    system = approx.system
    cert = certificate_display(approx.certificate)
    filt = approx.filtration
    blocks: list[Block] = [
        Text(f"growth vector {tuple(filt.growth_vector)}, weights {tuple(approx.weights)}, "
             f"step {filt.step}; {coords.method} privileged coordinates"),
        Equations(
            tuple(
                (sp.latex(y), expr_latex(e))
                for y, e in zip(coords.names, coords.forward, strict=True)
            )
        ),
        Text("the nilpotent approximation in y"),
        Equations(_field_rows(approx.fields, coords.names, r"\hat X")),
        Text("in the model coordinates" + ("" if approx.fields_x_exact else " (truncated)")),
        Equations(
            tuple(
                (rf"[\hat X_{{{i}}}]_x", field_latex(f, system.coordinates))
                for i, f in enumerate(approx.fields_x, start=1)
            )
        ),
        Text(cert.title),
        *cert.blocks,
    ]
    return Display(
        f"nilpotent approximation of {system.name} at {_point_text(approx.point)}", tuple(blocks)
    )


def comparison_display(comparison: Any) -> Display:
    """A bracket-motion comparison: the input, the prediction and the errors by weight."""
    c = comparison
    i, j = c.bracket
    names = c.system.coordinates
    bracket = field_latex([_float(v) for v in c.bracket_value], names)
    by_weight = tuple(
        (str(w), f"{c.errors_by_weight[w]:.3g}",
         f"{c.endpoint_by_weight[w]:.3g}" if w in c.endpoint_by_weight else "")
        for w in sorted(c.errors_by_weight)
    )
    return Display(
        f"bracket motion [X{i},X{j}] of {c.system.name}: original and approximation",
        (
            Equations(
                (
                    (rf"(u_{{{i}}}, u_{{{j}}})",
                     rf"\left(-A\omega\sin \omega t,\ A\omega\cos \omega t\right),\ "
                     rf"A = {_number_latex(c.amplitude)},\ \omega = {_number_latex(c.omega)},\ "
                     rf"{c.periods}\ \text{{period(s)}}"),
                    (rf"[X_{{{i}}}, X_{{{j}}}](p)", bracket),
                    ("x(T) - x(0)", _tuple_latex(
                        _float(float(b) - float(a), 4)
                        for a, b in zip(c.original[0], c.original[-1], strict=True))),
                    (r"|x(T) - \hat x(T)|", _number_latex(c.endpoint_error)),
                    (r"\max_t |x(t) - \hat x(t)|", _number_latex(c.max_error)),
                )
            ),
            Table(("weight w", "largest error over the motion", "error at the end"), by_weight),
        ),
    )


def plan_display(plan: Any) -> Display:
    """A :class:`~nilpotent.planning.Plan`: start, goal, what is reached, the iterations."""
    rows = tuple(
        (str(k), getattr(it, "kind", ""), f"{it.error:.3g}", f"{it.damping:.3g}",
         str(it.segments), f"{it.nilpotent_error:.3g}")
        for k, it in enumerate(plan.iterations, start=1)
    )
    verdict = "converged" if plan.converged else "not converged"
    return Display(
        f"plan for {plan.system.name}: {verdict}",
        (
            Equations(
                (
                    ("x_{\\mathrm{start}}", _floats_latex(plan.start)),
                    ("x_{\\mathrm{goal}}", _floats_latex(plan.goal)),
                    ("x(T)", _floats_latex(plan.reached)),
                    (r"\|x(T) - x_{\mathrm{goal}}\|", _number_latex(plan.error)),
                    ("T", _number_latex(plan.duration)),
                )
            ),
            Text(f"{len(plan.segments)} control segments, tolerance {plan.tol:g}, "
                 f"{plan.builder} approximations at the {plan.anchor} point"),
            Table(("iteration", "kind", "error", "damping", "segments", "nilpotent error"), rows),
        ),
    )


def _float(value: float, digits: int = 6) -> sp.Expr:
    """A float as a sympy number: an integer when it is one, else ``digits`` significant digits."""
    value = float(value)
    return sp.Integer(int(value)) if value.is_integer() else sp.Float(value, digits)


def _floats_latex(values: Iterable[float]) -> str:
    return _tuple_latex(_float(v) for v in values)


def _point_text(point: Iterable[object]) -> str:
    return "(" + ", ".join(str(v) for v in point) + ")"
