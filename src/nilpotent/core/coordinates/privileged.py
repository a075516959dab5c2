r"""Privileged coordinates at a point, with the certificate of their orders.

Coordinates $y$ centred at $p$ are *privileged* when the non-holonomic order
of each $y_j$ at $p$ equals the weight $w_j$ (the mathematics page, §3–4).  All methods
start from the **linear adapted coordinates** $z = A(x - p)$, $A = B^{-1}$,
where the columns of $B$ are the values $Y_1(p), \dots, Y_n(p)$ of the adapted
frame of :func:`nilpotent.core.analysis.filtration.analyze`, and describe the
coordinates by two polynomial maps: $y = \psi(z)$ (``forward``) and
$z = \chi(y)$ (``inverse``); then $x = p + B\chi(y)$.

Methods (registry :data:`METHODS`)
    ``"linear"``
        $y = z$.  Privileged when the step is $\le 2$, not in general: the
        certificate decides, and asking for it where it fails raises
        :class:`~nilpotent.errors.NotPrivilegedError` naming the coordinate,
        its computed order and its weight.
    ``"algebraic"``
        Bellaïche's algorithm, any step: for $j = 1..n$,
        $y_j = z_j - \sum_{k=2}^{w_j-1} h_k(z_1..z_{j-1})$ with
        $h_k = \sum_{|\alpha|=k,\ w(\alpha)<w_j}
        Y_1^{\alpha_1}\cdots Y_{j-1}^{\alpha_{j-1}}(z_j - \sum_{q<k} h_q)(p)\,z^\alpha/\alpha!$.
        The derivatives are read off one Taylor expansion:
        $\sum_\alpha Y^\alpha g(p)\,s^\alpha/\alpha! = g(E(s))$ where
        $E(s) = \exp(s_{j-1}Y_{j-1})\circ\cdots\circ\exp(s_1 Y_1)(p)$ (the
        operators act right to left, the flows are composed left to right), and
        only the terms of weighted degree $\le w_j - 1$ of $E$ are ever
        computed.  The change is triangular polynomial: its inverse is exact.
    ``"exponential"``
        Coordinates of the 2nd kind: $x = E(y) = \exp(y_nY_n)\circ\cdots\circ
        \exp(y_1Y_1)(p)$, the flows expanded as weighted Taylor series and
        truncated at weighted degree $r$ (the step), which is all the nilpotent
        approximation and its certificate see.  The forward map $y(x)$ is the
        series inverse, $y_j$ kept to degree $r + w_j$ in $z$ where $z_k$
        counts its order $\omega_k$ (the weighted order of $z_k = \chi_k(y)$),
        so the dropped terms have order $> r + w_j$: enough for the
        certificate (which needs $> w_j + 1$) and for pushing the
        approximation forward (composites $G(y(x))$ right to order $r$).
    ``"exponential-1"``
        Coordinates of the 1st kind, $x = \exp(\sum_j y_j Y_j)(p)$ (the flow of
        $\sum_j y_j Y_j$ for time 1, by Picard iteration on weighted jets),
        truncated at weighted degree $r$ and inverted like ``exponential``.
    ``"auto"``
        The cheapest privileged one: ``linear`` when its certificate passes,
        else ``algebraic``.

Certificate
    :attr:`PrivilegedCoordinates.orders` are *computed*.  From the weighted
    Taylor jets of the fields in $y$: if no component $[X_i]_{y_j}$ has a term of
    weighted degree $< w_j - 1$, every chain $X_{i_1}\cdots X_{i_s}y_j$ with
    $s < w_j$ has positive weighted order and vanishes at $p$, so
    $\mathrm{ord}_p(y_j) \ge w_j$; and a chain of length $w_j$ of the degree
    $-1$ parts that is nonzero at $0$ (computed) gives $= w_j$.  Where the jets
    show a lower term (the coordinates are not privileged), the orders are read
    in Bellaïche's coordinates $y'$, themselves certified first: the order of
    $y_j$ is the weighted order of $y_j(z(y'))$; failing that, it is computed
    directly as the least $s$ with some $X_{i_1}\cdots X_{i_s}y_j(p) \ne 0$
    (ordinary Taylor jets of the fields to degree $s - 1$).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from contextlib import nullcontext
from dataclasses import InitVar, dataclass, field

import sympy as sp

from nilpotent import typeset
from nilpotent.core.analysis.filtration import Filtration, analyze
from nilpotent.core.coordinates.exponential_map import (
    check_budget,
    exponential_map,
    first_kind_map,
    from_exponential_map,
    series_budget,
)
from nilpotent.core.coordinates.frame_context import (
    EXACT_TRIAL_BUDGET,
    SERIES_METHODS,
    FrameContext,
    needs_floats,
    rational_values,
)
from nilpotent.core.coordinates.jets import (
    Poly,
    lie_derivative,
    to_symengine,
    weighted_degree,
    weighted_jets,
)
from nilpotent.core.coordinates.orders import chain_order_homogeneous, low_order_terms
from nilpotent.core.model.expressions import as_expr
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import (
    ComputationLimitError,
    NotBracketGeneratingError,
    NotPrivilegedError,
    OptionError,
)

__all__ = ["METHODS", "PrivilegedCoordinates", "coordinate_names", "privileged_coordinates"]


@dataclass(frozen=True)
class PrivilegedCoordinates:
    r"""Privileged coordinates $y$ at a point $p$, with the computed orders.

    Attributes
    ----------
    method:
        ``"linear"``, ``"algebraic"`` or ``"exponential"``.
    filtration:
        The filtration at $p$ the coordinates are built from (weights, frame).
    names:
        The symbols $y_1..y_n$.
    forward:
        $y_j$ as functions (polynomials) of the model coordinates, $y(p) = 0$.
        Written in powers of $x_k - p_k$.
    inverse:
        $x_k$ as functions (polynomials) of $y$.
    inverse_exact:
        Whether ``inverse`` is exactly the inverse map of ``forward``
        (``linear``, ``algebraic``).
    inverse_order:
        For ``exponential``: the weighted degree at which the exponential map
        $E(y)$ was truncated (``inverse`` is that truncation).
    orders:
        Computed $\mathrm{ord}_p(y_j)$ (equal to the weights: privileged).
    forward_exact:
        Whether ``forward`` is exact (false for ``exponential``, a truncated
        series inverse).
    forward_order:
        For ``exponential``: $y_j$ is kept to degree $w_j +$ ``forward_order``
        in $z = A(x - p)$, $z_k$ counting its order $\omega_k$ (module doc).
    numeric:
        Whether the coefficients are floating-point numbers (15 digits) instead
        of exact numbers (see :func:`privileged_coordinates`).
    frame_matrix:
        $B$, column $k$ is $Y_{k+1}(p)$ (so $\partial_{z_k}|_p = Y_{k+1}(p)$).
    linear_part:
        $A = B^{-1}$ ($z = A(x - p)$, the linear adapted coordinates).
    forward_poly:
        $y_j$ as :class:`~nilpotent.core.coordinates.jets.Poly` in the linear adapted
        coordinates $z$ (the exact form of ``forward``).
    inverse_poly:
        $z_k$ as :class:`~nilpotent.core.coordinates.jets.Poly` in $y$ (the exact form of
        ``inverse``, before $x = p + Bz$).
    known_jets:
        :meth:`field_jets` with ``extra=1`` where already computed (the certificate
        of the orders computes them): kept instead of computed again (not a field).
    """

    method: str
    filtration: Filtration
    names: tuple[sp.Symbol, ...]
    forward: tuple[sp.Expr, ...]
    inverse: tuple[sp.Expr, ...]
    inverse_exact: bool
    inverse_order: int | None
    orders: tuple[int, ...]
    forward_exact: bool = True
    forward_order: int | None = None
    numeric: bool = False
    frame_matrix: sp.ImmutableMatrix = field(default=None, repr=False)  # type: ignore[assignment]
    linear_part: sp.ImmutableMatrix = field(default=None, repr=False)  # type: ignore[assignment]
    forward_poly: tuple[Poly, ...] = field(default=(), repr=False, compare=False)
    """$y_j$ as :class:`Poly` in the linear adapted coordinates $z$."""
    inverse_poly: tuple[Poly, ...] = field(default=(), repr=False, compare=False)
    """$z_k$ as :class:`Poly` in $y$."""
    known_jets: InitVar[tuple[tuple[Poly, ...], ...] | None] = None
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False, hash=False)

    def __post_init__(self, known_jets: tuple[tuple[Poly, ...], ...] | None) -> None:
        if known_jets is not None:
            self._cache[("field_jets", 1)] = known_jets

    # --- views ------------------------------------------------------------------
    @property
    def system(self) -> ControlSystem:
        return self.filtration.system

    @property
    def point(self) -> tuple[sp.Expr, ...]:
        return self.filtration.point

    @property
    def weights(self) -> tuple[int, ...]:
        return self.filtration.weights

    @property
    def n(self) -> int:
        return len(self.names)

    def jacobian(self) -> sp.ImmutableMatrix:
        r"""$\partial y/\partial x$ as a matrix of functions of the model coordinates."""
        return sp.ImmutableMatrix(sp.Matrix(self.forward).jacobian(self.system.coordinates))

    def inverse_jacobian(self) -> sp.ImmutableMatrix:
        r"""$\partial x/\partial y$ as a matrix of functions of $y$."""
        return sp.ImmutableMatrix(sp.Matrix(self.inverse).jacobian(self.names))

    def field_jets(self, extra: int = 1) -> tuple[tuple[Poly, ...], ...]:
        r"""Weighted Taylor jets of the system's fields in these coordinates.

        ``jets[i][j]`` is the $y_{j+1}$-component of $X_{i+1}$, exact up to
        weighted degree $w_{j+1} - 1 +$ ``extra`` (cached).
        """
        key = ("field_jets", extra)
        if key not in self._cache:
            ctx = FrameContext.of(self.filtration, self.numeric)
            degrees = [w - 1 + extra for w in self.weights]
            self._cache[key] = _fields_in(
                ctx, self.forward_poly, self.inverse_poly, self.weights, degrees
            )
        return self._cache[key]

    def to_y(self, x: Sequence[object]) -> tuple[sp.Expr, ...]:
        """Privileged coordinates of a point given in model coordinates."""
        subs = dict(zip(self.system.coordinates, (as_expr(v) for v in x), strict=True))
        return tuple(sp.expand(e.xreplace(subs)) for e in self.forward)

    def to_x(self, y: Sequence[object]) -> tuple[sp.Expr, ...]:
        """Model coordinates of a point given in these coordinates (through ``inverse``)."""
        subs = dict(zip(self.names, (as_expr(v) for v in y), strict=True))
        return tuple(sp.expand(e.xreplace(subs)) for e in self.inverse)

    def __str__(self) -> str:
        lines = [
            f"{self.method} privileged coordinates of {self.system.name} at "
            f"({', '.join(str(v) for v in self.point)}), weights {self.weights}, "
            f"computed orders {self.orders}"
        ]
        for y, e in zip(self.names, self.forward, strict=True):
            lines.append(f"  {y} = {e}")
        tag = "" if self.inverse_exact else f"  (truncated at weighted degree {self.inverse_order})"
        lines.append("inverse:" + tag)
        for x, e in zip(self.system.coordinates, self.inverse, strict=True):
            lines.append(f"  {x} = {e}")
        return "\n".join(lines)

    # --- display (nilpotent.typeset) -------------------------------------------------
    def to_latex(self) -> str:
        """The change of coordinates, weights and computed orders as LaTeX (``align*``)."""
        return typeset.privileged_display(self).latex()

    def _repr_latex_(self) -> str:
        return self.to_latex()

    def _repr_html_(self) -> str:
        return typeset.privileged_display(self).html()


def _identity(n: int) -> tuple[Poly, ...]:
    return tuple(Poly.variable(n, k) for k in range(n))


def _fields_in(
    ctx: FrameContext,
    forward_poly: Sequence[Poly],
    inverse_poly: Sequence[Poly],
    weights: Sequence[int],
    degrees: Sequence[int],
) -> tuple[tuple[Poly, ...], ...]:
    r"""Jets of $[X_i]_y = (\partial y/\partial z)(\chi(y))\,A\,X_i(p + B\chi(y))$.

    Component $j$ exact to weighted degree ``degrees[j]`` (in ``weights``).
    """
    n = ctx.n
    D = max(degrees)
    xargs = ctx.x_of(inverse_poly)
    flat = [c for f in ctx.fields for c in f]
    jets = weighted_jets(flat, ctx.xsyms, xargs, weights, D, ctx.numeric)
    linear = all(
        len(f.terms) == 1 and f.terms.get(tuple(int(i == j) for i in range(n))) == 1
        for j, f in enumerate(forward_poly)
    )
    if not linear:
        jac = []
        for j in range(n):
            row = []
            for l in range(n):
                check_budget(ctx)
                row.append(forward_poly[j].diff(l).compose(inverse_poly, weights, degrees[j]))
            jac.append(row)
    out = []
    for i in range(len(ctx.fields)):
        check_budget(ctx)
        xz = ctx.apply_A(jets[i * n : (i + 1) * n])
        if linear:
            comps = [xz[j].truncate(weights, degrees[j]) for j in range(n)]
        else:
            comps = []
            for j in range(n):
                acc = Poly(n)
                for l in range(n):
                    if jac[j][l].terms and xz[l].terms:
                        acc = acc + jac[j][l].mul(xz[l], weights, degrees[j])
                comps.append(acc)
        out.append(tuple(comps))
    return tuple(out)


# --- orders ---------------------------------------------------------------------------


def _chain_order(
    ctx: FrameContext,
    forward_poly: Sequence[Poly],
    inverse_poly: Sequence[Poly],
    f: Poly,
    max_order: int,
) -> int | None:
    """Least $s \\le$ ``max_order`` with some $X_{i_1}\\cdots X_{i_s} f(p) \\ne 0$ (``None``: none).

    ``f`` is a polynomial in $y$ with $f(p) = 0$; ordinary Taylor jets of the
    fields in $y$ to degree ``max_order − 1``, chains truncated as they go.
    """
    n = ctx.n
    ones = [1] * n
    if max_order < 1:
        return None
    jets = _fields_in(ctx, forward_poly, inverse_poly, ones, [max_order - 1] * n)
    level = {frozenset(f.truncate(ones, max_order).terms.items()): f.truncate(ones, max_order)}
    for s in range(1, max_order + 1):
        nxt: dict[frozenset, Poly] = {}
        for g in level.values():
            for X in jets:
                h = lie_derivative(X, g, ones, max_order - s).drop_zeros(ctx.zero)
                if h.terms:
                    nxt.setdefault(frozenset(h.terms.items()), h)
        if any(not h.is_zero_at((0,) * n, ctx.zero) for h in nxt.values()):
            return s
        level = nxt
        if not level:
            return None
    return None


def _certified_orders(
    ctx: FrameContext,
    forward_poly: Sequence[Poly],
    inverse_poly: Sequence[Poly],
    *,
    quick: bool = False,
    use_reference: bool = True,
) -> tuple[tuple[int | float, ...] | None, tuple[tuple[Poly, ...], ...]]:
    r"""Computed orders of the coordinates, and the field jets (to degree w_j) used.

    With ``quick``, return ``None`` for the orders as soon as the jets show the
    coordinates are not privileged (without computing the lower orders).  Where
    they are not privileged the orders are read in Bellaïche's coordinates $y'$
    (certified privileged first): $\mathrm{ord}_p(f)$ is the weighted order of
    $f(z(y'))$; failing that, from chains of Lie derivatives.
    """
    w = ctx.weights
    jets = _fields_in(ctx, forward_poly, inverse_poly, w, list(w))
    low = low_order_terms(jets, w, ctx.zero)
    if quick and low:
        return None, jets
    hat = [[c.homogeneous_part(w, w[j] - 1) for j, c in enumerate(comps)] for comps in jets]
    reference = _reference_inverse(ctx) if low and use_reference else None
    orders: list[int | float] = []
    for j, wj in enumerate(w):
        if not low and chain_order_homogeneous(hat, j, wj, ctx.zero):
            orders.append(wj)
            continue
        if reference is not None:
            g = forward_poly[j].compose(reference, w, wj + 1).drop_zeros(ctx.zero)
            if g.terms:
                orders.append(min(weighted_degree(m, w) for m in g.terms))
                continue
        s = _chain_order(ctx, forward_poly, inverse_poly, Poly.variable(ctx.n, j), wj)
        if s is None:
            s = _chain_order(ctx, forward_poly, inverse_poly, Poly.variable(ctx.n, j), ctx.step + 1)
        orders.append(s if s is not None else float("inf"))
    return tuple(orders), jets


def _reference_inverse(ctx: FrameContext) -> tuple[Poly, ...] | None:
    """$z$ as polynomials in Bellaïche's coordinates, when their certificate passes."""
    forward, inverse = _algebraic(ctx)[:2]
    orders, _ = _certified_orders(ctx, forward, inverse, quick=True, use_reference=False)
    if orders is None or tuple(orders) != tuple(ctx.weights):
        return None
    return inverse


# --- the three constructions --------------------------------------------------------


Built = tuple[tuple[Poly, ...], tuple[Poly, ...], bool, int | None, bool, int | None]
"""(forward_poly, inverse_poly, inverse_exact, inverse_order, forward_exact, forward_order)."""


def _linear(ctx: FrameContext) -> Built:
    ident = _identity(ctx.n)
    return ident, ident, True, None, True, None


def _algebraic(ctx: FrameContext) -> Built:
    n, w = ctx.n, ctx.weights
    if max(w) <= 2:
        return _linear(ctx)
    E = exponential_map(ctx, max(w) - 1)
    zE = ctx.apply_A([e - Poly.constant(n, to_symengine(p)) for e, p in zip(E, ctx.p, strict=True)])
    forward: list[Poly] = []
    for j, wj in enumerate(w):
        g = Poly.variable(n, j)
        if wj >= 3:
            args = [zE[l].restrict(j) for l in range(n)]
            for k in range(2, wj):
                G = g.compose(args, w, wj - 1)
                h = Poly(
                    n,
                    {
                        a: c
                        for a, c in G.terms.items()
                        if sum(a) == k
                        and weighted_degree(a, w) < wj
                        and not ctx.zero(c, G.magnitude(a))
                    },
                    G.mags,
                )
                g = g - h
        forward.append(g)
    inverse: list[Poly] = []
    for j in range(n):
        rest = Poly.variable(n, j) - forward[j]  # a polynomial in z_1..z_{j-1}
        args = inverse + [Poly.variable(n, l) for l in range(j, n)]
        inverse.append(Poly.variable(n, j) + rest.compose(args))
    return tuple(forward), tuple(inverse), True, None, True, None


def _exponential(ctx: FrameContext) -> Built:
    return from_exponential_map(ctx, exponential_map(ctx, max(ctx.weights)))


def _exponential_first_kind(ctx: FrameContext) -> Built:
    return from_exponential_map(ctx, first_kind_map(ctx, max(ctx.weights)))


METHODS: dict[str, Callable[[FrameContext], Built]] = {
    "linear": _linear,
    "algebraic": _algebraic,
    "exponential": _exponential,
    "exponential-1": _exponential_first_kind,
}
"""Registry: method name → builder of (forward, inverse) polynomial maps.  ``"auto"`` is
accepted by :func:`privileged_coordinates` besides these."""


def coordinate_orders(coords: PrivilegedCoordinates) -> tuple[int | float, ...]:
    r"""Recompute $\mathrm{ord}_p(y_j)$ from the polynomial maps of ``coords`` (module doc)."""
    ctx = FrameContext.of(coords.filtration, coords.numeric)
    orders, _ = _certified_orders(ctx, coords.forward_poly, coords.inverse_poly)
    assert orders is not None
    return orders


def coordinate_names(sys: ControlSystem) -> tuple[sp.Symbol, ...]:
    """Symbols ``y1..yn`` for the privileged coordinates (another letter if the model uses them)."""
    taken = set(sys.coordinate_names) | {k for k, _ in sys.parameters}
    for letter in ("y", "z", "w", "eta", "xi"):
        names = tuple(sp.Symbol(f"{letter}{k}") for k in range(1, sys.n + 1))
        if not taken & {str(s) for s in names}:
            return names
    return tuple(sp.Symbol(f"y_priv{k}") for k in range(1, sys.n + 1))


def _to_sympy_in_x(ctx: FrameContext, polys: Sequence[Poly]) -> tuple[sp.Expr, ...]:
    """Polynomials in $z$ written in the model coordinates, in powers of $x_k - p_k$."""
    n = ctx.n
    d = [Poly.variable(n, k) for k in range(n)]
    lin = ctx.apply_A(d)  # z = A d, d = x − p
    point = ctx.filtration.point  # exact, also in float mode: y(p) = 0 exactly
    shifts = [c - p if p != 0 else c for c, p in zip(ctx.sys.coordinates, point, strict=True)]
    return tuple(
        f.compose(lin).drop_zeros(ctx.zero_x).to_sympy(shifts, keep_factors=ctx.numeric)
        for f in polys
    )


def privileged_coordinates(
    sys: ControlSystem,
    point: Sequence[object] | None = None,
    method: str = "auto",
    filtration: Filtration | None = None,
    *,
    numeric: bool | None = None,
    max_length: int | None = None,
) -> PrivilegedCoordinates:
    r"""Privileged coordinates of ``sys`` at ``point``, with computed orders.

    Parameters
    ----------
    sys:
        The system (parameters substituted).
    point:
        $p$ (default: the origin; ignored when ``filtration`` is given).
    method:
        ``"auto"`` (default), or a name in :data:`METHODS`.
    filtration:
        A precomputed :func:`~nilpotent.core.analysis.filtration.analyze` result at $p$.
    numeric:
        ``False``: exact coefficients; ``True``: floating-point coefficients
        (15 digits); ``None`` (default): exact unless the values of the fields
        or of the frame at $p$ involve transcendental function values
        (``cos(1/5)``) or floats, where exact arithmetic cannot simplify
        ($\sin^2 + \cos^2$ is not recognised as 1) and expressions swell, and
        for the exponential methods where exact arithmetic with irrational
        values (``sqrt(3)/2``) would swell (at once from step 3, past
        :data:`EXACT_TRIAL_BUDGET` seconds at step 2); the result says which
        in ``numeric``.  Floating point never inverts the frame matrix by
        elimination on rounded numbers: $A$ is the inverse of the exact $B$
        enclosed in balls (pivoted, at rising precision) and rounded, checked
        by a scale-free residual (:func:`~nilpotent.core.decide.evaluation.double_inverse`).
    max_length:
        Longest bracket length examined at $p$ (see
        :func:`~nilpotent.core.analysis.filtration.analyze`; default automatic, raised
        within a budget while the search is exhausted before the dimension).

    Returns
    -------
    PrivilegedCoordinates
        With ``orders`` equal to the weights (computed, see the module docstring).

    Raises
    ------
    NotPrivilegedError
        ``method="linear"`` where linear adapted coordinates are not privileged
        (the message names each coordinate whose computed order differs from its weight).
    NotBracketGeneratingError
        If the system is not bracket-generating at $p$.
    ComputationLimitError
        If whether it is bracket-generating at $p$ stays undetermined within the
        budget (the message says what was tried and how to search further).
    OptionError
        Unknown method.

    Examples
    --------
    >>> x1, x2, x3 = sp.symbols("x1 x2 x3")
    >>> martinet = ControlSystem("martinet", (x1, x2, x3), ((1, 0, x2**2 / 2), (0, 1, 0)))
    >>> c = privileged_coordinates(martinet)
    >>> c.method, c.orders
    ('linear', (1, 1, 3))
    """
    if method != "auto" and method not in METHODS:
        raise OptionError(
            f"unknown privileged-coordinates method {method!r}; choose one of "
            f"auto, {', '.join(METHODS)}"
        )
    f = filtration if filtration is not None else analyze(sys, point, max_length=max_length)
    if f.bracket_generating is None:
        und = f.undetermined or {}
        raise ComputationLimitError(
            f"whether {sys.name!r} is bracket-generating at the point is undetermined: "
            f"{und.get('reason', '')}; no privileged coordinates (search longer brackets "
            "with max_length, CLI --max-length)"
        )
    if f.growth_vector_known_up_to is not None:
        raise ComputationLimitError(
            f"{sys.name!r} is bracket-generating at the point (proved through its orbit), but "
            f"its growth vector there is known up to bracket length "
            f"{f.growth_vector_known_up_to} only, and privileged coordinates need all the "
            "weights (search longer brackets with max_length, CLI --max-length)"
        )
    if not f.bracket_generating:
        raise NotBracketGeneratingError(
            f"{sys.name!r} is not bracket-generating at the point: its brackets span "
            f"{f.growth_vector[-1]} of {sys.n} dimensions (growth vector {f.growth_vector}); "
            "no privileged coordinates"
        )
    if numeric is None:
        numeric = needs_floats(f)
        # exact irrational values (sqrt(3)/2): the series inverse may swell for minutes;
        # exact arithmetic is tried for a short while, then floating point (below)
        irrational = not numeric and method in SERIES_METHODS and not rational_values(f)
        # step >= 3 swells past any budget (the kinematic snake at pi/3: > 600 s): floats
        # at once; step 2 (the trident snake at 0, under a second) tries exact first
        trial = irrational and f.step < 3
        numeric = numeric or (irrational and not trial)
    else:
        trial = False
    ctx = FrameContext.of(f, numeric)
    if method == "auto":
        built = _linear(ctx)
        orders, jets = _certified_orders(ctx, built[0], built[1], quick=True)
        name = "linear"
        if orders is None or tuple(orders) != tuple(f.weights):
            name = "algebraic"
            built = _algebraic(ctx)
            orders, jets = _certified_orders(ctx, built[0], built[1])
    else:
        name = method
        try:
            with series_budget(ctx, EXACT_TRIAL_BUDGET if trial else None) if (
                method in SERIES_METHODS
            ) else nullcontext():
                built = METHODS[method](ctx)
                orders, jets = _certified_orders(ctx, built[0], built[1])
        except ComputationLimitError:
            if not trial:
                raise
            numeric = True
            ctx = FrameContext.of(f, numeric)
            with series_budget(ctx):
                built = METHODS[method](ctx)
                orders, jets = _certified_orders(ctx, built[0], built[1])
    assert orders is not None  # only quick=True returns None, and it was redone above
    bad = [(j, o, wj) for j, (o, wj) in enumerate(zip(orders, f.weights, strict=True)) if o != wj]
    names = coordinate_names(sys)
    if bad:
        what = "; ".join(f"{names[j]} has order {o} but weight {wj}" for j, o, wj in bad)
        hint = (
            " (use method 'algebraic' or 'exponential', privileged at any step)"
            if name == "linear"
            else ""
        )
        raise NotPrivilegedError(
            f"{name} coordinates of {sys.name!r} at the point are not privileged: {what}{hint}"
        )
    forward_poly, inverse_poly, inv_exact, inv_order, fwd_exact, fwd_order = built
    x_of_y = ctx.x_of(inverse_poly)
    coords = PrivilegedCoordinates(
        method=name,
        filtration=f,
        names=names,
        forward=_to_sympy_in_x(ctx, forward_poly),
        inverse=tuple(e.drop_zeros(ctx.zero_x).to_sympy(names) for e in x_of_y),
        inverse_exact=inv_exact,
        inverse_order=inv_order,
        orders=tuple(int(o) for o in orders),
        forward_exact=fwd_exact,
        forward_order=fwd_order,
        numeric=numeric,
        frame_matrix=ctx.B,
        linear_part=ctx.A,
        forward_poly=tuple(forward_poly),
        inverse_poly=tuple(inverse_poly),
        known_jets=jets,
    )
    return coords
