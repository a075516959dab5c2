"""Triangular polynomial systems: the float form of a nilpotent approximation.

In privileged coordinates ``y`` with weights ``w_1 ≤ … ≤ w_n`` the fields of a
nilpotent approximation are ``X̂_i = Σ_j P_ij(y) ∂/∂y_j`` with ``P_ij`` weighted
homogeneous of weighted degree ``w_j − 1`` (the mathematics page, §5).  Hence ``P_ij`` only
involves coordinates of weight ``< w_j`` (weight-1 components are constants):
the system is *triangular*, and its flow under explicit inputs is computed by
successive quadratures (:mod:`nilpotent.planning.exact_flow`).

:class:`TriangularSystem` stores the ``P_ij`` as float coefficients and
exponent vectors, checked to be triangular when built.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp

from nilpotent.core.model.expressions import as_expr
from nilpotent.errors import PlanningError

Term = tuple[float, tuple[int, ...]]  # (coefficient, exponent of y_1..y_n)


@dataclass(frozen=True)
class TriangularSystem:
    """Polynomial fields ``X̂_i = Σ_j P_ij(y) ∂/∂y_j`` with a triangular structure.

    Parameters
    ----------
    names:
        Coordinate names ``y1..yn`` (for messages only).
    weights:
        ``w_j``; ``P_ij`` may only involve coordinates of weight ``< w_j``.
    terms:
        ``terms[i][j]`` is the tuple of ``(coefficient, exponents)`` of ``P_ij``
        (0-based: field ``X̂_{i+1}``, coordinate ``y_{j+1}``).

    Examples
    --------
    The Heisenberg system ``X̂1 = ∂1 − y2/2 ∂3``, ``X̂2 = ∂2 + y1/2 ∂3``:

    >>> import sympy as sp
    >>> y1, y2, y3 = sp.symbols("y1 y2 y3")
    >>> h = TriangularSystem.from_fields(
    ...     ((1, 0, -y2 / 2), (0, 1, y1 / 2)), (y1, y2, y3), (1, 1, 2))
    >>> h.n, h.m, h.step
    (3, 2, 2)
    """

    names: tuple[str, ...]
    weights: tuple[int, ...]
    terms: tuple[tuple[tuple[Term, ...], ...], ...]

    def __post_init__(self) -> None:
        n = len(self.weights)
        if len(self.names) != n:
            raise PlanningError("triangular system: one name per weight needed")
        if any(w < 1 for w in self.weights):
            raise PlanningError(f"triangular system: weights must be >= 1, got {self.weights}")
        for i, comps in enumerate(self.terms):
            if len(comps) != n:
                raise PlanningError(f"triangular system: field {i + 1} has {len(comps)} components")
            for j, poly in enumerate(comps):
                for _, exps in poly:
                    if len(exps) != n:
                        raise PlanningError("triangular system: exponent vector of wrong length")
                    bad = [
                        self.names[k]
                        for k, e in enumerate(exps)
                        if e and self.weights[k] >= self.weights[j]
                    ]
                    if bad:
                        raise PlanningError(
                            f"the fields are not triangular: component {self.names[j]} of "
                            f"X{i + 1} depends on {', '.join(bad)} (weight >= {self.weights[j]}); "
                            "exact steering needs a nilpotent approximation in privileged "
                            "coordinates"
                        )

    @property
    def n(self) -> int:
        return len(self.weights)

    @property
    def m(self) -> int:
        return len(self.terms)

    @property
    def step(self) -> int:
        """The largest weight (the nilpotency step for an approximation)."""
        return max(self.weights)

    @property
    def order(self) -> tuple[int, ...]:
        """Coordinate indices sorted by weight (the order of the quadratures)."""
        return tuple(sorted(range(self.n), key=lambda j: (self.weights[j], j)))

    @classmethod
    def from_fields(
        cls,
        fields: Sequence[Sequence[object]],
        names: Sequence[sp.Symbol],
        weights: Sequence[int],
    ) -> TriangularSystem:
        """Build from sympy polynomial fields in ``names``.

        ``fields[i][j]`` is the ``y_j``-component of ``X̂_i``.
        """
        syms = tuple(names)
        terms = []
        for i, comps in enumerate(fields):
            row = []
            for j, expr in enumerate(comps):
                e = sp.expand(as_expr(expr))
                if e == 0:
                    row.append(())
                    continue
                try:
                    poly = sp.Poly(e, *syms)
                except sp.PolynomialError:
                    raise PlanningError(
                        f"component {syms[j]} of X{i + 1} is not a polynomial in "
                        f"{', '.join(map(str, syms))}: {e}"
                    ) from None
                bad = [c for c in poly.coeffs() if not c.is_number]
                if bad:
                    raise PlanningError(
                        f"component {syms[j]} of X{i + 1} has a non-numeric coefficient {bad[0]}"
                    )
                row.append(tuple((float(c), tuple(int(k) for k in mon)) for mon, c in poly.terms()))
            terms.append(tuple(row))
        return cls(tuple(str(s) for s in syms), tuple(int(w) for w in weights), tuple(terms))

    def weight_one_matrix(self) -> np.ndarray:
        """``B[a, i]``: the (constant) component of X̂_i along the a-th weight-1 coordinate."""
        w1 = [j for j in range(self.n) if self.weights[j] == 1]
        out = np.zeros((len(w1), self.m))
        for i in range(self.m):
            for a, j in enumerate(w1):
                out[a, i] = sum(c for c, _ in self.terms[i][j])
        return out

    def field_values(self, y: np.ndarray) -> np.ndarray:
        """The matrix ``[X̂_1(y) … X̂_m(y)]`` (shape ``(n, m)``) at a float point."""
        y = np.asarray(y, dtype=float)
        out = np.zeros((self.n, self.m))
        for i in range(self.m):
            for j in range(self.n):
                out[j, i] = sum(c * float(np.prod(y**np.array(e))) for c, e in self.terms[i][j])
        return out

    def velocity(self, y: np.ndarray, u: np.ndarray) -> np.ndarray:
        """``Σ_i u_i X̂_i(y)``."""
        return self.field_values(y) @ np.asarray(u, dtype=float)

    def dilate(self, y: np.ndarray, factor: float) -> np.ndarray:
        """``δ_λ y = (λ^{w_1} y_1, …, λ^{w_n} y_n)``."""
        return np.asarray(y, dtype=float) * factor ** np.asarray(self.weights, dtype=float)

    def quasi_norm(self, y: np.ndarray) -> float:
        """The homogeneous quasi-norm ``max_j |y_j|^{1/w_j}`` (``‖δ_λ y‖ = λ‖y‖``)."""
        y = np.asarray(y, dtype=float)
        w = np.asarray(self.weights, dtype=float)
        return float(np.max(np.abs(y) ** (1.0 / w))) if y.size else 0.0
