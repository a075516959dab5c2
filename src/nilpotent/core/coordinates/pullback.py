r"""The pull-back check of a nilpotent approximation's certificate (``pushforward_ok``).

``fields_x`` (the approximation pushed forward to the model coordinates) is
pulled back to the privileged coordinates $y$ and compared with ``fields``, in
truncated polynomial arithmetic; floating-point coefficients are compared
relative to their tracked magnitudes (:class:`nilpotent.core.coordinates.jets.ZeroTest`),
never with an absolute threshold.  Split from :mod:`nilpotent.core.coordinates.approximation`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import symengine as se

from nilpotent.core.coordinates.frame_context import FrameContext
from nilpotent.core.coordinates.jets import Poly, ZeroTest, to_symengine

if TYPE_CHECKING:
    from nilpotent.core.coordinates.approximation import NilpotentApproximation

__all__ = ["pushforward_ok"]


def read_poly(expr: se.Basic, variables: Sequence[se.Symbol], numeric: bool) -> Poly:
    """A polynomial read from an expression; floats: their magnitudes tracked from here."""
    poly = Poly.from_expr(expr, variables)
    return poly.tracked() if numeric else poly


def pushforward_ok(
    approx: NilpotentApproximation, hat: Sequence[Sequence[Poly]], zero: ZeroTest
) -> bool:
    r"""Pull ``fields_x`` back: $(\partial y/\partial x)(x(y))\,[\hat X]_x(x(y))$ equals $\hat X$.

    All in truncated polynomial arithmetic in $y$: ``fields_x`` is read as a
    polynomial in $d = x - p$, composed with $d(y) = B\chi(y)$; the Jacobian is
    $(\partial y/\partial z)(\chi(y))\,A$ from the forward map $y(z)$.  Component
    $j$ is compared up to weighted degree $w_j$ (exact coordinates) or $w_j - 1$.
    """
    coords = approx.coordinates
    ctx = FrameContext.of(approx.filtration, approx.coordinates.numeric)
    w = coords.weights
    n = coords.n
    exact = coords.inverse_exact and coords.forward_exact and approx.fields_x_exact
    degrees = [wj if exact else wj - 1 for wj in w]
    top = max(degrees)
    ds = [se.Symbol(f"_nilpotent_d{k}") for k in range(n)]
    # fields_x is written in powers of x - p with the exact p (also in floating point)
    point = approx.filtration.point
    shift = {x: d + to_symengine(p) for x, d, p in zip(ctx.xsyms, ds, point, strict=True)}
    chi = list(coords.inverse_poly)
    d_of_y = [
        x - Poly.constant(n, to_symengine(p)) for x, p in zip(ctx.x_of(chi), ctx.p, strict=True)
    ]
    jac_z = [
        [coords.forward_poly[j].diff(l).compose(chi, w, top) for l in range(n)] for j in range(n)
    ]
    jac = []
    for j in range(n):
        row = []
        for k in range(n):
            acc = Poly(n)
            for l in range(n):
                a = ctx.Ase[l][k]
                if a != 0 and jac_z[j][l].terms:
                    acc = acc + jac_z[j][l].scale(a)
            row.append(acc)
        jac.append(row)
    for fx, h in zip(approx.fields_x, hat, strict=True):
        comps = [
            read_poly(to_symengine(c).xreplace(shift), ds, coords.numeric).compose(d_of_y, w, top)
            for c in fx
        ]
        for j in range(n):
            acc = Poly(n)
            for k in range(n):
                if jac[j][k].terms and comps[k].terms:
                    acc = acc + jac[j][k].mul(comps[k], w, degrees[j])
            diff = (acc - h[j]).truncate(w, degrees[j])
            if diff.drop_zeros(zero).terms:
                return False
    return True
