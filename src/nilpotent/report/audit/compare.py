"""Exact comparison and printing of the objects the audit checks.

Two expressions are equal when their difference vanishes at several random
rational points evaluated with 30 significant digits (a nonzero value there
proves a difference) *and* sympy cannot show it is nonzero.  Fields are
printed in the expression grammar with ``∂`` names; printed LaTeX is shown with
its layout commands removed.  Ranks are not decided here: the audit calls the
one rank engine, :func:`nilpotent.core.decide.rank`.
"""

from __future__ import annotations

import random
import re
from collections.abc import Sequence

import sympy as sp

from nilpotent.core.model.expressions import as_expr, format_expression
from nilpotent.report.latexmath import strip_layout
from nilpotent.report.paper import PrintedField

__all__ = [
    "at_origin",
    "exact_value",
    "fmt",
    "fmt_rate",
    "fmt_vec",
    "format_field",
    "matrix_text",
    "printed_field",
    "printed_matrix",
    "proportional",
    "push_forward",
    "same_exprs",
    "vanishes_identically",
    "weighted_part",
]

_SAMPLES = 6
_DIGITS = 30
_NUMERIC_ZERO = sp.Float("1e-20")


def vanishes_identically(expr: sp.Expr | int, seed: int = 0) -> bool:
    """Whether ``expr`` is identically zero (random 30-digit points, then sympy)."""
    e = sp.expand(as_expr(expr))
    if e == 0:
        return True
    free = sorted(e.free_symbols, key=str)
    if not free:
        return abs(sp.N(e, _DIGITS)) < _NUMERIC_ZERO and sp.simplify(e) == 0
    rng = random.Random(seed)
    for _ in range(_SAMPLES):
        point = {s: sp.Rational(rng.randint(-97, 97), 31) for s in free}
        if abs(sp.N(e.subs(list(point.items())), _DIGITS)) > _NUMERIC_ZERO:
            return False
    return True


def same_exprs(a: Sequence[sp.Expr | int], b: Sequence[sp.Expr | int]) -> bool:
    return len(a) == len(b) and all(
        vanishes_identically(as_expr(x) - as_expr(y)) for x, y in zip(a, b, strict=True)
    )


def exact_value(value: sp.Expr) -> sp.Expr:
    return sp.nsimplify(sp.simplify(value)) if as_expr(value).free_symbols == set() else value


def at_origin(field: Sequence[sp.Expr], coords: Sequence[sp.Symbol]) -> tuple[sp.Expr, ...]:
    zero = [(c, 0) for c in coords]
    return tuple(sp.radsimp(sp.simplify(as_expr(c).subs(zero))) for c in field)


def fmt(value: sp.Expr) -> str:
    return format_expression(as_expr(value))


def format_field(comps: Sequence[sp.Expr | int], coords: Sequence[sp.Symbol]) -> str:
    """``sqrt(3)*∂x5 - sqrt(3)*∂x6``: a field in the expression grammar with ∂ names."""
    terms = []
    for c, x in zip(comps, coords, strict=True):
        c = as_expr(c)
        if c == 0:
            continue
        name = f"∂{x}"
        if c == 1:
            terms.append(name)
        elif c == -1:
            terms.append(f"-{name}")
        else:
            sign = ""
            if c.could_extract_minus_sign():
                sign, c = "-", -c
            text = fmt(c)
            if not (c.is_Atom or c.is_Function or c.is_Pow or c.is_Mul):
                text = f"({text})"
            terms.append(f"{sign}{text}*{name}")
    text = " + ".join(terms) or "0"
    return text.replace("+ -", "- ")


def printed_field(field: PrintedField) -> str:
    """A field as printed in the paper: ``g_1 = <its LaTeX>``, whitespace normalised."""
    name = ("\\hat g_" if field.name.startswith("ĝ") else "g_") + field.name[-1]
    return f"{name} = " + re.sub(r"\s+", " ", field.latex).strip()


def printed_matrix(latex: str) -> str:
    """The printed matrix's LaTeX cells without layout commands: ``[a, b, ...; ...]``."""
    rows = []
    for row in latex.split("\\\\"):
        cells = [re.sub(r"\s+", " ", strip_layout(c)).strip() for c in row.split("&")]
        rows.append(", ".join(cells))
    return "[" + "; ".join(rows) + "]"


def fmt_vec(values: Sequence[sp.Expr]) -> str:
    return "(" + ", ".join(fmt(v) for v in values) + ")"


def fmt_rate(values: Sequence[float]) -> str:
    """Simulated rates to 4 decimals (values below 5e-5 print as 0)."""
    return "(" + ", ".join(f"{v:.4f}" if abs(v) >= 5e-5 else "0" for v in values) + ")"


def proportional(u: Sequence[sp.Expr | int], v: Sequence[sp.Expr | int]) -> bool:
    """Both nonzero and parallel (``u = c v`` for some real ``c ≠ 0``)."""
    if all(vanishes_identically(a) for a in u) or all(vanishes_identically(b) for b in v):
        return False
    return all(
        vanishes_identically(u[i] * v[j] - u[j] * v[i])
        for i in range(len(u))
        for j in range(i + 1, len(u))
    )


def weighted_part(
    expr: sp.Expr, ys: Sequence[sp.Symbol], weights: Sequence[int], d: int
) -> sp.Expr:
    """The terms of weighted degree ``d`` of ``expr`` at 0 (Taylor; weights ``w_k`` of ``y_k``)."""
    t = sp.Dummy("t")
    scaled = as_expr(expr).subs(
        {y: t**w * y for y, w in zip(ys, weights, strict=True)}, simultaneous=True
    )
    coeff = sp.diff(scaled, t, d).subs(t, 0) / sp.factorial(d)
    return sp.expand(sp.simplify(coeff))


def push_forward(
    fields: Sequence[Sequence[sp.Expr]],
    jac: sp.MatrixBase,
    old: Sequence[sp.Symbol],
    inverse: dict,
) -> tuple[tuple[sp.Expr, ...], ...]:
    """Push fields forward by a change of coordinates with Jacobian ``jac`` (new/old)."""
    out = []
    for f in fields:
        col = jac * sp.Matrix([as_expr(c) for c in f])
        out.append(tuple(sp.expand(as_expr(c).subs(inverse, simultaneous=True)) for c in col))
    return tuple(out)


def matrix_text(m: sp.MatrixBase) -> str:
    return "[" + "; ".join(", ".join(fmt(v) for v in m.row(r)) for r in range(m.rows)) + "]"
