"""The LaTeX-math translator: hand-written LaTeX against sympy built by hand."""

from __future__ import annotations

import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st

from nilpotent.core.model.expressions import parse_expression
from nilpotent.errors import ExpressionError
from nilpotent.report.latexmath import (
    PARTIAL_PREFIX,
    latex_to_grammar,
    split_top_level,
    strip_layout,
)

x1, x2, x3, th, A, w, t = sp.symbols("x1 x2 x3 theta A omega t")
SYMBOLS = {
    "x_1": "x1",
    "x_2": "x2",
    "x_3": "x3",
    r"\theta": "theta",
    "A": "A",
    r"\omega": "omega",
    "t": "t",
}
NAMES = {"x1": x1, "x2": x2, "x3": x3, "theta": th, "A": A, "omega": w, "t": t}
D = {f"{PARTIAL_PREFIX}{n}": sp.Symbol(f"{PARTIAL_PREFIX}{n}") for n in ("x1", "x2", "x3")}


def read(tex: str) -> sp.Expr:
    return parse_expression(latex_to_grammar(tex, SYMBOLS), {**NAMES, **D})


@pytest.mark.parametrize(
    ("tex", "expected"),
    [
        (r"\tfrac{\sqrt 3x_1}{4}", sp.sqrt(3) * x1 / 4),  # TeX: \sqrt takes one token
        (r"\sqrt{3}x_2", sp.sqrt(3) * x2),
        (r"\frac{x_1}{2}-x_2", x1 / 2 - x2),
        (r"-\tfrac{\sqrt{3}}{2}", -sp.sqrt(3) / 2),
        (r"\sin(x_1-\tfrac{2\pi}{3})", sp.sin(x1 - 2 * sp.pi / 3)),
        (r"\cos\theta", sp.cos(th)),
        (r"-A\omega\sin\omega t", -A * w * sp.sin(w * t)),
        (r"(1+\cos(x_1))", 1 + sp.cos(x1)),
        (r"x_1^2+x_{2}", x1**2 + x2),
        (r"\phantom{-}1", sp.Integer(1)),
        (r"2\cdot x_3", 2 * x3),
        (r"+ +x_1", x1),
        (r"--x_1", x1),
    ],
)
def test_expressions(tex: str, expected: sp.Expr) -> None:
    assert sp.simplify(read(tex) - expected) == 0


def test_vector_field_is_linear_in_placeholders() -> None:
    expr = sp.expand(
        read(r"\cos\theta \partial_{x_1}+\sin\theta\partial x_2-(1+x_3)\partial_{x_3}")
    )
    dx1, dx2, dx3 = D.values()
    assert expr.coeff(dx1) == sp.cos(th)
    assert expr.coeff(dx2) == sp.sin(th)
    assert sp.expand(expr.coeff(dx3) + 1 + x3) == 0


def test_unknown_symbol_is_refused_with_the_fragment() -> None:
    with pytest.raises(ExpressionError, match="unknown symbol 'z'"):
        latex_to_grammar("z+1", SYMBOLS)


@pytest.mark.parametrize("tex", [r"\int x_1", r"\frac{x_1}", r"(x_1", r"x_1)"])
def test_unsupported_or_malformed(tex: str) -> None:
    with pytest.raises(ExpressionError):
        latex_to_grammar(tex, SYMBOLS)


def test_layout_is_stripped() -> None:
    assert strip_layout(r"\phantom{-}1 & 2 % comment").split() == ["1", "2"]


def test_split_top_level_respects_nesting() -> None:
    assert split_top_level("(a,b),c,{d,e}", ",") == ["(a,b)", "c", "{d,e}"]


@given(st.integers(-50, 50), st.integers(1, 50))
def test_fractions_round_trip(p: int, q: int) -> None:
    tex = rf"\frac{{{abs(p)}}}{{{q}}}" if p >= 0 else rf"-\frac{{{-p}}}{{{q}}}"
    assert read(tex) == sp.Rational(p, q)
