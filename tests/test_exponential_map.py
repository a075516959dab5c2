"""The exponential map of an adapted frame on weighted jets, checked against a second method.

``frame_jets_along`` takes one Taylor jet of each frame field in ``d = x - p`` and
composes it with the Picard iterate; the second method here is the direct one (one
univariate series of ``Y_l(phi(s))`` in ``t`` after ``s_k -> t^{w_k} s_k``, for every
iterate), on random polynomial maps ``phi`` and on the whole exponential map.
"""

from __future__ import annotations

import hypothesis.strategies as st
import pytest
import symengine as se
import sympy as sp
from hypothesis import HealthCheck, given, settings

import nilpotent.core.lie.brackets as brackets
from nilpotent.core.analysis.filtration import analyze
from nilpotent.core.coordinates.exponential_map import (
    exponential_map,
    first_kind_map,
    frame_field,
    frame_jets_along,
    integrate,
)
from nilpotent.core.coordinates.jets import Poly, to_symengine, weighted_degree, weighted_jets
from nilpotent.core.coordinates.privileged import FrameContext, privileged_coordinates
from nilpotent.core.lie.brackets import word_field_symengine
from nilpotent.core.model.system import ControlSystem
from nilpotent.models import get_model

CASES = {
    "car-trailers:3": None,
    "trident-snake": None,
    "car-trailers:2 at theta0=pi/4": {"theta0": sp.pi / 4},
}


def fresh(name: str) -> ControlSystem:
    s = get_model(name).specialized()
    return ControlSystem(s.name, s.coordinates, s.fields, (), s.description)


def context(case: str) -> FrameContext:
    name = case.split(" ")[0]
    sys = fresh(name)
    at = CASES[case]
    point = None
    if at:
        point = [at.get(str(c), 0) for c in sys.coordinates]
    return FrameContext(analyze(sys, point), numeric=False)


def direct_jets(ctx: FrameContext, l: int, cur, degree: int) -> list[Poly]:
    """The second method: one series of the expanded field along ``cur``."""
    Y = word_field_symengine(ctx.sys, ctx.filtration.frame[l])
    return weighted_jets(Y, ctx.xsyms, cur, ctx.weights, degree)


def direct_exponential_map(ctx: FrameContext, degree: int) -> list[Poly]:
    """E(s) by Picard iteration with the direct jets (the construction before issue 13)."""
    w = ctx.weights
    E = [Poly.constant(ctx.n, to_symengine(v)) for v in ctx.p]
    for l, wl in enumerate(w):
        if wl > degree:
            continue
        base = cur = E
        for _ in range(-(-(degree + 1) // wl) - 1):
            vals = direct_jets(ctx, l, cur, degree - wl)
            cur = [b + integrate(v, l) for b, v in zip(base, vals, strict=True)]
        E = cur
    return E


def direct_first_kind_map(ctx: FrameContext, degree: int) -> list[Poly]:
    """E_1(y) by Picard iteration in (y, tau) with one series of all frame fields per iterate."""
    n, w = ctx.n, ctx.weights
    nv, wt = n + 1, [*w, 0]
    point = [Poly.constant(nv, to_symengine(v)) for v in ctx.p]
    flat = [c for word in ctx.filtration.frame for c in word_field_symengine(ctx.sys, word)]
    ys = [Poly.variable(nv, j) for j in range(n)]
    cur = point
    for it in range(1, degree + 1):
        top = min(degree, it)
        jets = weighted_jets(flat, ctx.xsyms, cur, wt, top - 1)
        cur = [
            point[k]
            + integrate(
                sum((ys[j].mul(jets[j * n + k], wt, top) for j in range(n)), Poly(nv)), n
            )
            for k in range(n)
        ]
    out = []
    for poly in cur:
        terms: dict = {}
        for m, c in poly.terms.items():
            terms[m[:n]] = terms[m[:n]] + c if m[:n] in terms else c
        out.append(Poly(n, terms))
    return out


def same(a: list[Poly], b: list[Poly]) -> bool:
    return all(
        (p - q).terms == {} or all(se.expand(c) == 0 for c in (p - q).terms.values())
        for p, q in zip(a, b, strict=True)
    )


@st.composite
def polynomial_maps(draw, ctx: FrameContext, degree: int):
    """x = p + a random polynomial in s without constant term, weighted degree <= degree."""
    n, w = ctx.n, ctx.weights
    monos = [m for m in _monomials(n, w, degree) if any(m)]
    out = []
    for k in range(n):
        chosen = draw(st.lists(st.sampled_from(monos), max_size=4, unique=True))
        terms = {m: se.Rational(draw(st.integers(-3, 3)), draw(st.integers(1, 3))) for m in chosen}
        out.append(Poly(n, terms) + Poly.constant(n, to_symengine(ctx.p[k])))
    return out


def _monomials(n: int, w, degree: int):
    def rec(k, left):
        if k == n:
            yield ()
            return
        for a in range(left // w[k] + 1):
            for rest in rec(k + 1, left - a * w[k]):
                yield (a, *rest)

    return list(rec(0, degree))


@pytest.mark.parametrize("case", list(CASES))
@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_frame_jets_along_equal_the_direct_series(case, data):
    ctx = context(case)
    top = max(ctx.weights)
    l = data.draw(st.integers(0, ctx.n - 1), label="frame index")
    degree = data.draw(st.integers(0, top), label="degree")
    cur = data.draw(polynomial_maps(ctx, top), label="map")
    got = frame_jets_along(ctx, l, cur, degree)
    assert same(got, direct_jets(ctx, l, cur, degree))
    assert all(weighted_degree(m, ctx.weights) <= degree for p in got for m in p.terms)


@pytest.mark.parametrize("case", list(CASES))
def test_exponential_map_equals_the_direct_construction(case):
    ctx = context(case)
    D = max(ctx.weights)
    assert same(exponential_map(ctx, D), direct_exponential_map(ctx, D))
    assert same(exponential_map(ctx, D - 1), direct_exponential_map(ctx, D - 1))


@pytest.mark.parametrize("case", list(CASES))
def test_first_kind_map_equals_the_direct_construction(case):
    ctx = context(case)
    D = max(ctx.weights)
    assert same(first_kind_map(ctx, D), direct_first_kind_map(ctx, D))


def test_frame_fields_past_the_expansion_budget_give_the_same_coordinates(monkeypatch):
    """Words whose expansion is refused are used unexpanded: same coordinates."""
    reference = privileged_coordinates(fresh("car-trailers:4"), method="algebraic")
    sys = fresh("car-trailers:4")
    f = analyze(sys)
    # the fields the analysis expanded, if any
    cache = brackets._MEMO.get(sys, dict).get(brackets._CACHE_KEY, {})
    for word in list(cache):
        if not isinstance(word, int):
            del cache[word]
    monkeypatch.setattr(brackets, "EXPANSION_TERMS_BUDGET", 3)
    with pytest.raises(brackets.ComputationLimitError):
        word_field_symengine(sys, f.frame[-1])
    ctx = FrameContext(f, numeric=False)
    assert not isinstance(frame_field(ctx, f.frame[-1])[4], se.Integer)
    coords = privileged_coordinates(sys, method="algebraic", filtration=f)
    assert coords.forward == reference.forward and coords.inverse == reference.inverse
    assert coords.orders == coords.weights
