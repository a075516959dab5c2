"""Sympy expressions as CasADi expressions (the fields of :mod:`nilpotent.planning.ocp`).

A walk of the sympy tree with a fixed table of operations: an output target, like the
LaTeX printer, not a second numerical compiler (nothing here generates or evaluates
source text).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import sympy as sp

from nilpotent.errors import MissingExtraError, OptionError

__all__ = ["casadi_module", "to_casadi"]

_INSTALL = 'pip install "nilpotent[ocp]"'


def casadi_module() -> Any:
    """The ``casadi`` module (the optional extra ``ocp``).

    Raises
    ------
    MissingExtraError
        CasADi is not installed.
    """
    try:
        import casadi  # pyright: ignore[reportMissingImports]  (the optional [ocp] extra)
    except ImportError:
        raise MissingExtraError(
            f"--refine ocp (refine='ocp') needs CasADi, which is not installed: {_INSTALL}"
        ) from None
    return casadi


def _functions(ca: Any) -> dict[type, Any]:
    return {
        sp.sin: ca.sin, sp.cos: ca.cos, sp.tan: ca.tan, sp.exp: ca.exp, sp.log: ca.log,
        sp.atan: ca.atan, sp.asin: ca.asin, sp.acos: ca.acos, sp.sinh: ca.sinh,
        sp.cosh: ca.cosh, sp.tanh: ca.tanh, sp.Abs: ca.fabs, sp.sign: ca.sign,
        sp.sec: lambda a: 1 / ca.cos(a), sp.csc: lambda a: 1 / ca.sin(a),
        sp.cot: lambda a: 1 / ca.tan(a),
    }


def to_casadi(expr: sp.Basic | float, symbols: Mapping[sp.Symbol, Any]) -> Any:
    """The CasADi expression of a sympy expression (a walk of its tree, shared parts once).

    Parameters
    ----------
    expr : sympy.Basic or float
        Numbers, the symbols of ``symbols``, ``+``, ``*``, powers and the functions
        ``sin cos tan exp log atan atan2 asin acos sinh cosh tanh Abs sign sec csc cot
        Min Max``.
    symbols : mapping
        sympy symbol → CasADi expression (``SX`` or ``MX``).

    Returns
    -------
    casadi.SX or casadi.MX

    Raises
    ------
    OptionError
        A symbol not in ``symbols`` (an unsubstituted parameter) or an operation outside
        the table.
    MissingExtraError
        CasADi is not installed.
    TypeError
        ``expr`` is neither a sympy expression nor a number (text is never parsed here).
    """
    ca = casadi_module()
    table = _functions(ca)
    memo: dict[sp.Basic, Any] = {}

    def walk(e: sp.Basic) -> Any:
        if e in memo:
            return memo[e]
        if isinstance(e, sp.Symbol):
            if e not in symbols:
                raise OptionError(f"--refine ocp: the fields use {e}, which is no coordinate")
            out = symbols[e]
        elif e.is_number and not e.free_symbols:
            value = complex(sp.N(e, 17))
            if value.imag != 0 or not math.isfinite(value.real):
                raise OptionError(f"--refine ocp: {e} is not a finite real number")
            out = value.real
        elif isinstance(e, sp.Add):
            parts = [walk(a) for a in e.args]
            out = parts[0]
            for p in parts[1:]:
                out = out + p
        elif isinstance(e, sp.Mul):
            parts = [walk(a) for a in e.args]
            out = parts[0]
            for p in parts[1:]:
                out = out * p
        elif isinstance(e, sp.Pow):
            base, exp = e.args
            if exp == sp.Rational(1, 2):
                out = ca.sqrt(walk(base))
            elif isinstance(exp, sp.Integer):
                out = ca.constpow(walk(base), int(exp))
            else:
                out = ca.power(walk(base), walk(exp))
        elif isinstance(e, sp.atan2):
            out = ca.atan2(walk(e.args[0]), walk(e.args[1]))
        elif isinstance(e, sp.Min | sp.Max):
            op = ca.fmin if isinstance(e, sp.Min) else ca.fmax
            parts = [walk(a) for a in e.args]
            out = parts[0]
            for p in parts[1:]:
                out = op(out, p)
        elif type(e) in table and len(e.args) == 1:
            out = table[type(e)](walk(e.args[0]))
        else:
            raise OptionError(
                f"--refine ocp: cannot translate {type(e).__name__} of the fields to CasADi")
        memo[e] = out
        return out

    if isinstance(expr, sp.Basic):
        return walk(expr)
    if isinstance(expr, int | float) and not isinstance(expr, bool):
        return walk(sp.Float(expr) if isinstance(expr, float) else sp.Integer(expr))
    # never text: user text reaches the fields only through the expression grammar
    raise TypeError(f"to_casadi takes a sympy expression or a number, not {type(expr).__name__}")
