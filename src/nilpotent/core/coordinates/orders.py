"""Non-holonomic orders of functions and vector fields at a point (the mathematics page, §3).

* The order of a function $f$ at $p$ is the least $s$ such that some
  $X_{i_1}\\cdots X_{i_s} f\\,(p) \\ne 0$ (0 when $f(p) \\ne 0$, $\\infty$ when every
  such derivative vanishes).
* In privileged coordinates $z$ with weights $w$, a vector field $Z$ has order
  $\\ge \\sigma$ iff each component $Z z_j$ has order $\\ge w_j + \\sigma$; the order
  of a polynomial (or Taylor series) in $z$ is its *weighted* order, the least
  $\\sum_k w_k \\alpha_k$ over its monomials $z^\\alpha$.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import symengine as se
import sympy as sp

from nilpotent.core.coordinates.jets import Poly, ZeroTest, lie_derivative, weighted_degree
from nilpotent.core.decide.spans import NotEvaluable, is_zero
from nilpotent.core.lie.brackets import (
    se_coordinates,
    se_lie_derivative,
    to_symengine,
    word_field_symengine,
)
from nilpotent.core.model.expressions import as_expr
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import OptionError, PointError

Order = int | float
"""An order: a non-negative integer, or ``math.inf``."""

def _is_zero(value: se.Basic) -> bool:
    """Whether an exact number (symengine) is 0, decided by the one rank engine.

    :func:`nilpotent.core.decide.spans.is_zero`: exact for rational and algebraic
    values, a certified ball (relative, at rising precision) proves a nonzero
    value, however small (``exp(-100)``); a value still enclosed around 0 at
    :data:`~nilpotent.core.decide.spans.MAX_PRECISION_BITS` bits without an exact
    proof (``cos(1)**2 + sin(1)**2 - 1``) counts as 0.
    """
    if value == 0:
        return True
    v = as_expr(value)
    if v.is_Rational:
        return False
    if v.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
        raise PointError(f"a derivative is undefined at the point ({v})")
    try:
        verdict = is_zero(value)
    except NotEvaluable as exc:
        raise PointError(f"a derivative cannot be evaluated at the point ({v}: {exc})") from exc
    return True if verdict is None else verdict


def _point_subs(sys: ControlSystem, point: Sequence[object] | None) -> dict:
    coords = se_coordinates(sys)
    if point is None:
        return {x: se.Integer(0) for x in coords}
    if len(point) != sys.n:
        raise PointError(f"a point of {sys.name!r} has {sys.n} coordinates, got {len(point)}")
    return {x: to_symengine(as_expr(v)) for x, v in zip(coords, point, strict=True)}


def function_order(
    sys: ControlSystem, f: sp.Expr, point: Sequence[object] | None = None, max_order: int = 12
) -> Order:
    """Non-holonomic order at ``point`` of the function ``f`` of the coordinates.

    Computed by applying the fields $X_i$ as derivations to ``f`` (symengine,
    expanded), keeping at each length only the distinct non-zero derivatives,
    and evaluating them exactly at the point.

    Parameters
    ----------
    sys:
        The system (parameters are substituted in the fields and in ``f``).
    f:
        A sympy expression in ``sys.coordinates``.
    point:
        The point (default: the origin).
    max_order:
        Derivatives of length up to this are examined.

    Returns
    -------
    int or float
        The order, or ``math.inf`` if every derivative of length $\\le$
        ``max_order`` vanishes at the point (also when they vanish identically).

    Raises
    ------
    OptionError
        If ``max_order`` is negative.
    PointError
        If the point has the wrong number of coordinates, or a derivative is
        undefined there.

    Examples
    --------
    >>> x, y, th = sp.symbols("x y theta")
    >>> uni = ControlSystem("unicycle", (x, y, th), ((sp.cos(th), sp.sin(th), 0), (0, 0, 1)))
    >>> function_order(uni, x, (0, 0, 0)), function_order(uni, y, (0, 0, 0))
    (1, 2)
    >>> function_order(uni, 1 + x, (0, 0, 0))
    0
    """
    if max_order < 0:
        raise OptionError(f"max_order must be >= 0, got {max_order}")
    subs = _point_subs(sys, point)
    params = {se.Symbol(k): to_symengine(v) for k, v in sys.parameters}
    g = se.expand(to_symengine(as_expr(f)))
    if params:
        g = se.expand(g.subs(params))
    coords = se_coordinates(sys)
    fields = [word_field_symengine(sys, i) for i in range(1, sys.m + 1)]
    level: set[se.Basic] = {g} if g != 0 else set()
    for s in range(max_order + 1):
        if not level:
            return math.inf
        for h in level:
            if not _is_zero(se.expand(h.subs(subs)) if h.free_symbols else h):
                return s
        if s == max_order:
            break
        nxt: set[se.Basic] = set()
        for h in level:
            for field in fields:
                d = se_lie_derivative(field, h, coords)
                if d != 0:
                    nxt.add(d)
        level = nxt
    return math.inf


def weighted_order(
    expr: sp.Expr,
    names: Sequence[sp.Expr],
    weights: Sequence[int],
    max_order: int = 30,
) -> Order:
    """Weighted order at 0 of ``expr`` in the variables ``names`` with ``weights``.

    The least $\\sum_k w_k\\alpha_k$ over the monomials $z^\\alpha$ of the Taylor
    series of ``expr`` at 0.  Polynomials are read exactly; other expressions are
    expanded in $t$ after $z_k \\to t^{w_k} z_k$ (symengine series) up to
    ``max_order``; ``math.inf`` if no term of weighted degree $\\le$ ``max_order``
    (and for 0).

    Examples
    --------
    >>> y1, y2, y3 = sp.symbols("y1 y2 y3")
    >>> weighted_order(y1**2 + y3, (y1, y2, y3), (1, 1, 2))
    2
    >>> weighted_order(sp.sin(y1) * y3, (y1, y2, y3), (1, 1, 2))
    3
    """
    if len(names) != len(weights):
        raise OptionError(f"{len(names)} names but {len(weights)} weights")
    e = as_expr(expr)
    if e == 0:
        return math.inf
    if e.is_polynomial(*names):
        poly = sp.Poly(e, *names)
        return min(sum(w * a for w, a in zip(weights, mono, strict=True)) for mono in poly.monoms())
    t = se.Symbol("t_weighted_order")
    scaled = to_symengine(e).subs({to_symengine(x): t**w * to_symengine(x)
                                   for x, w in zip(names, weights, strict=True)})
    series = se.series(scaled, t, 0, max_order + 1)
    series = se.expand(series)
    for k in range(max_order + 1):
        c = series.coeff(t, k)
        if c != 0 and se.expand(c) != 0:
            return k
    return math.inf


def field_order(
    components_in_privileged: Sequence[sp.Expr | sp.Poly],
    weights: Sequence[int],
    names: Sequence[sp.Expr] | None = None,
) -> Order:
    """Non-holonomic order of a vector field given in privileged coordinates.

    With $Z = \\sum_j Z_j(z)\\,\\partial_{z_j}$ in privileged coordinates $z$
    of weights $w$ (the mathematics page, §3): $\\mathrm{ord}(Z) \\ge \\sigma$ iff every
    $Z z_j = Z_j$ has order $\\ge w_j + \\sigma$, so
    $\\mathrm{ord}(Z) = \\min_j (\\mathrm{ord}_w(Z_j) - w_j)$, with $\\mathrm{ord}_w$
    the weighted order (:func:`weighted_order`).  Each $X_i$ has order $\\ge -1$.

    Parameters
    ----------
    components_in_privileged:
        $Z_j$ as sympy expressions in ``names``, or as ``sympy.Poly`` whose
        generators are the privileged coordinates in order.
    weights:
        $w_1, \\dots, w_n$.
    names:
        The privileged coordinates $z_1..z_n$ (needed unless the components are
        ``Poly`` objects).

    Returns
    -------
    int or float
        The order (``math.inf`` for the zero field).

    Examples
    --------
    >>> y1, y2, y3 = sp.symbols("y1 y2 y3")
    >>> field_order((1, 0, -y2 / 2), (1, 1, 2), (y1, y2, y3))   # Heisenberg X1
    -1
    >>> field_order((0, 0, 1), (1, 1, 2), (y1, y2, y3))          # ∂/∂y3
    -2
    """
    n = len(weights)
    if len(components_in_privileged) != n:
        raise OptionError(f"{len(components_in_privileged)} components but {n} weights")
    if names is None:
        polys = [c for c in components_in_privileged if isinstance(c, sp.Poly)]
        if len(polys) != n:
            raise OptionError("field_order needs names unless every component is a sympy Poly")
        names = polys[0].gens
    if len(names) != n:
        raise OptionError(f"{len(names)} names but {n} weights")
    best: Order = math.inf
    for comp, w in zip(components_in_privileged, weights, strict=True):
        expr = comp.as_expr() if isinstance(comp, sp.Poly) else comp
        best = min(best, weighted_order(expr, names, weights) - w)
    return best


# --- orders of polynomial coordinates (used by the certificate of privileged.py) ----


def low_order_terms(
    jets: Sequence[Sequence[Poly]], weights: Sequence[int], zero: ZeroTest
) -> dict[int, int]:
    """For each coordinate j with a term of weighted degree < w_j − 1: that least degree."""
    low: dict[int, int] = {}
    for comps in jets:
        for j, comp in enumerate(comps):
            for mono, c in comp.terms.items():
                d = weighted_degree(mono, weights)
                if d < weights[j] - 1 and not zero(c, comp.magnitude(mono)):
                    low[j] = min(low.get(j, d), d)
    return low


def chain_order_homogeneous(hat: Sequence[Sequence[Poly]], j: int, w: int, zero: ZeroTest) -> bool:
    """Whether some $\\hat X_{i_1}\\cdots\\hat X_{i_w} y_j$ is nonzero (a constant)."""
    n = len(hat[0])
    level: dict[frozenset, Poly] = {}
    f = Poly.variable(n, j)
    level[frozenset(f.terms.items())] = f
    for _ in range(w):
        nxt: dict[frozenset, Poly] = {}
        for g in level.values():
            for X in hat:
                h = lie_derivative(X, g).drop_zeros(zero)
                if h.terms:
                    nxt.setdefault(frozenset(h.terms.items()), h)
        level = nxt
        if not level:
            return False
    return any(not g.is_zero_at((0,) * n, zero) for g in level.values())
