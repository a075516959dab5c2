r"""The context every privileged-coordinates construction shares, and its arithmetic.

:class:`FrameContext` holds the system's fields in symengine, the point, the frame
matrix $B$ (column $k$ is $Y_{k+1}(p)$), its inverse $A$ and the zero test, in
exact arithmetic or in floating point; :func:`needs_floats` and
:func:`rational_values` say which arithmetic a point needs.  In floating point
$A$ is never computed by elimination on rounded numbers: it is the inverse of
the exact $B$ enclosed in balls, rounded, with a scale-free residual check
(:func:`nilpotent.core.decide.evaluation.double_inverse`).  Split from
:mod:`nilpotent.core.coordinates.privileged`, which re-exports these names.
"""

from __future__ import annotations

from collections.abc import Sequence

import symengine as se
import sympy as sp

from nilpotent.core.analysis.filtration import Filtration
from nilpotent.core.coordinates.jets import Poly, ZeroTest, to_symengine
from nilpotent.core.decide.evaluation import double_inverse, exact_value
from nilpotent.core.decide.spans import to_double
from nilpotent.core.model.memo import IdentityMemo
from nilpotent.errors import ComputationLimitError

__all__ = ["EXACT_TRIAL_BUDGET", "needs_floats"]


# the frame contexts of each system, owned here (the system is immutable); a context
# refers to its system, so the table is bounded
_CONTEXTS: IdentityMemo[dict] = IdentityMemo(maxsize=64)


class FrameContext:
    """What every construction needs: frame matrices, fields in symengine, the zero test."""

    def __init__(self, filtration: Filtration, numeric: bool) -> None:
        sys = filtration.system
        self.filtration = filtration
        self.numeric = numeric
        self.sys = sys
        self.n = sys.n
        self.weights = filtration.weights
        self.step = filtration.step
        self.xsyms = tuple(se.Symbol(str(c)) for c in sys.coordinates)
        self.fields = tuple(
            tuple(se.expand(to_symengine(e)) for e in f) for f in sys.specialized_fields
        )
        n = self.n
        B = sp.Matrix(n, n, lambda j, k: filtration.frame_values[k][j])
        if numeric:
            self.p = tuple(_to_float(v) for v in filtration.point)
            # never an elimination on the rounded matrix (sympy's LU does not pivot on
            # size): the inverse of the exact frame, enclosed in arb balls (pivoted, at
            # rising precision) and rounded, with a scale-free residual check
            exact = [[to_symengine(B[j, k]) for k in range(n)] for j in range(n)]
            try:
                inv = double_inverse(exact)
            except ZeroDivisionError as exc:
                raise ComputationLimitError(
                    f"the frame matrix of {sys.name!r} at the point cannot be inverted in "
                    f"floating point ({exc}); no floating-point privileged coordinates"
                ) from exc
            B = sp.Matrix(n, n, lambda j, k: _to_float(exact[j][k]))
            A = sp.Matrix(n, n, lambda j, k: sp.Float(inv[j][k], 15) if inv[j][k] else sp.S(0))
        else:
            self.p = filtration.point
            A = B.inv()
            A = A.applyfunc(lambda e: sp.radsimp(e) if e.has(sp.Pow) else e)
        self.B = sp.ImmutableMatrix(B)
        self.A = sp.ImmutableMatrix(A)
        self.Bse = [[to_symengine(B[j, k]) for k in range(n)] for j in range(n)]
        self.Ase = [[to_symengine(A[j, k]) for k in range(n)] for j in range(n)]
        # floats in the adapted coordinates z, y (the frame is the unit there), and in the
        # model coordinates x (no natural unit: relative to the tracked magnitudes only)
        self.zero = ZeroTest(unit=1.0)
        self.zero_x = ZeroTest()

    @staticmethod
    def of(filtration: Filtration, numeric: bool = False) -> FrameContext:
        cache = _CONTEXTS.get(filtration.system, dict)
        key = (filtration.point, filtration.frame, numeric)
        if key not in cache:
            cache[key] = FrameContext(filtration, numeric)
        return cache[key]

    def x_of(self, inverse_poly: Sequence[Poly]) -> list[Poly]:
        """$x = p + B\\chi(y)$ as polynomials in $y$."""
        n = self.n
        out = []
        for k in range(n):
            acc = Poly.constant(n, to_symengine(self.p[k]))
            for l in range(n):
                b = self.Bse[k][l]
                if b != 0:
                    acc = acc + inverse_poly[l].scale(b)
            out.append(acc)
        return out

    def apply_A(self, vec: Sequence[Poly]) -> list[Poly]:
        n = self.n
        out = []
        for j in range(n):
            acc = Poly(vec[0].nvars)
            for k in range(n):
                a = self.Ase[j][k]
                if a != 0 and vec[k].terms:
                    acc = acc + vec[k].scale(a)
            out.append(acc)
        return out


def _to_float(value: object) -> sp.Expr:
    """A 15-digit float of an exact value (a certified ball, :func:`spans.to_double`); 0 is 0."""
    if value == 0:
        return sp.S(0)
    return sp.Float(to_double(value), 15)


def needs_floats(filtration: Filtration) -> bool:
    """Whether exact arithmetic at the filtration's point would carry transcendental values.

    True when the point has floats, or the values at $p$ of the fields or of the
    frame words contain function values (``cos(1/5)``, ``exp(1)``) that exact
    arithmetic cannot simplify.
    """
    p = filtration.point
    if any(isinstance(v, sp.Float) or v.atoms(sp.Float) for v in p):
        return True
    at = dict(zip(filtration.system.coordinates, p, strict=True))
    values = [v for f in filtration.frame_values for v in f]
    values += [e.xreplace(at) for f in filtration.system.specialized_fields for e in f]
    return any(v.atoms(sp.Function) or v.atoms(sp.Float) for v in values)


SERIES_METHODS = ("exponential", "exponential-1")
"""Methods whose forward map is a series inverse: exact irrational coefficients swell there."""

EXACT_TRIAL_BUDGET = 10.0
"""Seconds the exponential methods try exact arithmetic at an exact point with irrational
values (with ``numeric=None``) before they work in floating point instead (CPU seconds)."""


def rational_values(filtration: Filtration) -> bool:
    r"""Whether the frame values and the fields' values at the point are rational.

    The point itself may be irrational (``theta = pi/2``: ``cos`` and ``sin`` of it
    are rational).

    At an exact point with irrational algebraic values (``sqrt(3)/2`` at
    $\alpha = \pi/3$) the series inverse of the exponential methods carries
    coefficients in a number field and can run for many minutes: there they work
    in floating point (with the same certificate), as at a decimal point, at once
    from step 3, after :data:`EXACT_TRIAL_BUDGET` seconds of exact arithmetic at
    step 2.
    """
    p = filtration.point
    at = dict(zip(filtration.system.coordinates, p, strict=True))
    values = [v for f in filtration.frame_values for v in f]
    values += [e.xreplace(at) for f in filtration.system.specialized_fields for e in f]
    return all(exact_value(v) is not None for v in values)
