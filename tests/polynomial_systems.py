"""Test helpers: polynomial systems with known structure, coordinate changes, and
plain-sympy re-derivations (independent of ``nilpotent.core``'s jet arithmetic).

Bracket convention ``[X, Y] = DY·X − DX·Y``.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import sympy as sp
from hypothesis import strategies as st

from nilpotent.core.model.system import ControlSystem
from nilpotent.models import get_model


def witt_dimension(m: int, k: int) -> int:
    """Dimension of the length-``k`` part of the free Lie algebra on ``m`` generators (Witt)."""
    return sum(sp.mobius(d) * m ** (k // d) for d in sp.divisors(k)) // k


def free_nilpotent(m: int, r: int) -> ControlSystem:
    """A polynomial system whose Lie algebra is free nilpotent of step ``r`` on ``m`` generators.

    ``(m, r)`` in ``(2, 1..4)`` and ``(3, 2)``.  For ``m = 2``:
    ``X1 = ∂1``, ``X2 = ∂2 + Σ x1^a x2^b ∂_{(a,b)}`` over the monomials with
    ``a ≥ 1`` and ``1 ≤ a + b ≤ r − 1`` (one coordinate per monomial):
    ``1 + 2 + ... `` new directions per length, the free dimensions 2, 3, 5, 8.
    For ``(3, 2)`` the classical model on ``R^6`` with ``[X_i, X_j] = ∂_{ij}``.
    """
    if m == 3 and r == 2:
        x1, x2, x3, a, b, c = sp.symbols("x1 x2 x3 x12 x13 x23")
        h = sp.Rational(1, 2)
        return ControlSystem(
            "free-3-2",
            (x1, x2, x3, a, b, c),
            (
                (1, 0, 0, -h * x2, -h * x3, 0),
                (0, 1, 0, h * x1, 0, -h * x3),
                (0, 0, 1, 0, h * x1, h * x2),
            ),
        )
    assert m == 2 and 1 <= r <= 4
    monos = [(a, d - a) for d in range(1, r) for a in range(d, 0, -1)]
    x1, x2 = sp.symbols("x1 x2")
    extra = sp.symbols(" ".join(f"x{a}{b}" for a, b in monos)) if monos else ()
    if not isinstance(extra, tuple):
        extra = (extra,)
    coords = (x1, x2, *extra)
    f1 = [1, 0] + [0] * len(monos)
    f2 = [0, 1] + [x1**a * x2**b for a, b in monos]
    return ControlSystem(f"free-2-{r}", coords, (tuple(f1), tuple(f2)))


def change_coordinates(sys: ControlSystem, shifts: Sequence[sp.Expr]) -> ControlSystem:
    """The system in the coordinates ``u_j = x_j + shifts[j](x_1..x_{j−1})`` (triangular).

    The fields are transformed with the Jacobian, ``[X]_u = (Du/Dx · X)(x(u))``;
    the inverse ``x(u)`` is computed by back substitution (exact polynomials).
    The new coordinates reuse the names of the old ones.
    """
    xs = sys.coordinates
    us = tuple(sp.Symbol(f"_u{k}") for k in range(sys.n))
    shifts = [sp.S(s) for s in shifts]
    phi = [x + s for x, s in zip(xs, shifts, strict=True)]
    for j, s in enumerate(shifts):
        assert not (s.free_symbols & set(xs[j:])), "shift must depend on earlier coordinates"
    inv: dict[sp.Symbol, sp.Expr] = {}
    for j, x in enumerate(xs):
        inv[x] = sp.expand(us[j] - shifts[j].xreplace(inv))
    jac = sp.Matrix(phi).jacobian(xs)
    fields = []
    for f in sys.specialized_fields:
        v = jac * sp.Matrix(f)
        fields.append(
            tuple(sp.expand(e.xreplace(inv)).xreplace(dict(zip(us, xs, strict=True))) for e in v)
        )
    return ControlSystem(sys.name + "-changed", xs, tuple(fields))


def sympy_bracket(X: Sequence[sp.Expr], Y: Sequence[sp.Expr], coords: Sequence[sp.Symbol]) -> tuple:
    """``[X, Y] = DY·X − DX·Y`` with plain sympy."""
    JX = sp.Matrix(X).jacobian(coords)
    JY = sp.Matrix(Y).jacobian(coords)
    return tuple(sp.expand(e) for e in JY * sp.Matrix(X) - JX * sp.Matrix(Y))


def lie_derivative(X: Sequence[sp.Expr], f: sp.Expr, coords: Sequence[sp.Symbol]) -> sp.Expr:
    return sp.expand(sum(c * sp.diff(f, x) for c, x in zip(X, coords, strict=True)))


def function_order(
    fields: Sequence[Sequence[sp.Expr]],
    coords: Sequence[sp.Symbol],
    f: sp.Expr,
    point: Sequence[sp.Expr],
    max_order: int,
) -> int | None:
    """Non-holonomic order of ``f`` at ``point`` by plain sympy Lie-derivative chains."""
    at = dict(zip(coords, point, strict=True))
    level = [f]
    if sp.simplify(f.xreplace(at)) != 0:
        return 0
    for s in range(1, max_order + 1):
        level = [lie_derivative(X, g, coords) for g in level for X in fields]
        level = [g for g in level if g != 0]
        if any(sp.simplify(g.xreplace(at)) != 0 for g in level):
            return s
    return None


def right_normed_brackets(
    fields: Sequence[Sequence[sp.Expr]], coords: Sequence[sp.Symbol], length: int
) -> list:
    """All right-normed brackets ``[X_{i1},[X_{i2},…X_{ik}]]`` of the given length (plain sympy)."""
    out = [tuple(f) for f in fields]
    for _ in range(length - 1):
        out = [sympy_bracket(X, b, coords) for X in fields for b in out]
        out = [b for b in out if any(e != 0 for e in b)]
    return out


def span_dimension(vector_fields: Sequence[Sequence[sp.Expr]], coords: Sequence[sp.Symbol]) -> int:
    """Dimension over R of the span of polynomial vector fields (as coefficient vectors)."""
    rows = []
    keys: dict = {}
    polys = []
    for v in vector_fields:
        entry = {}
        for j, e in enumerate(v):
            if e == 0:
                continue
            for mono, c in sp.Poly(e, *coords).terms():
                entry[(j, mono)] = c
                keys.setdefault((j, mono), len(keys))
        polys.append(entry)
    for entry in polys:
        row = [0] * len(keys)
        for k, c in entry.items():
            row[keys[k]] = c
        rows.append(row)
    if not rows or not keys:
        return 0
    return sp.Matrix(rows).rank()


def growth_vector_at(
    fields: Sequence[Sequence[sp.Expr]], coords: Sequence[sp.Symbol], point, max_length: int
) -> tuple[int, ...]:
    """Growth vector by plain sympy brackets evaluated at ``point``."""
    at = dict(zip(coords, point, strict=True))
    vals = []
    growth = []
    for k in range(1, max_length + 1):
        vals += [
            [sp.nsimplify(sp.simplify(e.xreplace(at))) for e in b]
            for b in right_normed_brackets(fields, coords, k)
        ]
        growth.append(sp.Matrix(vals).rank() if vals else 0)
        if growth[-1] == len(coords):
            break
    while len(growth) > 1 and growth[-1] == growth[-2]:
        growth.pop()
    return tuple(growth)


def weighted_parts(
    expr: sp.Expr, coords: Sequence[sp.Symbol], weights: Sequence[int]
) -> dict[int, sp.Expr]:
    """Split a polynomial into its weighted-homogeneous parts (plain sympy)."""
    out: dict[int, sp.Expr] = {}
    if expr == 0:
        return out
    for mono, c in sp.Poly(sp.expand(expr), *coords).terms():
        d = sum(a * w for a, w in zip(mono, weights, strict=True))
        out[d] = out.get(d, 0) + c * sp.Mul(*[x**a for x, a in zip(coords, mono, strict=True)])
    return out


def monomials(variables: Sequence[sp.Symbol], degrees: Sequence[int]):
    """All monomials of the given total degrees in ``variables``."""
    for d in degrees:
        for combo in itertools.combinations_with_replacement(variables, d):
            yield sp.Mul(*combo)


# --- random triangular coordinate changes (hypothesis) ---------------------------------

BASES = ["heisenberg", "engel", "cartan", "free-2-3", "martinet"]


def base_system(name: str) -> ControlSystem:
    return free_nilpotent(2, 3) if name == "free-2-3" else get_model(name)


@st.composite
def changed_systems(draw):
    """A polynomial system pushed through a random triangular polynomial change of degree 2–3."""
    name = draw(st.sampled_from(BASES))
    sys = base_system(name)
    x = sys.coordinates
    shifts = [sp.Integer(0)]
    for j in range(1, sys.n):
        earlier = x[:j]
        terms = draw(
            st.lists(
                st.tuples(
                    st.integers(-2, 2).filter(bool),
                    st.lists(st.sampled_from(range(j)), min_size=2, max_size=3),
                ),
                max_size=2,
            )
        )
        shifts.append(sp.Add(*[c * sp.Mul(*[earlier[k] for k in ks]) for c, ks in terms]))
    return name, change_coordinates(sys, shifts)
