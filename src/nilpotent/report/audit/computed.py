"""The computed side of the audit: the models, filtrations, approximation and simulations.

Every object is built lazily and once per audit run (:class:`Computed`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import cached_property

import sympy as sp

from nilpotent.core.lie.brackets import bracket
from nilpotent.core.model.expressions import as_expr
from nilpotent.core.model.system import ControlSystem
from nilpotent.report.audit.compare import at_origin, push_forward, weighted_part
from nilpotent.report.paper import PaperContent, X, Y

__all__ = ["Computed"]


class Computed:
    """The computed side, built lazily (each object once)."""

    def __init__(self, paper: PaperContent) -> None:
        self.paper = paper

    @cached_property
    def body(self) -> ControlSystem:
        from nilpotent.models import get_model

        model = get_model("trident-snake", {"r": sp.Integer(1), "l": sp.Integer(1)}).specialized()
        # the paper's names: (x, y, θ, φ1, φ2, φ3) =: (x1, ..., x6)
        rename = dict(zip(model.coordinates, X, strict=True))
        fields = tuple(tuple(as_expr(v.xreplace(rename)) for v in f) for f in model.fields)
        return ControlSystem(model.name, X, fields, (), model.description)

    @cached_property
    def vf(self) -> ControlSystem:
        from nilpotent.models import get_model

        return get_model("trident-snake-paper").specialized()

    def bracket_at_origin(self, sys: ControlSystem, i: int, j: int) -> tuple[sp.Expr, ...]:
        key = (sys.name, i, j)
        cache = self.__dict__.setdefault("_brackets", {})
        if key not in cache:
            f = sys.specialized_fields
            cache[key] = at_origin(bracket(f[i - 1], f[j - 1], sys.coordinates), sys.coordinates)
        return cache[key]

    @cached_property
    def body_filtration(self):
        from nilpotent.core.analysis.filtration import analyze

        return analyze(self.body)

    @cached_property
    def vf_filtration(self):
        from nilpotent.core.analysis.filtration import analyze

        return analyze(self.vf)

    @cached_property
    def approximation(self):
        from nilpotent.core.coordinates.approximation import approximate

        return approximate(self.vf)

    def frame_matrix(self, labels: dict[int, tuple[int, int]], sys: ControlSystem) -> sp.Matrix:
        """Columns ``g1(0) .. g6(0)``, ``g_k = [g_i, g_j]`` as ``labels`` names them."""
        cols = [at_origin(f, sys.coordinates) for f in sys.specialized_fields]
        cols += [self.bracket_at_origin(sys, *labels[k]) for k in (4, 5, 6)]
        return sp.Matrix(cols).T

    @cached_property
    def paper_y_fields(self) -> tuple[tuple[sp.Expr, ...], ...]:
        """eq. (vf) written in the paper's coordinates ``y = M x`` (exact pushforward)."""
        m = self.paper.privileged_matrix
        inverse = dict(zip(X, list(m.inv() * sp.Matrix(Y)), strict=True))
        return push_forward(self.vf.specialized_fields, sp.Matrix(m), X, inverse)

    @cached_property
    def paper_y_truncation(self) -> tuple[tuple[sp.Expr, ...], ...]:
        """Terms of weighted degree ``w_j − 1`` of eq. (vf) in the paper's ``y``."""
        w = self.paper.weights
        return tuple(
            tuple(weighted_part(c, Y, w, w[j] - 1) for j, c in enumerate(f))
            for f in self.paper_y_fields
        )

    @cached_property
    def paper_y_low_terms(self) -> tuple[tuple[sp.Expr, ...], ...]:
        """Terms of weighted degree ``< w_j − 1`` (nonzero only for non-privileged ``y``)."""
        w = self.paper.weights
        return tuple(
            tuple(
                sp.Add(*[weighted_part(c, Y, w, d) for d in range(w[j] - 1)])
                for j, c in enumerate(f)
            )
            for f in self.paper_y_fields
        )

    def displacement_rate(self, sys: ControlSystem, i: int, j: int) -> tuple[float, ...]:
        """``Δx / (πA²)`` over one period of the ``(i, j)`` periodic input, extrapolated to A → 0.

        One-period simulations (:func:`nilpotent.simulation.simulate`) at
        ``A = 0.02`` and ``0.01`` from the origin (adaptive DOP853, rtol 1e-12);
        since ``Δx/(πA²) = [X_i,X_j](0) + c A + O(A²)``, the Richardson
        combination ``2 r(A/2) − r(A)`` removes the ``O(A)`` term.
        """
        from nilpotent.numeric import compile_system
        from nilpotent.numeric.signals import bracket_signal
        from nilpotent.simulation import simulate

        key = (sys.name, i, j)
        cache = self.__dict__.setdefault("_rates", {})
        if key not in cache:
            compiled = compile_system(sys, backend="numpy")
            rates = []
            for amp in (0.02, 0.01):
                run = simulate(
                    compiled, bracket_signal(sys.m, i, j, amp), samples=2, rtol=1e-12, atol=1e-14
                )
                assert run.final is not None  # two samples were asked for
                rates.append(run.final / (math.pi * amp**2))
            cache[key] = tuple(float(v) for v in 2 * rates[1] - rates[0])
        return cache[key]

    def linear_order(self, row: sp.Matrix) -> float:
        """Non-holonomic order at 0 of the linear function ``row · x`` for eq. vf."""
        from nilpotent.core.coordinates.orders import function_order

        return function_order(self.vf, as_expr(sum(row[j] * X[j] for j in range(6))), None, 4)

    def field_order(self, field: Sequence[sp.Expr]) -> float:
        """Non-holonomic order at 0 of a vector field on eq. vf's space (the mathematics page, §3).

        In privileged coordinates ``z`` (approximate()'s), ``ord(Z) = min_j ord(Z z_j) − w_j``.
        """
        from nilpotent.core.coordinates.orders import function_order

        z = self.approximation.coordinates.forward
        weights = self.vf_filtration.weights
        out = math.inf
        for zj, wj in zip(z, weights, strict=True):
            f = sp.expand(sum(as_expr(field[k]) * sp.diff(zj, X[k]) for k in range(6)))
            out = min(out, function_order(self.vf, f, None, wj + 2) - wj)
        return out
