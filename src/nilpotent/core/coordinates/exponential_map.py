r"""The exponential map of an adapted frame, on weighted jets.

The two exponential constructions of privileged coordinates (A. Bellaïche, *The
tangent space in sub-Riemannian geometry*, 1996, §5; F. Jean, *Control of
Nonholonomic Systems*, 2014, §2.2.2) give $x$ as a function of the new coordinates:

- 2nd kind: $E(s) = \exp(s_nY_n)\circ\cdots\circ\exp(s_1Y_1)(p)$
  (:func:`exponential_map`);
- 1st kind: $E_1(y) = \exp(\sum_j y_jY_j)(p)$ (:func:`first_kind_map`);

each computed by Picard iteration on weighted jets truncated at the weighted degree
needed, then inverted as a series (:func:`from_exponential_map`).  The builders of
:mod:`nilpotent.core.coordinates.privileged` call these; ``ctx`` is that module's context (the
system, the point, the filtration, the weights and the linear adapted map ``A``).
"""

from __future__ import annotations

import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING

import symengine as se

from nilpotent.core.coordinates.jets import Poly, to_symengine, weighted_degree, weighted_jets
from nilpotent.core.lie.brackets import SeField, Word, word_field_symengine
from nilpotent.errors import ComputationLimitError

if TYPE_CHECKING:
    from nilpotent.core.coordinates.privileged import Built, FrameContext

__all__ = [
    "SERIES_TIME_BUDGET",
    "check_budget",
    "exponential_grading",
    "exponential_map",
    "first_kind_map",
    "from_exponential_map",
    "series_budget",
]

SERIES_TIME_BUDGET = 60.0
"""CPU seconds the exponential methods may spend on exact coordinates before they refuse.

CPU time of this process, so that a loaded machine does not trip it.
The same budget as the analysis (``ANALYSIS_TIME_BUDGET``): at an exact point with
irrational algebraic values ($\\alpha = \\pi/3$) the series inverse carries
coefficients in a number field and can run for many minutes; past the budget a
:class:`~nilpotent.errors.ComputationLimitError` says so and what to do instead.
"""


@contextmanager
def series_budget(ctx: FrameContext, seconds: float | None = None) -> Iterator[None]:
    """Run a construction on ``ctx`` under a time budget (default :data:`SERIES_TIME_BUDGET`)."""
    old = ctx.__dict__.get("deadline")
    budget = SERIES_TIME_BUDGET if seconds is None else seconds
    ctx.__dict__["deadline"] = (time.process_time() + budget, budget)
    try:
        yield
    finally:
        ctx.__dict__["deadline"] = old


def check_budget(ctx: FrameContext) -> None:
    """Raise :class:`~nilpotent.errors.ComputationLimitError` past the budget of ``ctx``.

    Raises
    ------
    ComputationLimitError
        When a :func:`series_budget` is running on ``ctx`` and its time is spent.
    """
    deadline = ctx.__dict__.get("deadline")
    if deadline is not None and time.process_time() > deadline[0]:
        raise ComputationLimitError(
            f"exponential coordinates of {ctx.sys.name!r} in exact arithmetic at the point "
            f"exceed the time budget of {deadline[1]:g} s (SERIES_TIME_BUDGET in "
            "nilpotent.core.coordinates.exponential_map): their series inverse swells with "
            "the exact irrational values there; use method 'algebraic' (the default), or give the "
            "point as decimals (floating-point coefficients, seconds)"
        )


def integrate(poly: Poly, k: int) -> Poly:
    terms = {}
    for m, c in poly.terms.items():
        mm = list(m)
        mm[k] += 1
        terms[tuple(mm)] = c / se.Integer(mm[k])
    return Poly(poly.nvars, terms)


def exponential_map(ctx: FrameContext, degree: int) -> list[Poly]:
    r"""$E(s) = \exp(s_nY_n)\circ\cdots\circ\exp(s_1Y_1)(p)$ in $x$, to weighted degree ``degree``.

    Each flow by Picard iteration $x \leftarrow E_{l-1} + \int_0^{s_l} Y_l(x)$ on
    weighted jets (the integral raises the weighted degree by $w_l$, so a fixed
    number of iterations is exact to ``degree``); the jets of $Y_l$ along an
    iterate by :func:`frame_jets_along`.
    """
    n, w = ctx.n, ctx.weights
    key = ("exponential_map", degree)
    cache = ctx.__dict__.setdefault("cache", {})
    if key in cache:
        return cache[key]
    E = [Poly.constant(n, to_symengine(v)) for v in ctx.p]
    for l, wl in enumerate(w):
        if wl > degree:
            continue
        base = E
        cur = base
        # The error of the k-th iterate has weighted order >= (k + 1) w_l (the integral
        # adds w_l), so ceil((degree + 1) / w_l) - 1 iterations are exact to ``degree``.
        for _ in range(-(-(degree + 1) // wl) - 1):
            check_budget(ctx)
            vals = frame_jets_along(ctx, l, cur, degree - wl)
            cur = [b + integrate(v, l) for b, v in zip(base, vals, strict=True)]
        E = cur
    cache[key] = E
    return E


def frame_field(ctx: FrameContext, word: Word) -> SeField:
    r"""The field of a frame word in symengine: expanded, or else the bracket of its halves.

    The expanded field (:func:`~nilpotent.core.lie.brackets.word_field_symengine`, cached on
    the system) where its size is within
    :data:`~nilpotent.core.lie.brackets.EXPANSION_TERMS_BUDGET`; past it, $[u, v] =
    Dv\cdot u - Du\cdot v$ written with the fields of $u$ and $v$ and left unexpanded
    (only low-order jets of the longest words are ever taken, and the series of the
    unexpanded form never builds the expansion).  Cached on ``ctx``.
    """
    cache = ctx.__dict__.setdefault("cache", {})
    key = ("frame_field", word)
    if key in cache:
        return cache[key]
    try:
        field = word_field_symengine(ctx.sys, word)
    except ComputationLimitError:
        if isinstance(word, int):
            raise
        u, v = frame_field(ctx, word[0]), frame_field(ctx, word[1])
        field = tuple(
            se.Add(
                *[uk * vj.diff(x) for uk, x in zip(u, ctx.xsyms, strict=True) if uk != 0],
                *[-vk * uj.diff(x) for vk, x in zip(v, ctx.xsyms, strict=True) if vk != 0],
            )
            for uj, vj in zip(u, v, strict=True)
        )
    cache[key] = field
    return field


def frame_jets_along(
    ctx: FrameContext,
    l: int,
    cur: Sequence[Poly],
    degree: int,
    weights: Sequence[int] | None = None,
) -> list[Poly]:
    r"""Weighted jets of $Y_l(\varphi)$ to degree ``degree`` along the map $x = \varphi$ (``cur``).

    ``cur`` are polynomials in variables of ``weights`` (default: the weights at
    $p$), starting at $p$.  Two steps instead of one series of $Y_l\circ\varphi$:
    the Taylor jet of $Y_l(p + d)$ in $d = x - p$, where $d_k$ has the weight
    $\nu_k$ = the least weighted degree of a term of $\varphi_k - p_k$ (capped at
    ``degree`` + 1), truncated at $\nu$-degree ``degree`` (a monomial $d^\beta$ with
    $\nu(\beta) >$ ``degree`` composes to terms of degree $>$ ``degree`` only; the
    coordinates with $\nu_k >$ ``degree`` are set to $p_k$ before the series); then
    that polynomial composed with $d = \varphi - p$, truncated.  The jet in $d$ is
    computed once per weights $\nu$ and reused by every Picard iterate; degree 0 is
    the frame's value at $p$ (from the filtration: the field is not needed).  With
    floats (``ctx.numeric``), or a $d_k$ with a term of weighted degree 0, one
    series of the composite (the direct method).
    """
    n = ctx.n
    w = ctx.weights if weights is None else weights
    nv = cur[0].nvars
    d = [c - Poly.constant(nv, to_symengine(p)) for c, p in zip(cur, ctx.p, strict=True)]
    nu = tuple(min([weighted_degree(m, w) for m in dk.terms] + [degree + 1]) for dk in d)
    if ctx.numeric or 0 in nu:
        # floats: one series along the iterate, as computed before (same rounding); a
        # d_k with a term of degree 0 (not from these builders) has no truncated jet in d
        Y = frame_field(ctx, ctx.filtration.frame[l])
        return weighted_jets(Y, ctx.xsyms, cur, w, degree, ctx.numeric)
    cache = ctx.__dict__.setdefault("cache", {})
    if degree == 0:
        key0 = ("frame_value", l, nv)
        if key0 not in cache:
            values = [to_symengine(v) for v in ctx.filtration.frame_values[l]]
            cache[key0] = [Poly.constant(nv, v) for v in values]
        return cache[key0]
    key = ("frame_jet", l, nu, degree)
    jet = cache.get(key)
    if jet is None:
        Y = frame_field(ctx, ctx.filtration.frame[l])
        # x_k = p_k + d_k; where d_k cannot reach the degree (nu_k > degree), x_k = p_k:
        # the expression collapses before its series (cos(0) = 1, ...)
        shifted = [
            Poly.constant(n, to_symengine(p)) + Poly.variable(n, k)
            if nu[k] <= degree
            else Poly.constant(n, to_symengine(p))
            for k, p in enumerate(ctx.p)
        ]
        jet = weighted_jets(Y, ctx.xsyms, shifted, nu, degree, ctx.numeric)
        cache[key] = jet
    return [c.compose(d, w, degree) for c in jet]


def exponential_grading(weights: Sequence[int], chi: Sequence[Poly]) -> list[int]:
    r"""Orders $\omega_k$ of the linear adapted $z_k$: the weighted orders of $z_k = \chi_k(y)$."""
    return [min(weighted_degree(m, weights) for m in c.terms) for c in chi]


def first_kind_map(ctx: FrameContext, degree: int) -> list[Poly]:
    r"""$E_1(y) = \exp(\sum_j y_j Y_j)(p)$ in $x$, to weighted degree ``degree``.

    The flow $x(\tau)$ of $Z = \sum_j y_j Y_j$ from $p$, by Picard iteration
    $x \leftarrow p + \int_0^\tau Z(x)\,d\sigma$ on jets in $(y, \tau)$ ($\tau$ of
    weight 0): every term of $Z$ carries some $y_j$ (weight $\ge 1$), so each
    iteration is exact to one more degree; then $\tau = 1$.
    """
    n, w = ctx.n, ctx.weights
    nv = n + 1
    wt = [*w, 0]
    point = [Poly.constant(nv, to_symengine(v)) for v in ctx.p]
    ys = [Poly.variable(nv, j) for j in range(n)]
    cur = point
    for it in range(1, degree + 1):
        # iterate ``it`` is exact to weighted degree ``it``: jets to ``it - 1`` suffice
        top = min(degree, it)
        check_budget(ctx)
        jets = [frame_jets_along(ctx, j, cur, top - 1, wt) for j in range(n)]
        new = []
        for k in range(n):
            acc = Poly(nv)
            for j in range(n):
                comp = jets[j][k]
                if comp.terms:
                    acc = acc + ys[j].mul(comp, wt, top)
            new.append(point[k] + integrate(acc, n))
        cur = new
    out = []
    for poly in cur:
        terms: dict = {}
        for m, c in poly.terms.items():
            key = (*m[:n],)
            terms[key] = terms[key] + c if key in terms else c
        out.append(Poly(n, terms))
    return out


def from_exponential_map(ctx: FrameContext, E: Sequence[Poly]) -> Built:
    """Coordinates defined by $x = E(y)$ (weighted degree <= r); forward: the series inverse."""
    n, w = ctx.n, ctx.weights
    r = max(w)
    zE = ctx.apply_A([e - Poly.constant(n, to_symengine(p)) for e, p in zip(E, ctx.p, strict=True)])
    # Truncation grading: z_k counts its order ω_k, the weighted order of χ_k(y) in the
    # privileged y (computed); a dropped monomial z^β has order >= Σ β_k ω_k.  y_m is kept
    # to ω-degree r + w_m: then the composites G(ψ(z)) used by the push-forward of the
    # approximation are right to order r (a ∂/∂y_m costs at most w_m).
    omega = exponential_grading(w, zE)
    top = 2 * r
    nonlinear = [zE[j] - Poly.variable(n, j) for j in range(n)]  # χ(y) − y
    y = [Poly.variable(n, j) for j in range(n)]
    # Fixed point y = z - N(y), N of omega-order >= 2: iterate k is right to omega-degree
    # k + 1 at least (each substitution gains one degree), so it is truncated there.
    for k in range(1, top + 1):
        deg = min(top, k + 1)
        check_budget(ctx)
        y = [
            (Poly.variable(n, j) - nonlinear[j].compose(y, omega, deg)).truncate(omega, deg)
            for j in range(n)
        ]
    forward = tuple(y[j].truncate(omega, r + w[j]) for j in range(n))
    return forward, tuple(zE), False, r, False, r
