"""Points and parameter assignments written by users: ``NAME=VALUE,NAME=VALUE``.

A point (``--at``, ``--from``, ``--to``) names some coordinates of a system;
the unnamed ones are 0.  Values go through the expression grammar
(:func:`nilpotent.core.model.expressions.parse_expression`) with no names but ``pi``
and ``E``, so they are constants: exact where written exactly (``pi/3``,
``1/2``, ``sqrt(2)``); decimals are read as the exact rationals they denote
(``0.7`` is ``7/10``, ``1e-300`` is ``10**-300``).  They must be finite real
numbers; a point's coordinates are of magnitude at most :data:`MAX_MAGNITUDE`
(``1e6``; a bigger coordinate is refused with a clear error: no numerical
computation of the tool is meaningful at that scale, and doubles lose the small
terms).  Parameters (``--param``) may be any finite double.
Commas inside parentheses (``atan2(1, 2)``) belong to the value.  A name may
appear once per option (``x=1,x=2`` is refused, not "the last one wins").

:func:`check_magnitude` is the one check of every number given at the boundary
(command-line options, world files): finite, and within the documented range.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence

import sympy as sp

from nilpotent.core.model.expressions import (
    exact_decimals,
    format_expression,
    parse_expression,
    real_value,
)
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ExpressionError, ModelError, NilpotentError, OptionError, PointError

__all__ = [
    "MAX_MAGNITUDE",
    "check_magnitude",
    "format_point",
    "parse_assignments",
    "parse_param_assignments",
    "parse_point",
]

#: Largest magnitude of a number given by a user: a coordinate of a point, a parameter,
#: a length, a time, a bound of a world (model units, radians, seconds).
MAX_MAGNITUDE = 1e6


def check_magnitude(
    value: float,
    where: str,
    *,
    low: float = -MAX_MAGNITUDE,
    high: float = MAX_MAGNITUDE,
    error: type[NilpotentError] = OptionError,
) -> float:
    """``value`` as a float if it is finite and in ``[low, high]``, else ``error``.

    Parameters
    ----------
    value : float
        The number (anything :class:`float` takes; ``int`` of any size included).
    where : str
        What the number is (an option, a file's key), put at the start of the message.
    low, high : float
        The closed range allowed (default ``±MAX_MAGNITUDE``).
    error : type of NilpotentError
        The error raised (default :class:`~nilpotent.errors.OptionError`).

    Returns
    -------
    float
        The value.

    Raises
    ------
    NilpotentError
        ``error``: not finite, beyond the range of a double, or outside ``[low, high]``.

    Examples
    --------
    >>> check_magnitude(2.5, "--tol")
    2.5
    """
    try:
        number = float(value)
    except OverflowError:
        raise error(f"{where}: the number is beyond the range of a double (allowed: "
                    f"{low:g} to {high:g})") from None
    if not math.isfinite(number):
        raise error(f"{where}: expected a finite number, got {number}")
    if not low <= number <= high:
        raise error(f"{where}: {number!r} is outside the allowed range [{low:g}, {high:g}]")
    return number


def _split_top_level(text: str) -> list[str]:
    """Split at the commas that are outside parentheses."""
    parts, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    parts.append(text[start:])
    return parts


def parse_assignments(
    text: str, where: str, error: type[NilpotentError], example: str,
    limit: float | None = MAX_MAGNITUDE,
) -> list[tuple[str, sp.Expr]]:
    """Parse ``NAME=VALUE,...`` into (name, constant value) pairs, in order.

    The one parser of every ``NAME=VALUE,...`` option (points, ``--param``,
    ``--mismatch``): each value a finite real constant of the grammar of
    magnitude at most ``limit`` (:data:`MAX_MAGNITUDE`; ``None``: any double, as
    for parameters, whose scale the exact commands handle), each name once.

    Parameters
    ----------
    text : str
        The option's value.
    where : str
        The option's name, put at the start of messages.
    error : type of NilpotentError
        The error raised for a malformed text.
    example : str
        A well-formed example, shown in messages.
    limit : float or None
        The largest magnitude allowed (``None``: any finite double).

    Returns
    -------
    list of (str, sympy.Expr)
        The names and their exact values, in order.

    Raises
    ------
    NilpotentError
        ``error``: an empty text or item, an item without ``=``, an empty name or value, a
        name given twice, a value that is not a finite real constant or is too large.
    """
    if not isinstance(text, str) or not text.strip():
        raise error(f"{where}: empty; write NAME=VALUE pairs separated by commas, e.g. {example}")
    out: list[tuple[str, sp.Expr]] = []
    seen: set[str] = set()
    for item in _split_top_level(text):
        if not item.strip():
            raise error(f"{where}: empty item in {text!r} (two commas, or a trailing comma?)")
        name, eq, value = item.partition("=")
        name, value = name.strip(), value.strip()
        if not eq:
            raise error(f"{where}: {item.strip()!r} in {text!r} has no '='; write NAME=VALUE, "
                        f"e.g. {example}")
        if not name:
            raise error(f"{where}: missing name before '=' in {item.strip()!r} of {text!r}")
        if not value:
            raise error(f"{where}: empty value for {name!r} in {text!r}")
        if name in seen:
            raise error(f"{where}: {name!r} given twice in {text!r}")
        seen.add(name)
        place = f"{where} {name}"
        try:
            expr = parse_expression(value, {}, where=place)
            number = real_value(expr, where=place)  # finite, within a double
            if limit is not None:
                check_magnitude(number, place, low=-limit, high=limit, error=error)
        except ExpressionError as exc:
            raise error(str(exc)) from None
        out.append((name, _exact_decimal_value(value, expr)))
    return out


def _exact_decimal_value(text: str, expr: sp.Expr) -> sp.Expr:
    """``expr`` with its decimals read as the rationals they denote.

    A value that is one decimal literal is read from its text (every digit
    counts: ``0.1000000000000000000001`` is not rounded to a double); decimals
    inside a larger expression are read as the shortest decimal of their double.
    """
    if not expr.atoms(sp.Float):
        return expr
    literal = text.strip()
    if _DECIMAL.fullmatch(literal):
        return sp.Rational(literal)
    return exact_decimals(expr)


_DECIMAL = re.compile(r"[+-]?(\d{1,400}\.?\d{0,400}|\.\d{1,400})([eE][+-]?\d{1,3})?")


def parse_point(text: str, sys: ControlSystem, *, option: str = "--at") -> tuple[sp.Expr, ...]:
    """Parse ``NAME=VALUE,...`` into a point of ``sys`` (unnamed coordinates are 0).

    Parameters
    ----------
    text:
        The option's value, e.g. ``"theta=pi/4,x=1/2"``.
    sys:
        The system whose coordinates are named.
    option:
        The option's name, put at the start of error messages.

    Returns
    -------
    tuple of sympy.Expr
        The point, aligned with ``sys.coordinates``; exact where the text is exact.

    Raises
    ------
    PointError
        Empty text, an item without ``=``, an empty value, an unknown or repeated
        coordinate name, or a value that is not a finite real constant of the grammar.

    Examples
    --------
    >>> import sympy as sp
    >>> x, y, th = sp.symbols("x y theta")
    >>> s = ControlSystem("unicycle", (x, y, th), ((sp.cos(th), sp.sin(th), 0), (0, 0, 1)))
    >>> parse_point("theta=pi/3, x=1/2", s)
    (1/2, 0, pi/3)
    """
    names = sys.coordinate_names
    example = f"{option} {names[0]}=1/2" + (f",{names[-1]}=pi/4" if len(names) > 1 else "")
    values: dict[str, sp.Expr] = dict.fromkeys(names, sp.Integer(0))
    for name, expr in parse_assignments(text, option, PointError, example):
        if name not in values:
            raise PointError(
                f"{option}: unknown coordinate {name!r} in {text!r} "
                f"(coordinates of {sys.name}: {', '.join(names)})"
            )
        values[name] = expr
    return tuple(values[n] for n in names)


def parse_param_assignments(
    items: Sequence[str], *, option: str = "--param"
) -> dict[str, sp.Expr]:
    """Parse repeated ``NAME=VALUE`` options (each may hold several, comma-separated).

    Values are finite real constants of the grammar. Whether the names are
    parameters of a model is checked where the model is known
    (:meth:`ControlSystem.with_parameters`).

    Raises
    ------
    ModelError
        A malformed item, an empty value, a name that is not an identifier, a
        name given twice, or a value that is not a finite real constant.

    Examples
    --------
    >>> parse_param_assignments(["r=1/2", "l=sqrt(2)"])
    {'r': 1/2, 'l': sqrt(2)}
    """
    if isinstance(items, str):
        items = [items]
    out: dict[str, sp.Expr] = {}
    for item in items:
        # parameters: any finite double (exact commands are scale-invariant: l = 1e300
        # is a valid trident); the commands that compute in floats check what they use
        for name, expr in parse_assignments(item, option, ModelError, f"{option} r=1/2",
                                            limit=None):
            if not name.isidentifier():
                raise ModelError(f"{option}: {name!r} in {item!r} is not a parameter name")
            if name in out:
                raise ModelError(f"{option}: parameter {name!r} given twice")
            out[name] = expr
    return out


def format_point(sys: ControlSystem, point: Sequence[sp.Basic]) -> dict[str, str]:
    """The JSON ``point`` object: coordinate name → value as grammar text.

    Examples
    --------
    >>> import sympy as sp
    >>> x, y = sp.symbols("x y")
    >>> format_point(ControlSystem("s", (x, y), ((1, 0),)), (sp.sqrt(3) / 2, 0))
    {'x': 'sqrt(3)/2', 'y': '0'}
    """
    point = tuple(point)
    if len(point) != sys.n:
        raise PointError(
            f"a point of {sys.name!r} has {sys.n} coordinates, got {len(point)}"
        )
    return {
        name: format_expression(value)
        for name, value in zip(sys.coordinate_names, point, strict=True)
    }
