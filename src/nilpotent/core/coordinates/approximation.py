r"""The nilpotent approximation of a system at a point, and its certificate.

In privileged coordinates $y$ at $p$ (:mod:`nilpotent.core.coordinates.privileged`) write
$X_i = \sum_j f_{ij}(y)\,\partial_{y_j}$.  Each $f_{ij}$ has weighted order
$\ge w_j - 1$; keeping in $f_{ij}$ exactly its terms of weighted degree
$w_j - 1$ gives $\hat X_i$ (the mathematics page, §5).  Only the weighted Taylor jets of
the fields to degree $w_j$ are computed (:func:`nilpotent.core.coordinates.jets.weighted_jets`:
$y_k \to t^{w_k} y_k$ and one univariate series in $t$), never a full
expansion.

$\hat X_i$ is pushed forward to the model coordinates with the Jacobian,
$[\hat X_i]_x(x) = (\partial x/\partial y)(y(x))\,[\hat X_i]_y(y(x))$; for the
``linear`` and ``algebraic`` coordinates both maps are polynomial and exact,
so ``fields_x`` is exact (polynomials in $x - p$).  For ``exponential`` and
``exponential-1`` coordinates the forward map is a truncated series and so is
``fields_x`` (terms of degree $> r$ in $z = A(x - p)$ dropped, $z_k$ counting
its order: the dropped part is a vector field of order $\ge 1$): it differs
from the formula above from degree 3 in $x - p$, and its pull-back to $y$
still equals $\hat X$ up to the degrees checked by ``pushforward_ok``.

The :class:`Certificate` is computed, never assumed (see :func:`certify`).
Bracket convention $[X,Y] = DY\cdot X - DX\cdot Y$.
"""

from __future__ import annotations

from collections.abc import Sequence
from contextlib import nullcontext
from dataclasses import dataclass, replace

import symengine as se
import sympy as sp

from nilpotent import typeset
from nilpotent.core.analysis.filtration import Filtration
from nilpotent.core.coordinates.exponential_map import (
    check_budget,
    exponential_grading,
    series_budget,
)
from nilpotent.core.coordinates.jets import (
    Poly,
    ZeroTest,
    bracket,
    to_symengine,
)
from nilpotent.core.coordinates.privileged import (
    FrameContext,
    PrivilegedCoordinates,
    coordinate_orders,
    privileged_coordinates,
)
from nilpotent.core.coordinates.pullback import pushforward_ok as _pushforward_ok
from nilpotent.core.coordinates.pullback import read_poly as _read
from nilpotent.core.decide.spans import Decision, ExprVector, MeasuredSpan, Span
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import OptionError
from nilpotent.progress import progress
from nilpotent.strict_json import json_object

__all__ = ["Certificate", "NilpotentApproximation", "approximate", "certify"]


@dataclass(frozen=True)
class Certificate:
    r"""What was computed to check a nilpotent approximation.

    Attributes
    ----------
    orders:
        Computed $\mathrm{ord}_p(y_j)$ of the privileged coordinates
        (``math.inf`` where no finite order was found, only when recomputed).
    weights:
        The weights $w_j$ at $p$.
    homogeneous:
        Every $\hat X_i$ is homogeneous of degree $-1$ under the dilations
        $\delta_\lambda y = (\lambda^{w_1}y_1, \dots)$: computed as
        $\hat X_i^j(\delta_\lambda y) - \lambda^{w_j-1}\hat X_i^j(y) \equiv 0$.
    nilpotent_step:
        The least $s$ such that every bracket of length $s + 1$ of the
        $\hat X_i$ vanishes identically (computed on a basis of each length);
        ``None`` when brackets up to length $2r+1$ do not all vanish.
    step:
        $r(p)$, the step of the original system at $p$.
    growth_vector_at_0:
        Growth vector of $(\hat X_i)$ at $y = 0$ (computed from its brackets).
    growth_vector:
        Growth vector of $(X_i)$ at $p$.
    remainder_orders:
        For each $i$: a lower bound of the order of $X_i - \hat X_i$ at $p$,
        $\min_j(\text{least weighted degree of a nonzero term of component } j) - w_j$,
        read from the jets of component $j$ up to weighted degree $w_j$
        (``1`` means no term up to that degree: order $\ge 1$).
    remainder_order_ok:
        All ``remainder_orders`` are $\ge 0$ ($\hat X$ is a first-order approximation).
    pushforward_ok:
        Pulling ``fields_x`` back with $\partial y/\partial x$ at $x(y)$ gives
        ``fields`` again (compared up to weighted degree $w_j$ in component $j$
        for exact coordinates, $w_j - 1$ for truncated ones).
    exact:
        Whether every decision above was exact (no numerical zero test).
    """

    orders: tuple[int | float, ...]
    weights: tuple[int, ...]
    homogeneous: bool
    nilpotent_step: int | None
    step: int
    growth_vector_at_0: tuple[int, ...]
    growth_vector: tuple[int, ...]
    remainder_orders: tuple[int, ...]
    remainder_order_ok: bool
    pushforward_ok: bool
    exact: bool

    @property
    def privileged(self) -> bool:
        """The computed orders equal the weights."""
        return tuple(self.orders) == tuple(self.weights)

    @property
    def ok(self) -> bool:
        """Every check passed."""
        return (
            self.privileged
            and self.homogeneous
            and self.nilpotent_step == self.step
            and tuple(self.growth_vector_at_0) == tuple(self.growth_vector)
            and self.remainder_order_ok
            and self.pushforward_ok
        )

    def failures(self) -> tuple[str, ...]:
        """One line per failed check."""
        out = []
        if not self.privileged:
            out.append(f"coordinate orders {self.orders} differ from the weights {self.weights}")
        if not self.homogeneous:
            out.append("some field is not homogeneous of degree -1")
        if self.nilpotent_step != self.step:
            out.append(f"nilpotent step {self.nilpotent_step}, expected {self.step}")
        if tuple(self.growth_vector_at_0) != tuple(self.growth_vector):
            out.append(
                f"growth vector at 0 {self.growth_vector_at_0}, expected {self.growth_vector}"
            )
        if not self.remainder_order_ok:
            out.append(f"X_i - X̂_i has order {self.remainder_orders} (need >= 0)")
        if not self.pushforward_ok:
            out.append("fields_x pulled back to y differ from fields")
        return tuple(out)

    def __str__(self) -> str:
        lines = [
            f"orders of y: {self.orders} (weights {self.weights})",
            f"homogeneous of degree -1: {self.homogeneous}",
            f"nilpotent of step {self.nilpotent_step} (system step {self.step})",
            f"growth vector at 0: {self.growth_vector_at_0} (system at p: {self.growth_vector})",
            f"order of X_i - X̂_i >= {min(self.remainder_orders)}: {self.remainder_order_ok}",
            f"push-forward consistent: {self.pushforward_ok}",
            f"all decisions exact: {self.exact}",
        ]
        return "\n".join(lines)

    # --- display (nilpotent.typeset) -------------------------------------------------
    def to_latex(self) -> str:
        """Each check, computed and expected values, verdict as LaTeX (``align*``)."""
        return typeset.certificate_display(self).latex()

    def _repr_latex_(self) -> str:
        return self.to_latex()

    def _repr_html_(self) -> str:
        return typeset.certificate_display(self).html()


@dataclass(frozen=True)
class NilpotentApproximation:
    r"""The nilpotent approximation $(\hat X_1, \dots, \hat X_m)$ of a system at $p$.

    Attributes
    ----------
    system:
        The original system.
    point:
        $p$, in the model coordinates.
    filtration:
        The filtration at $p$.
    coordinates:
        The privileged coordinates used.
    fields:
        ``fields[i][j]`` is the $y_{j+1}$-component of $\hat X_{i+1}$, a
        polynomial in ``coordinates.names``, homogeneous of weighted degree
        $w_{j+1} - 1$.
    fields_x:
        $\hat X_i$ pushed forward to the model coordinates (polynomials in
        $x - p$; exact unless ``fields_x_exact`` is false).
    fields_x_exact:
        Whether ``fields_x`` is exact (false for exponential coordinates).
    certificate:
        The computed checks.
    """

    system: ControlSystem
    point: tuple[sp.Expr, ...]
    filtration: Filtration
    coordinates: PrivilegedCoordinates
    fields: tuple[tuple[sp.Expr, ...], ...]
    fields_x: tuple[tuple[sp.Expr, ...], ...]
    fields_x_exact: bool
    certificate: Certificate

    @property
    def names(self) -> tuple[sp.Symbol, ...]:
        return self.coordinates.names

    @property
    def weights(self) -> tuple[int, ...]:
        return self.filtration.weights

    def as_system(self, coordinates: str = "y") -> ControlSystem:
        """The approximation as a :class:`ControlSystem`, coordinates ``"y"`` or ``"x"``."""
        if coordinates == "y":
            return ControlSystem(
                f"{self.system.name}-nilpotent",
                self.names,
                self.fields,
                (),
                f"nilpotent approximation of {self.system.name} at {self._point_text()} "
                f"in {self.coordinates.method} privileged coordinates",
            )
        if coordinates == "x":
            return ControlSystem(
                f"{self.system.name}-nilpotent-x",
                self.system.coordinates,
                self.fields_x,
                (),
                f"nilpotent approximation of {self.system.name} at {self._point_text()} "
                f"in the model coordinates",
            )
        raise OptionError(f"coordinates must be 'y' or 'x', got {coordinates!r}")

    def _point_text(self) -> str:
        return "(" + ", ".join(str(v) for v in self.point) + ")"

    def __str__(self) -> str:
        coords = self.coordinates
        lines = [
            f"nilpotent approximation of {self.system.name} at {self._point_text()}",
            f"growth vector {self.filtration.growth_vector}, weights {self.weights}, "
            f"step {self.filtration.step}, frame {', '.join(self.filtration.frame_names)}",
            f"{coords.method} privileged coordinates:",
        ]
        for y, e in zip(coords.names, coords.forward, strict=True):
            lines.append(f"  {y} = {e}")
        if coords.numeric:
            lines.append(
                "coefficients: floating point (15 digits): the values at the point are "
                "transcendental, exact arithmetic would not simplify"
            )
        lines.append("approximation in y:")
        lines += _field_lines(self.fields, coords.names)
        lines.append(
            "approximation in the model coordinates:"
            + ("" if self.fields_x_exact else " (truncated)")
        )
        lines += _field_lines(self.fields_x, self.system.coordinates)
        lines.append("certificate:")
        lines += ["  " + s for s in str(self.certificate).splitlines()]
        return "\n".join(lines)

    def to_json(self) -> dict[str, object]:
        """The ``nilpotent/approximation@1`` JSON object (the interface page).

        The analysis@1 keys of the filtration, plus ``method``, ``privileged``
        (names, expressions, inverse, exactness), ``fields``, ``fields_x`` and
        ``certificate``.
        """
        from nilpotent.core.model.expressions import format_expression

        coords = self.coordinates
        cert = self.certificate
        payload = self.filtration.to_json()
        payload["schema"] = "nilpotent/approximation@1"
        payload["method"] = coords.method
        payload["privileged"] = {
            "names": [str(s) for s in coords.names],
            "expressions": [format_expression(e) for e in coords.forward],
            "inverse": [format_expression(e) for e in coords.inverse],
            "inverse_exact": coords.inverse_exact,
            "forward_exact": coords.forward_exact,
            "numeric": coords.numeric,
        }
        payload["fields"] = [[format_expression(c) for c in f] for f in self.fields]
        payload["fields_x"] = [[format_expression(c) for c in f] for f in self.fields_x]
        payload["certificate"] = {
            "orders": list(cert.orders),
            "weights": list(cert.weights),
            "nilpotent_step": cert.nilpotent_step,
            "homogeneous": cert.homogeneous,
            "growth_vector_at_0": list(cert.growth_vector_at_0),
            "remainder_order_ok": cert.remainder_order_ok,
            "remainder_orders": list(cert.remainder_orders),
            "step": cert.step,
            "growth_vector": list(cert.growth_vector),
            "pushforward_ok": cert.pushforward_ok,
            "privileged": cert.privileged,
            "exact": cert.exact,
            "ok": cert.ok,
            "failures": list(cert.failures()),
        }
        return json_object(payload)

    # --- display (nilpotent.typeset) -------------------------------------------------
    def to_latex(self) -> str:
        """Coordinates, both forms of the fields and the certificate as LaTeX (``align*``)."""
        return typeset.approximation_display(self).latex()

    def _repr_latex_(self) -> str:
        return self.to_latex()

    def _repr_html_(self) -> str:
        return typeset.approximation_display(self).html()


def _field_lines(fields: Sequence[Sequence[sp.Expr]], coords: Sequence[sp.Symbol]) -> list[str]:
    out = []
    for i, f in enumerate(fields, start=1):
        text = ""
        for e, c in zip(f, coords, strict=True):
            if e == 0:
                continue
            negative = e.could_extract_minus_sign()
            a = -e if negative else e
            term = f"∂{c}" if a == 1 else (f"({a})·∂{c}" if isinstance(a, sp.Add) else f"{a}·∂{c}")
            if text:
                text += (" - " if negative else " + ") + term  # ASCII minus, as sympy's
            else:  # text in the other lines: the formulas paste as they print
                text = ("-" if negative else "") + term
        out.append(f"  X̂{i} = " + (text or "0"))
    return out


# --- certificate ------------------------------------------------------------------------


def _se_symbols(names: Sequence[sp.Symbol]) -> list[se.Symbol]:
    return [to_symengine(s) for s in names]


def _polys(
    fields: Sequence[Sequence[sp.Expr]], names: Sequence[sp.Symbol], numeric: bool = False
) -> list[list[Poly]]:
    ys = _se_symbols(names)
    return [[_read(to_symengine(c), ys, numeric) for c in f] for f in fields]


def _homogeneous(
    fields: Sequence[Sequence[sp.Expr]], names: Sequence[sp.Symbol], weights: Sequence[int]
) -> bool:
    lam = se.Symbol("_lambda")
    ys = _se_symbols(names)
    dil = {y: lam**w * y for y, w in zip(ys, weights, strict=True)}
    for f in fields:
        for c, w in zip(f, weights, strict=True):
            e = to_symengine(c)
            if se.expand(e.xreplace(dil) - lam ** (w - 1) * e) != 0:
                return False
    return True


class _Echelon:
    """Incremental rank of sparse coefficient vectors, through :mod:`nilpotent.core.decide.spans`.

    Exact coefficients are decided by the certified engine (:class:`Span`);
    floating-point coefficients (approximations at transcendental points) by a
    scale-invariant :class:`MeasuredSpan`.  Every decision that is not proved
    (floats, or *undetermined*) is counted in ``zero.numeric_decisions``, so
    that the certificate says it was not exact.
    """

    def __init__(self, zero: ZeroTest) -> None:
        self.zero = zero
        self.span = Span()
        self.measured: MeasuredSpan | None = None

    def add(self, vec: dict) -> bool:
        v = {k: c for k, c in vec.items() if c != 0}
        if not v:
            return False
        if self.measured is not None or any(_is_float(c) for c in v.values()):
            if self.measured is None:
                self.measured = MeasuredSpan()
                for old in self.span.vectors:
                    self.measured.try_add(old.entries)  # type: ignore[attr-defined]
            self.zero.numeric_decisions += 1
            return self.measured.try_add(v)
        decision = self.span.add(ExprVector(v))
        if decision is Decision.UNDETERMINED:
            self.zero.numeric_decisions += 1
        return decision is Decision.INDEPENDENT

    @property
    def rank(self) -> int:
        return self.measured.rank if self.measured is not None else self.span.rank


def _is_float(c: object) -> bool:
    e = se.S(c)
    return isinstance(e, se.RealDouble) or bool(e.atoms(se.RealDouble))


def _field_vector(field: Sequence[Poly]) -> dict:
    return {(j, m): c for j, comp in enumerate(field) for m, c in comp.terms.items()}


def _bracket_levels(
    hat: Sequence[Sequence[Poly]], max_length: int, zero: ZeroTest
) -> list[list[tuple[Poly, ...]]]:
    """A basis of the span of the brackets of each length 1..max_length (until one is empty)."""
    levels: list[list[tuple[Poly, ...]]] = []
    ech = _Echelon(zero)
    current = []
    for X in hat:
        if ech.add(_field_vector(X)):
            current.append(tuple(X))
    levels.append(current)
    for _ in range(2, max_length + 1):
        if not current:
            break
        ech = _Echelon(zero)
        nxt = []
        for X in hat:
            for b in current:
                br = bracket(X, b)
                if any(c.mags is not None for c in br):  # floats: drop what cancelled
                    br = tuple(c.drop_zeros(zero) for c in br)
                if ech.add(_field_vector(br)):
                    nxt.append(br)
        levels.append(nxt)
        current = nxt
    return levels


def _growth_at_zero(
    levels: Sequence[Sequence[tuple[Poly, ...]]], n: int, zero: ZeroTest
) -> tuple[int, ...]:
    ech = _Echelon(zero)
    growth = []
    for level in levels:
        for f in level:
            origin = (0,) * n
            ech.add(
                {j: c.value_at_zero() for j, c in enumerate(f) if not c.is_zero_at(origin, zero)}
            )
        growth.append(ech.rank)
    while len(growth) > 1 and growth[-1] == growth[-2]:
        growth.pop()
    return tuple(growth)


def _remainder_orders(
    jets: Sequence[Sequence[Poly]],
    hat: Sequence[Sequence[Poly]],
    weights: Sequence[int],
    zero: ZeroTest,
) -> tuple[int, ...]:
    out = []
    for true, approx in zip(jets, hat, strict=True):
        best = 1
        for j, (a, b) in enumerate(zip(true, approx, strict=True)):
            rem = (a - b).truncate(weights, weights[j])
            o = rem.order(weights, zero)
            if o is not None:
                best = min(best, o - weights[j])
        out.append(best)
    return tuple(out)


def certify(approx: NilpotentApproximation, *, recompute_orders: bool = False) -> Certificate:
    """Recompute every check of ``approx`` from its system, coordinates and fields.

    Works on any :class:`NilpotentApproximation`, also one modified with
    :func:`dataclasses.replace` (this is how the tests show each check can fail).
    The orders of the coordinates are those computed when the coordinates were
    built (``coordinates.orders``); ``recompute_orders`` computes them again from
    the coordinates' polynomial maps.
    """
    coords = approx.coordinates
    w = coords.weights
    r = approx.filtration.step
    zero = ZeroTest(unit=1.0)  # the fields in y: frame units (taylor.ZeroTest)
    hat = _polys(approx.fields, coords.names, coords.numeric)
    homogeneous = _homogeneous(approx.fields, coords.names, w)
    levels = _bracket_levels(hat, 2 * r + 2, zero)
    nonzero = [k for k, lev in enumerate(levels, start=1) if lev]
    vanished = len(levels) > len(nonzero) or not levels
    nil_step = (max(nonzero) if nonzero else 0) if vanished else None
    growth0 = _growth_at_zero(levels, coords.n, zero)
    jets = coords.field_jets(extra=1)
    rem = _remainder_orders(jets, hat, w, zero)
    push = _pushforward_ok(approx, hat, zero)
    ctx = FrameContext.of(approx.filtration, approx.coordinates.numeric)
    ctx_decisions = ctx.zero.numeric_decisions + ctx.zero_x.numeric_decisions
    orders = coordinate_orders(coords) if recompute_orders else coords.orders
    return Certificate(
        orders=tuple(orders),
        weights=w,
        homogeneous=homogeneous,
        nilpotent_step=nil_step,
        step=r,
        growth_vector_at_0=growth0,
        growth_vector=approx.filtration.growth_vector,
        remainder_orders=rem,
        remainder_order_ok=all(o >= 0 for o in rem),
        pushforward_ok=push,
        exact=approx.filtration.exact
        and zero.numeric_decisions == 0
        and ctx_decisions == 0,
    )


# --- the approximation ----------------------------------------------------------------------


def _pushforward(
    coords: PrivilegedCoordinates, hat: Sequence[Sequence[Poly]]
) -> tuple[tuple[tuple[sp.Expr, ...], ...], bool]:
    r"""$[\hat X]_x = B\,(\partial\chi/\partial y)(\psi(z))\,\hat X(\psi(z))$ at $z = A(x - p)$."""
    ctx = FrameContext.of(coords.filtration, coords.numeric)
    n = coords.n
    exact = coords.forward_exact and coords.inverse_exact
    omega = exponential_grading(coords.weights, coords.inverse_poly)  # ord(z_k), privileged.py
    top = None if exact else ctx.step
    fwd = coords.forward_poly
    dchi = [
        [coords.inverse_poly[k].diff(l).compose(fwd, omega, top) for l in range(n)]
        for k in range(n)
    ]
    d = [Poly.variable(n, k) for k in range(n)]
    lin = ctx.apply_A(d)
    shifts = [
        c - p if p != 0 else c for c, p in zip(coords.system.coordinates, coords.point, strict=True)
    ]
    out = []
    for h in hat:
        check_budget(ctx)
        hz = [c.compose(fwd, omega, top) for c in h]
        vz = []
        for k in range(n):
            acc = Poly(n)
            for l in range(n):
                if dchi[k][l].terms and hz[l].terms:
                    acc = acc + dchi[k][l].mul(hz[l], omega, top)
            vz.append(acc)
        vx = []
        for k in range(n):
            acc = Poly(n)
            for l in range(n):
                b = ctx.Bse[k][l]
                if b != 0 and vz[l].terms:
                    acc = acc + vz[l].scale(b)
            vx.append(
                acc.compose(lin).drop_zeros(ctx.zero_x).to_sympy(shifts, keep_factors=ctx.numeric)
            )
        out.append(tuple(vx))
    return tuple(out), exact


def approximate(
    sys: ControlSystem,
    point: Sequence[object] | None = None,
    method: str = "auto",
    *,
    numeric: bool | None = None,
    max_length: int | None = None,
) -> NilpotentApproximation:
    r"""The nilpotent approximation of ``sys`` at ``point``, with its computed certificate.

    Parameters
    ----------
    sys:
        The system (parameters substituted).
    point:
        $p$ (default: the origin).  Regular or singular.
    method:
        Privileged coordinates: ``"auto"`` (linear where privileged, else
        algebraic), ``"linear"``, ``"algebraic"`` or ``"exponential"``.
    numeric:
        ``True`` for floating-point coefficients, ``False`` for exact ones,
        ``None`` (default) for exact unless the values at the point are
        transcendental (see :func:`~nilpotent.core.coordinates.privileged.privileged_coordinates`);
        ``coordinates.numeric`` and the printed output say which.
    max_length:
        Longest bracket length examined at $p$ (default automatic: raised
        within a budget while the search is exhausted before the dimension;
        see :func:`~nilpotent.core.analysis.filtration.analyze`).

    Returns
    -------
    NilpotentApproximation

    Raises
    ------
    NotPrivilegedError
        ``method="linear"`` where linear adapted coordinates are not privileged.
    NotBracketGeneratingError
        If the system is not bracket-generating at the point.
    ComputationLimitError
        If whether it is bracket-generating stays undetermined within the budget.

    Examples
    --------
    >>> x1, x2, x3 = sp.symbols("x1 x2 x3")
    >>> martinet = ControlSystem("martinet", (x1, x2, x3), ((1, 0, x2**2 / 2), (0, 1, 0)))
    >>> a = approximate(martinet)
    >>> a.fields
    ((1, 0, -y2**2/2), (0, 1, 0))
    >>> a.certificate.ok
    True
    """
    with progress(f"nilpotent approximation of {sys.name}", total=3) as bar:
        bar.update(0, "privileged coordinates")
        coords = privileged_coordinates(
            sys, point, method, numeric=numeric, max_length=max_length
        )
        bar.update(1, "approximation")
        series = coords.method in ("exponential", "exponential-1") and not coords.numeric
        ctx = FrameContext.of(coords.filtration, coords.numeric)
        with series_budget(ctx) if series else nullcontext():
            result = _approximation(sys, coords)
            bar.update(2, "certificate")
            cert = certify(result)
        bar.update(3)
    return replace(result, certificate=cert)


def _approximation(sys: ControlSystem, coords: PrivilegedCoordinates) -> NilpotentApproximation:
    """The approximation in ``coords`` (its certificate not computed yet)."""
    w = coords.weights
    ctx = FrameContext.of(coords.filtration, coords.numeric)
    jets = coords.field_jets(extra=1)
    hat = [
        tuple(c.homogeneous_part(w, w[j] - 1).drop_zeros(ctx.zero) for j, c in enumerate(comps))
        for comps in jets
    ]
    fields = tuple(tuple(c.to_sympy(coords.names) for c in h) for h in hat)
    fields_x, x_exact = _pushforward(coords, hat)
    return NilpotentApproximation(
        system=sys,
        point=coords.point,
        filtration=coords.filtration,
        coordinates=coords,
        fields=fields,
        fields_x=fields_x,
        fields_x_exact=x_exact,
        certificate=None,  # type: ignore[arg-type]
    )
