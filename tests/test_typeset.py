"""Typeset results (nilpotent.typeset): the LaTeX reads back to the same mathematics.

The LaTeX of a field is read back with the report's independent LaTeX reader
(:mod:`nilpotent.report.latexmath`, written for the paper's source) and the
safe expression grammar, and compared with the field symbolically; the HTML
carries MathML whose ``data-latex`` is exactly that LaTeX.
"""

from __future__ import annotations

import html
import re

import pytest
import sympy as sp

import nilpotent as nil
from nilpotent.core.model.expressions import parse_expression
from nilpotent.report.latexmath import PARTIAL_PREFIX, vector_field_to_grammar
from nilpotent.typeset import (
    Display,
    Equations,
    Math,
    Table,
    Text,
    field_latex,
    formula_html,
    mathml,
    matrix_latex,
    word_latex,
)

MODELS = ("unicycle", "trident-snake", "trident-snake-paper", "heisenberg", "engel")


def _read_back(tex: str, coords: tuple[sp.Symbol, ...]) -> list[sp.Expr]:
    """Components of the field printed as ``tex``, read with latexmath + the grammar."""
    table = {}
    for x in coords:
        key = re.sub(r"_\{(\w+)\}", r"_\1", sp.latex(x))
        table[key] = str(x)
    text = vector_field_to_grammar(tex, table)
    names = {str(x): x for x in coords}
    names.update({PARTIAL_PREFIX + str(x): sp.Symbol(PARTIAL_PREFIX + str(x)) for x in coords})
    expr = sp.expand(parse_expression(text, names))
    return [expr.coeff(sp.Symbol(PARTIAL_PREFIX + str(x))) for x in coords]


@pytest.mark.parametrize("name", MODELS)
def test_field_latex_reads_back_to_the_field(name):
    system = nil.get_model(name).specialized()
    for f in system.fields:
        back = _read_back(field_latex(f, system.coordinates), system.coordinates)
        for got, want in zip(back, f, strict=True):
            assert sp.simplify(got - want) == 0, (name, got, want)


def test_field_latex_signs_and_zero():
    x, y = sp.symbols("x y")
    assert field_latex((0, 0), (x, y)) == "0"
    assert field_latex((-1, 1), (x, y)) == r"-\partial_{x} + \partial_{y}"
    assert field_latex((0, -x - 1), (x, y)) == r"-\left(x + 1\right)\partial_{y}"


def test_word_latex():
    assert word_latex(3) == "X_{3}"
    assert word_latex(((1, 2), 3), "g") == "[[g_{1}, g_{2}], g_{3}]"


def test_mathml_of_matrix_and_formula_html_keeps_the_latex():
    tex = matrix_latex([[1, sp.Rational(1, 2)], [0, sp.sqrt(3)]])
    out = mathml(tex)
    assert out.startswith("<math") and "<mtable>" in out and "<mfrac>" in out and "<msqrt>" in out
    frag = formula_html(tex)
    latex_attr = re.search(r'data-latex="([^"]*)"', frag).group(1)
    assert html.unescape(latex_attr) == tex
    assert 'class="copy-latex"' in frag and "<math" in frag


def test_display_latex_is_one_align_environment_and_html_has_a_formula_per_math():
    d = Display(
        "t",
        (
            Text("a & b_c"),
            Equations((("y_{1}", "x^{2}"),)),
            Table(("h",), ((Math(r"\alpha"),), ("plain",))),
        ),
    )
    tex = d.latex()
    assert tex.startswith("\\begin{align*}") and tex.endswith("\\end{align*}")
    assert tex.count("\\begin{align*}") == 1
    assert r"\text{a \& b\_c}" in tex and r"y_{1} &= x^{2}" in tex
    page = d.html()
    assert page.count('class="formula"') == 2 and page.count("<math") == 2


def test_results_have_latex_and_html_reprs():
    snake = nil.get_model("trident-snake")
    approx = nil.approximate(snake)
    objects = (snake, approx.filtration, approx.coordinates, approx, approx.certificate)
    for obj in objects:
        tex = obj.to_latex()
        assert tex == obj._repr_latex_()
        assert tex.startswith("\\begin{align*}")
        page = obj._repr_html_()
        assert "<math" in page and "data-latex" in page
    # the weights and orders are tables; the approximation shows its certificate
    assert "<table>" in approx.coordinates._repr_html_()
    assert "certificate" in approx._repr_html_()
    assert r"\hat X_{3}" in approx.to_latex()


def test_comparison_and_plan_reprs():
    snake = nil.get_model("unicycle")
    cmp = nil.compare_bracket_motion(snake, (1, 2), 0.1)
    assert cmp._repr_latex_() == cmp.to_latex() and r"[X_{1}, X_{2}](p)" in cmp.to_latex()
    assert "<math" in cmp._repr_html_()
    for plan in (nil.steer(snake, (0, 0, 0), (0.1, 0.05, 0.0)),  # local steering: Plan
                 nil.plan(snake, (0, 0, 0), (0.1, 0.05, 0.0))):  # as the command: GlobalPlan
        tex = plan.to_latex()
        assert tex == plan._repr_latex_() and "x_{\\mathrm{goal}}" in tex
        page = plan._repr_html_()
        assert "<math" in page and ("converged" in page)
