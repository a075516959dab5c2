"""The safe expression grammar: user text → sympy expressions, and back.

Every expression a user writes (model-file components, parameter values,
``--at`` points, ``--param`` values) goes through :func:`parse_expression`.
It parses with Python's :mod:`ast` (``mode="eval"``; nothing is ever
evaluated by Python) and walks an explicit whitelist of node types, building
the sympy objects itself:

* integer literals → exact :class:`sympy.Integer`; decimal literals (``0.5``,
  ``1e-3``) → :class:`sympy.Float` (so floats stay floats; ``1/2`` is the exact
  rational one half, by sympy division);
* names from the caller's ``names`` mapping, plus the constants ``pi`` and ``E``;
* ``+ - * / **``, unary ``+``/``-``, parentheses;
* calls of the functions in :data:`FUNCTIONS` with their arity
  (``atan2(y, x)`` takes two arguments, the others one).

Anything else is refused with :class:`~nilpotent.errors.ExpressionError`, whose
message names the place (``where``, e.g. ``"model.toml: fields[1].theta (X2)"``),
the offending piece and the whole text.  Blow-ups are refused before sympy
evaluates them: a numeric exponent of magnitude above :data:`MAX_EXPONENT`
(so ``9**9**9**9`` fails at ``9**387420489``), an exact power result above
:data:`MAX_BITS` bits, a decimal value outside the range of a double, text
longer than :data:`MAX_LENGTH` characters, nesting deeper than :data:`MAX_DEPTH`.

:func:`format_expression` prints an expression of the grammar as text that
:func:`parse_expression` parses back to an equal expression (``"sqrt(3)/2"``,
``"pi/3"``, ``"0.1"``).  :func:`real_value` evaluates a constant expression
with Python floats (never with unbounded-precision arithmetic) and checks that
it is a finite real number.
"""

from __future__ import annotations

import ast
import keyword
import math
import operator
import warnings
from collections.abc import Callable, Mapping, Sequence

import sympy as sp
from sympy.core.sympify import _sympify as _strict_sympy
from sympy.printing.str import StrPrinter

from nilpotent.core.model.linear_printer import print_linear
from nilpotent.errors import ComputationLimitError, ExpressionError

__all__ = [
    "CONSTANTS",
    "FUNCTIONS",
    "MAX_BITS",
    "MAX_DEPTH",
    "MAX_EXPONENT",
    "MAX_LENGTH",
    "RESERVED_NAMES",
    "as_expr",
    "exact_decimals",
    "format_expression",
    "negative_root",
    "parse_expression",
    "real_value",
]

#: Longest accepted expression text, in characters.
MAX_LENGTH = 2000
#: Deepest accepted nesting (parentheses, operators, calls).
MAX_DEPTH = 100
#: Largest accepted magnitude of a numeric exponent.
MAX_EXPONENT = 100
#: Largest accepted size, in bits, of an exact number produced by a power.
MAX_BITS = 4096
#: Most terms an expression may have once expanded (estimated before expanding).
MAX_TERMS = 10_000

#: Functions of the grammar: name → (sympy function, number of arguments).
FUNCTIONS: dict[str, tuple[Callable[..., sp.Expr], int]] = {
    "sin": (sp.sin, 1),
    "cos": (sp.cos, 1),
    "tan": (sp.tan, 1),
    "exp": (sp.exp, 1),
    "log": (sp.log, 1),
    "sqrt": (sp.sqrt, 1),
    "atan": (sp.atan, 1),
    "atan2": (sp.atan2, 2),
    "sinh": (sp.sinh, 1),
    "cosh": (sp.cosh, 1),
    "tanh": (sp.tanh, 1),
}

#: Named constants of the grammar.
CONSTANTS: dict[str, sp.Expr] = {"pi": sp.pi, "E": sp.E}

#: Names a user may not give to a coordinate or a parameter.
RESERVED_NAMES: frozenset[str] = frozenset(FUNCTIONS) | frozenset(CONSTANTS)

_ARITHMETIC: dict[type, Callable[[sp.Expr, sp.Expr], sp.Expr]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
}

_REFUSED_OPERATORS: dict[type, str] = {
    ast.FloorDiv: "floor division '//'",
    ast.Mod: "the operator '%'",
    ast.MatMult: "the operator '@'",
    ast.BitXor: "the operator '^' (write powers as '**')",
    ast.BitOr: "the operator '|'",
    ast.BitAnd: "the operator '&'",
    ast.LShift: "the operator '<<'",
    ast.RShift: "the operator '>>'",
    ast.Invert: "the operator '~'",
    ast.Not: "'not'",
}

_REFUSED_NODES: dict[type, str] = {
    ast.Attribute: "attribute access",
    ast.Subscript: "subscripts",
    ast.Slice: "slices",
    ast.Lambda: "lambda expressions",
    ast.ListComp: "comprehensions",
    ast.SetComp: "comprehensions",
    ast.DictComp: "comprehensions",
    ast.GeneratorExp: "comprehensions",
    ast.List: "lists",
    ast.Tuple: "tuples (a comma outside a function call)",
    ast.Set: "sets",
    ast.Dict: "dictionaries",
    ast.Compare: "comparisons",
    ast.BoolOp: "boolean operators ('and', 'or')",
    ast.IfExp: "conditional expressions",
    ast.NamedExpr: "assignment expressions (':=')",
    ast.JoinedStr: "strings",
    ast.FormattedValue: "strings",
    ast.Starred: "starred arguments",
    ast.Await: "'await'",
    ast.Yield: "'yield'",
    ast.YieldFrom: "'yield'",
}

_SHOW = 80  # characters of the text shown in messages


def _shorten(text: str) -> str:
    return repr(text if len(text) <= _SHOW else text[: _SHOW - 3] + "...")


class _Parser:
    """Walks the whitelisted AST of one expression and builds sympy objects."""

    def __init__(self, text: str, names: Mapping[str, sp.Basic], where: str) -> None:
        self.text = text
        self.names = names
        self.where = where
        self.seen: set[sp.Basic] = set()

    # --- errors -----------------------------------------------------------
    def fail(self, problem: str, node: ast.AST | None = None, hint: str = "") -> ExpressionError:
        prefix = f"{self.where}: " if self.where else ""
        suffix = f" ({hint})" if hint else ""
        piece = None
        if node is not None:
            try:
                piece = ast.get_source_segment(self.text, node)
            except (ValueError, IndexError):  # pragma: no cover - positions always valid
                piece = None
        if piece is not None and piece.strip() != self.text.strip():
            return ExpressionError(
                f"{prefix}{problem}: {_shorten(piece)} in {_shorten(self.text)}{suffix}")
        return ExpressionError(f"{prefix}{problem} in {_shorten(self.text)}{suffix}")

    def allowed_names(self) -> str:
        user = sorted(str(k) for k in self.names if k not in RESERVED_NAMES)
        return (
            "allowed names: " + ", ".join([*user, *CONSTANTS])
            + "; functions: " + ", ".join(FUNCTIONS)
        )

    # --- walking ----------------------------------------------------------
    def build(self, node: ast.AST, depth: int) -> sp.Expr:
        if depth > MAX_DEPTH:
            raise self.fail(f"expression nested deeper than {MAX_DEPTH} levels", node)
        if isinstance(node, ast.Constant):
            return self.constant(node)
        if isinstance(node, ast.Name):
            return self.name(node)
        if isinstance(node, ast.BinOp):
            return self.binary_chain(node, depth)
        if isinstance(node, ast.UnaryOp):
            operand = self.build(node.operand, depth + 1)
            if isinstance(node.op, ast.USub):
                return self.checked_call(_negative, (operand,), node)
            if isinstance(node.op, ast.UAdd):
                return operand
            raise self.fail(f"{_REFUSED_OPERATORS.get(type(node.op), 'this operator')} "
                            "is not allowed", node)
        if isinstance(node, ast.Call):
            return self.call(node, depth)
        what = _REFUSED_NODES.get(type(node), f"{type(node).__name__} syntax")
        raise self.fail(f"{what} not allowed", node)

    def constant(self, node: ast.Constant) -> sp.Expr:
        value = node.value
        if isinstance(value, bool) or value is None or value is Ellipsis:
            raise self.fail(f"the constant {value!r} is not allowed", node)
        if isinstance(value, int):
            return sp.Integer(value)
        if isinstance(value, float):
            if not math.isfinite(value):
                raise self.fail("number too large (outside the range of a double)", node)
            return sp.Float(value)
        if isinstance(value, str | bytes):
            raise self.fail("strings not allowed", node)
        if isinstance(value, complex):
            raise self.fail("complex numbers not allowed", node)
        raise self.fail(f"the constant {value!r} is not allowed", node)  # pragma: no cover

    def name(self, node: ast.Name) -> sp.Expr:
        ident = node.id
        if ident.startswith("__") and ident.endswith("__"):
            raise self.fail(f"the name {ident!r} is not allowed", None, self.allowed_names())
        if ident in CONSTANTS:
            return CONSTANTS[ident]
        if ident in FUNCTIONS:
            raise self.fail(f"{ident!r} is a function: call it, as in {ident}(x)", node)
        if ident in self.names:
            value = self.names[ident]
            if not isinstance(value, sp.Expr):
                raise self.fail(f"the name {ident!r} does not stand for a scalar", node)
            return value
        raise self.fail(f"unknown name {ident!r}", None, self.allowed_names())

    def binary_chain(self, node: ast.BinOp, depth: int) -> sp.Expr:
        # Left-associative chains (a + b - c + ...) are walked iteratively, so a
        # long sum costs neither recursion nor nesting depth.
        spine: list[ast.BinOp] = []
        left: ast.AST = node
        while isinstance(left, ast.BinOp) and not isinstance(left.op, ast.Pow):
            spine.append(left)
            left = left.left
        if not spine:  # a power: right-associative, walked recursively
            assert isinstance(node.op, ast.Pow)
            base = self.build(node.left, depth + 1)
            exponent = self.build(node.right, depth + 1)
            return self.power(base, exponent, node)
        value = self.build(left, depth + 1)
        for op_node in reversed(spine):
            right = self.build(op_node.right, depth + 1)
            value = self.apply(op_node, value, right)
        return value

    def apply(self, node: ast.BinOp, left: sp.Expr, right: sp.Expr) -> sp.Expr:
        op = type(node.op)
        if op is ast.Div and right.is_zero:
            raise self.fail("division by zero", node)
        operation = _ARITHMETIC.get(op)
        if operation is None:
            raise self.fail(f"{_REFUSED_OPERATORS.get(op, 'this operator')} is not allowed", node)
        return self.checked_call(operation, (left, right), node)

    def power(self, base: sp.Expr, exponent: sp.Expr, node: ast.AST) -> sp.Expr:
        if exponent.is_Number:
            if abs(exponent) > MAX_EXPONENT:
                raise self.fail(
                    f"exponent {_shorten(str(exponent))} too large (at most {MAX_EXPONENT} "
                    "in magnitude)", node)
            if base.is_zero and exponent.is_negative:
                raise self.fail("division by zero (0 to a negative power)", node)
            if isinstance(base, sp.Rational):
                bits = max(int(base.p).bit_length(), int(base.q).bit_length())
                if bits * abs(float(exponent)) > MAX_BITS:
                    raise self.fail(f"power too large (more than {MAX_BITS} bits)", node)
        result = self.checked_call(sp.Pow, (base, exponent), node)
        if (
            isinstance(result, sp.Pow)
            and isinstance(result.exp, sp.Number)
            and abs(result.exp) > MAX_EXPONENT
        ):
            raise self.fail(
                f"combined exponent {_shorten(str(result.exp))} too large (at most "
                f"{MAX_EXPONENT} in magnitude)", node)
        return result

    def call(self, node: ast.Call, depth: int) -> sp.Expr:
        func = node.func
        if not isinstance(func, ast.Name):
            what = _REFUSED_NODES.get(type(func), "this kind of call")
            raise self.fail(f"only the grammar's functions may be called ({what})", node)
        if func.id not in FUNCTIONS:
            raise self.fail(f"{func.id!r} is not a function of the grammar", node,
                            "functions: " + ", ".join(FUNCTIONS))
        if node.keywords:
            raise self.fail(f"keyword arguments not allowed in a call of {func.id}", node)
        function, arity = FUNCTIONS[func.id]
        if any(isinstance(a, ast.Starred) for a in node.args):
            raise self.fail("starred arguments not allowed", node)
        if len(node.args) != arity:
            raise self.fail(
                f"{func.id} takes {arity} argument{'s' if arity > 1 else ''}, "
                f"got {len(node.args)}", node)
        args = [self.build(a, depth + 1) for a in node.args]
        if func.id == "log" and args[0].is_zero:
            raise self.fail("log(0) is undefined", node)
        return self.checked_call(function, args, node)

    def checked_call(
        self, function: Callable[..., sp.Expr], args: Sequence[sp.Expr], node: ast.AST
    ) -> sp.Expr:
        """Apply a sympy operation, turning arithmetic failures into ExpressionError."""
        try:
            value = function(*args)
        except ZeroDivisionError:
            raise self.fail("division by zero", node) from None
        except (OverflowError, ValueError, ArithmeticError) as exc:
            raise self.fail(f"cannot evaluate ({type(exc).__name__})", node) from None
        return self.checked(value, node)

    def checked(self, value: sp.Expr, node: ast.AST) -> sp.Expr:
        """Refuse undefined, infinite, complex or out-of-range results.

        sympy may move numbers around while evaluating (``exp(710.0 + x)`` becomes
        ``exp(710.0)*exp(x)``), so the whole result is inspected, not only its head.
        """
        stack: list[sp.Basic] = [value]
        while stack:
            part = stack.pop()
            if part in self.seen:  # subtrees already checked (operands) are skipped
                continue
            self.seen.add(part)
            stack.extend(part.args)
            if part in _UNDEFINED:
                raise self.fail("undefined or infinite value", node)
            if part is sp.I or negative_root(part):
                raise self.fail("complex value (expressions must be real)", node)
            if isinstance(part, sp.Float) and not math.isfinite(float(part)):
                raise self.fail("number too large (outside the range of a double)", node)
            if isinstance(part, sp.Rational) and max(int(part.p).bit_length(),
                                                     int(part.q).bit_length()) > MAX_BITS:
                raise self.fail(f"exact number too large (more than {MAX_BITS} bits)", node)
        return value


_UNDEFINED = (sp.zoo, sp.nan, sp.oo, -sp.oo)


def negative_root(part: sp.Basic) -> bool:
    """A non-integer power of a negative number: ``(-8)**(1/3)`` is ``2*(-1)**(1/3)``, complex."""
    return (isinstance(part, sp.Pow) and part.base.is_number and part.exp.is_number
            and part.base.is_negative is True and part.exp.is_integer is False)


def _max_paren_depth(text: str) -> int:
    depth = best = 0
    for ch in text:
        if ch in "([{":
            depth += 1
            best = max(best, depth)
        elif ch in ")]}":
            depth -= 1
    return best


def parse_expression(text: str, names: Mapping[str, sp.Basic], *, where: str = "") -> sp.Expr:
    """Parse user text of the safe grammar into a sympy expression.

    Parameters
    ----------
    text:
        The expression, e.g. ``"cos(theta)"`` or ``"sqrt(3)/2"``.
    names:
        The names the text may use (coordinates, parameters) and their sympy
        values. ``pi`` and ``E`` are always available and take precedence, as
        do the function names of :data:`FUNCTIONS`.
    where:
        Where the text comes from, put at the start of error messages
        (``"model.toml: fields[1].theta (X2)"``, ``"--at theta"``).

    Returns
    -------
    sympy.Expr
        The expression, built with sympy's constructors (integers and ``a/b``
        exact, decimals as :class:`sympy.Float`).

    Raises
    ------
    ExpressionError
        For anything outside the grammar (see the module docstring), for
        undefined or complex values (``1/0``, ``sqrt(-1)``), and for blow-ups.

    Examples
    --------
    >>> import sympy as sp
    >>> th = sp.Symbol("theta")
    >>> parse_expression("cos(theta)/2", {"theta": th})
    cos(theta)/2
    >>> parse_expression("sqrt(3)/2 + 0.5", {})
    0.5 + sqrt(3)/2
    """
    prefix = f"{where}: " if where else ""
    if not isinstance(text, str):
        raise ExpressionError(f"{prefix}expected an expression as text, got {text!r}")
    if not text.strip():
        raise ExpressionError(f"{prefix}empty expression")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(
            f"{prefix}expression too long ({len(text)} characters, at most {MAX_LENGTH}): "
            f"{_shorten(text)}")
    if _max_paren_depth(text) > MAX_DEPTH:
        raise ExpressionError(
            f"{prefix}expression nested deeper than {MAX_DEPTH} levels: {_shorten(text)}")
    try:
        with warnings.catch_warnings():  # e.g. "invalid decimal literal": we report our own
            warnings.simplefilter("ignore", SyntaxWarning)
            tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        detail = exc.msg if exc.msg else "invalid syntax"
        col = f" at column {exc.offset}" if exc.offset else ""
        raise ExpressionError(f"{prefix}syntax error ({detail}){col} in {_shorten(text)}") from None
    except (ValueError, RecursionError, MemoryError, OverflowError) as exc:
        raise ExpressionError(f"{prefix}cannot parse {_shorten(text)}: {exc}") from None
    parser = _Parser(text.strip(), names, where)
    try:
        result = parser.build(tree.body, 1)
    except RecursionError:
        raise ExpressionError(
            f"{prefix}expression nested too deeply: {_shorten(text)}") from None
    terms = expanded_terms(result)
    if terms > MAX_TERMS:
        raise ComputationLimitError(
            f"{prefix}{_shorten(text)} would expand to about {terms:.3g} terms, above the "
            f"limit {MAX_TERMS:,} (nilpotent.core.model.expressions.MAX_TERMS); brackets and "
            "Taylor expansions expand it: write the system with fewer or smaller powers")
    return result


def expanded_terms(expr: sp.Basic) -> int:
    """An upper estimate of the number of terms of ``expr`` once expanded, computed without
    expanding: sums add, products multiply, ``(a_1 + ... + a_k)**e`` gives the
    number of monomials of degree ``e`` in ``k`` terms, ``C(k + e - 1, e)``; a function
    counts as one term, but its argument's count is kept (derivatives bring it out).
    The result is capped just above :data:`MAX_TERMS` times a large margin."""
    cap = MAX_TERMS * 1000
    memo: dict[sp.Basic, int] = {}

    def count(e: sp.Basic) -> int:
        if e in memo:
            return memo[e]
        if e.is_Add:
            value = sum(count(a) for a in e.args)
        elif e.is_Mul:
            value = math.prod(count(a) for a in e.args)
        elif isinstance(e, sp.Pow):
            k = count(e.base)
            x = e.exp
            if isinstance(x, sp.Integer) and k > 1:
                n = abs(int(x))
                value = math.comb(k + n - 1, n) if n < 10_000 else cap
            else:
                value = max(k, count(x))
        elif e.args:
            value = max(1, *(count(a) for a in e.args))
        else:
            value = 1
        memo[e] = value = min(value, cap)
        return value

    return count(expr)


# --- printing ----------------------------------------------------------------

_PRINTABLE_FUNCTIONS = {FUNCTIONS[name][0]: name for name in FUNCTIONS if name != "sqrt"}


class _GrammarPrinter(StrPrinter):
    """sympy's str printer with floats printed as the shortest round-tripping decimal."""

    def _print_Float(self, expr: sp.Float) -> str:
        return repr(float(expr))


_PRINTER = _GrammarPrinter({"order": None})


SMALL_EXPRESSION_NODES = 2_000
"""Expressions with more nodes are printed by the linear-time printer (``print_linear``)."""


def _check_printable(expr: sp.Basic) -> int:
    """Refuse what the grammar cannot write; return the number of nodes of ``expr``."""
    nodes = 0
    stack = [expr]
    while stack:
        node = stack.pop()
        nodes += 1
        if isinstance(node, sp.Add | sp.Mul | sp.Pow):
            stack.extend(node.args)
            continue
        if isinstance(node, sp.Integer | sp.Rational):
            continue
        if isinstance(node, sp.Function):
            stack.extend(node.args)
        if isinstance(node, sp.Symbol):
            name = node.name
            if (not name.isidentifier() or keyword.iskeyword(name) or name in RESERVED_NAMES
                    or (name.startswith("__") and name.endswith("__"))):
                raise ExpressionError(
                    f"cannot write {expr} in the expression grammar: symbol name {node.name!r}")
        elif isinstance(node, sp.Float):
            if not math.isfinite(float(node)):
                raise ExpressionError(f"cannot write {expr} in the expression grammar: "
                                      f"non-finite number {node}")
        elif node in (sp.zoo, sp.nan, sp.oo, -sp.oo, sp.I):
            raise ExpressionError(f"cannot write {expr} in the expression grammar: {node}")
        elif not (
            isinstance(node, sp.Rational | sp.Add | sp.Mul | sp.Pow)
            or node in (sp.pi, sp.E)
            or (isinstance(node, sp.Function) and node.func in _PRINTABLE_FUNCTIONS)
        ):
            raise ExpressionError(
                f"cannot write {expr} in the expression grammar: {type(node).__name__} "
                f"({node})")
    return nodes


def format_expression(expr: sp.Basic | int | float) -> str:
    """Print an expression as text of the grammar.

    The result parses back, with :func:`parse_expression` and the same names,
    to an equal expression: exact numbers stay exact (``"sqrt(3)/2"``,
    ``"-pi/3"``), floats are printed as the shortest decimal that reads back
    as the same double (``"0.1"``, ``"1e-05"``).

    Parameters
    ----------
    expr : sympy expression, int or float
        The expression to print.

    Raises
    ------
    ExpressionError
        When the expression uses something the grammar cannot write (another
        function, ``I``, infinities, a symbol name that is not an identifier).

    Examples
    --------
    >>> import sympy as sp
    >>> format_expression(sp.sqrt(3) / 2)
    'sqrt(3)/2'
    >>> format_expression(sp.Float(0.1) * sp.Symbol("x") - sp.pi / 3)
    '0.1*x - pi/3'
    """
    if isinstance(expr, bool):
        raise ExpressionError(f"cannot write {expr!r} in the expression grammar")
    if isinstance(expr, int):
        expr = sp.Integer(expr)
    elif isinstance(expr, float):
        expr = sp.Float(expr)
    if not isinstance(expr, sp.Basic):
        raise ExpressionError(f"cannot write {expr!r} in the expression grammar")
    nodes = _check_printable(expr)
    try:
        if nodes > SMALL_EXPRESSION_NODES:
            return print_linear(expr, _PRINTABLE_FUNCTIONS)
        return _PRINTER.doprint(expr)
    except ValueError as exc:  # an integer past Python's 4300-digit int-to-str limit
        if "digits" not in str(exc):
            raise
        raise ComputationLimitError(
            "an exact number of the result has more than 4300 decimal digits: too large to "
            "print (use decimal values or smaller exact numbers)") from None


# --- numeric values of constants ----------------------------------------------

_FLOAT_FUNCTIONS: dict[type, Callable[..., float]] = {
    sp.sin: math.sin,
    sp.cos: math.cos,
    sp.tan: math.tan,
    sp.exp: math.exp,
    sp.log: math.log,
    sp.atan: math.atan,
    sp.atan2: math.atan2,
    sp.sinh: math.sinh,
    sp.cosh: math.cosh,
    sp.tanh: math.tanh,
}


def _negative(value: sp.Expr) -> sp.Expr:
    return -value


def as_expr(value: object) -> sp.Expr:
    """A number or sympy expression built by the program as a scalar sympy expression.

    Never for user text, which goes through :func:`parse_expression`.

    Parameters
    ----------
    value : int, float, fractions.Fraction or sympy expression
        The value.

    Raises
    ------
    TypeError
        If ``value`` is text, or is not a scalar (a matrix, a set, a boolean, ...).
    """
    if isinstance(value, str):
        raise TypeError(f"as_expr does not read text ({value!r}): use parse_expression")
    expr = _strict_sympy(value)  # strict: never parses text
    if not isinstance(expr, sp.Expr):
        raise TypeError(f"{value!r} is not a scalar expression")
    return expr


def _decimal_rational(f: float | sp.Float) -> sp.Expr:
    """The exact rational a decimal denotes: the shortest decimal that reads back as the float."""
    if isinstance(f, sp.Float) and f._prec != 53:
        return sp.Rational(str(f))
    return sp.Rational(repr(float(f)))


def exact_decimals(expr: object) -> sp.Expr:
    """``expr`` with every decimal (float) replaced by the exact rational it denotes.

    ``0.7`` becomes ``7/10`` (the shortest decimal that reads back as the double),
    so that decimals are decided exactly like fractions.

    Examples
    --------
    >>> exact_decimals(sp.Float(0.7) * sp.Symbol("x"))
    7*x/10
    """
    e = as_expr(expr)
    floats = e.atoms(sp.Float)
    if not floats:
        return e
    return as_expr(e.xreplace({f: _decimal_rational(f) for f in floats}))


def _float_value(expr: sp.Basic) -> float:
    if isinstance(expr, sp.Rational):
        return int(expr.p) / int(expr.q)
    if isinstance(expr, sp.Float):
        return float(expr)
    if expr is sp.pi:
        return math.pi
    if expr is sp.E:
        return math.e
    if expr.is_Add:
        return math.fsum(_float_value(a) for a in expr.args)
    if expr.is_Mul:
        return math.prod(_float_value(a) for a in expr.args)
    if isinstance(expr, sp.Pow):
        return math.pow(_float_value(expr.base), _float_value(expr.exp))
    if isinstance(expr, sp.Function) and expr.func in _FLOAT_FUNCTIONS:
        return _FLOAT_FUNCTIONS[expr.func](*(_float_value(a) for a in expr.args))
    raise TypeError(type(expr).__name__)


def real_value(expr: sp.Basic, *, where: str = "") -> float:
    """The value of a constant expression as a Python float, checked finite and real.

    Evaluation uses double-precision arithmetic only (so it is fast and bounded
    whatever the expression); exact cancellations that pass through complex
    or non-finite intermediate values are reported as not real.

    Raises
    ------
    ExpressionError
        If the expression has free symbols, is not real (``log(-1)``), or
        overflows a double (``exp(1000)``).

    Examples
    --------
    >>> import sympy as sp
    >>> real_value(sp.sqrt(2) / 2)
    0.7071067811865476
    """
    prefix = f"{where}: " if where else ""
    if not isinstance(expr, sp.Basic):
        raise ExpressionError(f"{prefix}not an expression: {expr!r}")
    if expr.free_symbols:
        names = ", ".join(sorted(str(s) for s in expr.free_symbols))
        raise ExpressionError(f"{prefix}not a constant (it uses {names}): {expr}")
    try:
        value = _float_value(expr)
    except OverflowError:
        raise ExpressionError(f"{prefix}number too large: {_shorten(str(expr))}") from None
    except (ValueError, ZeroDivisionError):
        raise ExpressionError(f"{prefix}not a real number: {_shorten(str(expr))}") from None
    except TypeError:
        raise ExpressionError(
            f"{prefix}cannot evaluate {_shorten(str(expr))} as a real number") from None
    if isinstance(value, complex) or not math.isfinite(value):
        raise ExpressionError(f"{prefix}not a finite real number: {_shorten(str(expr))}")
    return float(value)
