"""A small translator from the LaTeX math of the paper to the expression grammar.

The audit reads the paper's formulas from its LaTeX source (shipped as
``report/assets/paper.tex``) instead of copying them by hand.  This module turns
a LaTeX math fragment into *text of the safe expression grammar*
(:mod:`nilpotent.core.model.expressions`), which
:func:`~nilpotent.core.model.expressions.parse_expression` then turns into sympy.
Nothing here evaluates anything: it is a tokenizer and a recursive-descent
parser that re-prints what it reads.

What it understands (the subset the paper uses):

* numbers, single-letter symbols and commands with subscripts (``x_1``,
  ``x_{1}``, ``\\phi_1``, ``\\theta``), looked up in a caller's table that maps
  the LaTeX spelling (``"x_1"``, ``"\\phi_1"``) to a grammar name;
* ``+ -``, ``\\cdot``, juxtaposition (multiplication), ``^``, parentheses
  (``(...)``, ``\\left( ... \\right)``) and braces;
* ``\\frac``, ``\\tfrac``, ``\\dfrac``; ``\\sqrt{..}`` and ``\\sqrt 3`` (TeX's
  one-token argument); ``\\pi``;
* ``\\sin \\cos \\tan \\exp \\log``, with a parenthesised argument or, as in
  ``\\sin\\omega t``, the juxtaposed product that follows;
* ``\\partial_{x_1}``, ``\\partial_x``, ``\\partial x_4``: a coordinate vector
  field, printed as the placeholder name :data:`PARTIAL_PREFIX` + name so that a
  vector field becomes a linear form in placeholders (see
  :func:`vector_field_to_grammar`);
* spacing commands, ``\\phantom{..}`` and alignment ``&`` are dropped.

Anything else raises :class:`~nilpotent.errors.ExpressionError` naming the
fragment, so a change of the paper's source is noticed rather than misread.

Examples
--------
>>> latex_to_grammar(r"\\sin(x_4-\\tfrac{2\\pi}{3})\\partial_{x_4}", {"x_4": "x4"})
'sin(((x4 - ((2*pi)/(3)))))*D_x4'
>>> latex_to_grammar(r"\\tfrac{\\sqrt 3x_1}{4}", {"x_1": "x1"})
'((sqrt(3)*x1)/(4))'
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass

from nilpotent.errors import ExpressionError

__all__ = [
    "PARTIAL_PREFIX",
    "latex_to_grammar",
    "split_top_level",
    "strip_layout",
    "vector_field_to_grammar",
]

#: Prefix of the placeholder name that stands for a coordinate field ``∂/∂v``.
PARTIAL_PREFIX = "D_"

_FUNCTIONS = {r"\sin": "sin", r"\cos": "cos", r"\tan": "tan", r"\exp": "exp", r"\log": "log"}
_FRACTIONS = {r"\frac", r"\tfrac", r"\dfrac"}
_SPACING = {r"\,", r"\;", r"\:", r"\!", r"\ ", r"\quad", r"\qquad", r"\left", r"\right"}
_TOKEN = re.compile(r"\\[A-Za-z]+|\\[,;:! ]|[0-9]+(?:\.[0-9]+)?|[A-Za-z]|[{}()+\-_^,&=*/\[\]|.]|\S")


@dataclass
class _Token:
    text: str


def strip_layout(tex: str) -> str:
    """Drop ``\\phantom{...}``, alignment ``&`` and TeX comments from a fragment."""
    out = re.sub(r"(?<!\\)%[^\n]*", "", tex)
    out = _remove_command_with_group(out, r"\phantom")
    return out.replace("&", " ")


def _remove_command_with_group(tex: str, command: str) -> str:
    while True:
        start = tex.find(command + "{")
        if start < 0:
            return tex
        depth = 0
        for k in range(start + len(command), len(tex)):
            if tex[k] == "{":
                depth += 1
            elif tex[k] == "}":
                depth -= 1
                if depth == 0:
                    tex = tex[:start] + tex[k + 1 :]
                    break
        else:
            raise ExpressionError(f"unbalanced braces after {command} in {tex!r}")


def split_top_level(tex: str, separator: str) -> list[str]:
    """Split ``tex`` at ``separator`` where it is outside every bracket and brace."""
    parts: list[str] = []
    depth = 0
    current: list[str] = []
    k = 0
    while k < len(tex):
        ch = tex[k]
        if ch in "({[":
            depth += 1
        elif ch in ")}]":
            depth -= 1
        if depth == 0 and tex.startswith(separator, k):
            parts.append("".join(current))
            current = []
            k += len(separator)
            continue
        current.append(ch)
        k += 1
    parts.append("".join(current))
    return parts


class _Parser:
    """Recursive descent over LaTeX tokens, printing grammar text."""

    def __init__(self, tex: str, symbols: Mapping[str, str]) -> None:
        self.source = tex
        self.symbols = symbols
        tokens = [m.group(0) for m in _TOKEN.finditer(strip_layout(tex))]
        self.tokens = [t for t in tokens if t not in _SPACING]
        self.pos = 0

    # -- token access -------------------------------------------------------
    def peek(self) -> str | None:
        return self.tokens[self.pos] if self.pos < len(self.tokens) else None

    def take(self) -> str:
        tok = self.peek()
        if tok is None:
            raise self.error("unexpected end")
        self.pos += 1
        return tok

    def expect(self, text: str) -> None:
        tok = self.take()
        if tok != text:
            raise self.error(f"expected {text!r}, found {tok!r}")

    def error(self, problem: str) -> ExpressionError:
        return ExpressionError(f"LaTeX math {self.source!r}: {problem}")

    # -- grammar ------------------------------------------------------------
    def parse(self) -> str:
        out = self.expression()
        if self.peek() is not None:
            raise self.error(f"unexpected {self.peek()!r}")
        return out

    def expression(self) -> str:
        pieces: list[str] = []
        sign = self.signs()
        pieces.append(f"{sign}{self.term()}")
        while self.peek() in ("+", "-"):
            sign = self.signs()
            pieces.append(f" {sign or '+'} {self.term()}")
        text = "".join(pieces).strip()
        return f"({text})" if len(pieces) > 1 or text.startswith("-") else text

    def signs(self) -> str:
        negative = False
        seen = False
        while self.peek() in ("+", "-"):
            seen = True
            negative ^= self.take() == "-"
        if not seen:
            return ""
        return "-" if negative else ""

    def starts_factor(self, tok: str | None) -> bool:
        if tok is None or tok in ("+", "-", ")", "}", ",", "=", r"\right"):
            return False
        return tok != "]"

    def term(self) -> str:
        factors = [self.factor()]
        while True:
            tok = self.peek()
            if tok == r"\cdot":
                self.take()
                factors.append(self.factor())
            elif tok == "/":
                self.take()
                factors[-1] = f"{factors[-1]}/{self.factor()}"
            elif self.starts_factor(tok):
                factors.append(self.factor())
            else:
                return "*".join(factors)

    def factor(self) -> str:
        base = self.atom()
        if self.peek() == "^":
            self.take()
            base = f"{base}**({self.group_or_token()})"
        return base

    def group_or_token(self, *, single: bool = True) -> str:
        """A ``{...}`` group, a parenthesised or a one-token argument (TeX style)."""
        tok = self.peek()
        if tok == "{":
            self.take()
            inner = self.expression()
            self.expect("}")
            return inner
        if single and tok is not None and tok.isdigit() and len(tok) > 1:
            # TeX takes one character as an undelimited argument: \sqrt 32 = sqrt(3)*2
            self.tokens[self.pos] = tok[1:]
            return tok[0]
        return self.atom()

    def atom(self) -> str:
        tok = self.take()
        if tok in ("(", r"\left("):
            inner = self.expression()
            closing = self.take()
            if closing != ")":
                raise self.error(f"expected ')', found {closing!r}")
            return f"({inner})"
        if tok == "{":
            inner = self.expression()
            self.expect("}")
            return f"({inner})"
        if re.fullmatch(r"[0-9]+(?:\.[0-9]+)?", tok):
            return tok
        if tok in _FRACTIONS:
            num = self.group_or_token()
            den = self.group_or_token()
            return f"(({num})/({den}))"
        if tok == r"\sqrt":
            return f"sqrt({self.group_or_token()})"
        if tok == r"\pi":
            return "pi"
        if tok in _FUNCTIONS:
            return f"{_FUNCTIONS[tok]}({self.function_argument()})"
        if tok == r"\partial":
            return PARTIAL_PREFIX + self.partial_variable()
        if re.fullmatch(r"[A-Za-z]|\\[A-Za-z]+", tok):
            return self.symbol(tok)
        raise self.error(f"unsupported token {tok!r}")

    def function_argument(self) -> str:
        if self.peek() == "(":
            self.take()
            inner = self.expression()
            self.expect(")")
            return f"({inner})"
        # \sin\omega t: the juxtaposed product up to an operator, a field or a function
        factors = [self.factor()]
        while True:
            tok = self.peek()
            if not self.starts_factor(tok) or tok in _FUNCTIONS or tok in (r"\partial", "("):
                break
            factors.append(self.factor())
        return "*".join(factors)

    def partial_variable(self) -> str:
        if self.peek() == "_":
            self.take()
            if self.peek() == "{":
                self.take()
                name = self.symbol(self.take())
                self.expect("}")
                return name
        return self.symbol(self.take())

    def symbol(self, base: str) -> str:
        key = base
        if self.peek() == "_":
            self.take()
            if self.peek() == "{":
                self.take()
                sub: list[str] = []
                while self.peek() not in ("}", None):
                    sub.append(self.take())
                self.expect("}")
                key = f"{base}_{''.join(sub)}"
            else:
                sub_tok = self.take()
                if sub_tok.isdigit() and len(sub_tok) > 1:
                    self.tokens.insert(self.pos, sub_tok[1:])
                    sub_tok = sub_tok[0]
                key = f"{base}_{sub_tok}"
        if key not in self.symbols:
            known = ", ".join(sorted(self.symbols))
            raise self.error(f"unknown symbol {key!r} (known: {known})")
        return self.symbols[key]


def latex_to_grammar(tex: str, symbols: Mapping[str, str]) -> str:
    """Translate one LaTeX math expression into text of the expression grammar.

    Parameters
    ----------
    tex:
        The LaTeX fragment (no ``$``), e.g. ``r"\\cos\\theta\\partial_x"``.
    symbols:
        LaTeX spelling → grammar name, e.g. ``{"\\theta": "theta", "x_1": "x1"}``.
        ``\\partial_v`` prints as ``PARTIAL_PREFIX + symbols[v]``.

    Returns
    -------
    str
        Text that :func:`nilpotent.core.model.expressions.parse_expression` parses.
    """
    return _Parser(tex, symbols).parse()


def vector_field_to_grammar(tex: str, symbols: Mapping[str, str]) -> str:
    """Translate a vector field ``Σ a_j ∂_{v_j}`` into grammar text linear in placeholders.

    The result, parsed with names that include ``PARTIAL_PREFIX + name`` for
    every coordinate, is a linear form whose coefficient of each placeholder is
    the component along that coordinate.  A field ``0`` is accepted.
    """
    if tex.strip() == "0":
        return "0"
    return latex_to_grammar(tex, symbols)
