"""A printer of sympy expressions as text of the expression grammar, linear in their size.

Used by :func:`nilpotent.core.model.expressions.format_expression` for large
expressions (the polynomials of exponential coordinates have thousands of
terms), where sympy's ``StrPrinter`` sorts every sum and is far slower.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import sympy as sp

from nilpotent.errors import ExpressionError

__all__ = ["print_linear"]


def print_linear(e: sp.Basic, functions: Mapping[Any, str]) -> str:
    """Text of the grammar for ``e`` in time linear in its size (terms in stored order).

    sympy's printer sorts the terms of every sum and computes precedences
    through the assumptions system, quadratic in practice on polynomials of
    thousands of terms; this walks the tree once.  The text parses back to an
    equal expression.  ``functions`` names the printable functions (sympy class →
    name in the grammar).

    Raises
    ------
    ExpressionError
        For a node the grammar cannot write.
    """
    if isinstance(e, sp.Float):
        return repr(float(e))
    if isinstance(e, sp.Integer):
        return str(int(e))
    if isinstance(e, sp.Rational):
        return f"{e.p}/{e.q}"
    if isinstance(e, sp.Symbol):
        return e.name
    if e is sp.pi:
        return "pi"
    if e is sp.E:
        return "E"
    if isinstance(e, sp.Add):
        out = []
        for k, a in enumerate(e.args):
            t = print_linear(a, functions)
            if k == 0:
                out.append(t)
            elif t.startswith("-"):
                out.append(" - " + t[1:])
            else:
                out.append(" + " + t)
        return "".join(out)
    if isinstance(e, sp.Mul):
        parts = []
        for k, a in enumerate(e.args):
            t = print_linear(a, functions)
            if k == 0 and a == -1 and len(e.args) > 1:
                parts.append("-")
                continue
            if isinstance(a, sp.Add) or (k > 0 and t.startswith("-")):
                t = f"({t})"
            parts.append(t)
        head = parts[0] if parts[0] == "-" else None
        body = "*".join(parts[1:] if head else parts)
        return f"-{body}" if head else body
    if isinstance(e, sp.Pow):
        base, ex = e.args
        b = print_linear(base, functions)
        if not (isinstance(base, sp.Symbol | sp.Function) or base in (sp.pi, sp.E)
                or (isinstance(base, sp.Integer) and base > 0)):
            b = f"({b})"
        x = print_linear(ex, functions)
        if not (isinstance(ex, sp.Integer) and ex >= 0):
            x = f"({x})"
        return f"{b}**{x}"
    if isinstance(e, sp.Function):
        return f"{functions[e.func]}({', '.join(print_linear(a, functions) for a in e.args)})"
    raise ExpressionError(f"cannot write {type(e).__name__} in the expression grammar")
