"""Closed-form flow of a triangular polynomial system under sinusoidal inputs.

Within a :class:`~nilpotent.planning.controls.Segment` every input is a
trigonometric polynomial ``Σ_k c_k e^{ikωt}``.  For a
:class:`~nilpotent.planning.triangular.TriangularSystem`
``ẏ_j = Σ_i u_i(t) P_ij(y_{<w_j})``, so taking the coordinates in increasing
weight each ``y_j(t)`` is ``y_j(0)`` plus the integral of a product of known
functions of the form ``Σ_{p,k} c_{pk} t^p e^{ikωt}`` ("quasi-polynomials"),
which stays in that class:

.. math::

    \\int_0^t s^p e^{\\lambda s}\\,ds = e^{\\lambda t}\\sum_{q=0}^p
    \\frac{(-1)^{p-q} p!}{q!\\,\\lambda^{p-q+1}} t^q - \\frac{(-1)^p p!}{\\lambda^{p+1}}
    \\quad(\\lambda = ik\\omega \\ne 0),
    \\qquad \\int_0^t s^p\\,ds = \\frac{t^{p+1}}{p+1}.

The endpoint is therefore computed exactly up to floating-point rounding (no
time stepping).  The same arithmetic carries first derivatives with respect to
the input coefficients (forward-mode, a trailing "dual" axis), which gives the
exact Jacobian of the endpoint map used by the Newton steering of
:mod:`nilpotent.planning.nilpotent`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from nilpotent.errors import PlanningError
from nilpotent.numeric.types import State
from nilpotent.planning.controls import Segment
from nilpotent.planning.triangular import TriangularSystem


class QuasiPolynomial:
    """``f(t) = Σ_{p=0}^{D} Σ_{k=-L}^{L} c[p, k+L, :] t^p e^{ikωt}`` with a dual axis.

    ``c[..., 0]`` holds the value, ``c[..., 1:]`` derivatives with respect to
    parameters (forward mode).  Complex coefficients; real functions have
    conjugate-symmetric ones.
    """

    __slots__ = ("c", "half_width")

    def __init__(self, c: np.ndarray) -> None:
        self.c = c
        self.half_width = (c.shape[1] - 1) // 2

    @classmethod
    def constant(cls, value: np.ndarray) -> QuasiPolynomial:
        value = np.asarray(value, dtype=complex)
        return cls(value.reshape(1, 1, -1).copy())

    @property
    def degree(self) -> int:
        return self.c.shape[0] - 1

    def _padded(self, degree: int, half_width: int) -> np.ndarray:
        if degree == self.degree and half_width == self.half_width:
            return self.c
        out = np.zeros((degree + 1, 2 * half_width + 1, self.c.shape[2]), dtype=complex)
        off = half_width - self.half_width
        out[: self.degree + 1, off : off + self.c.shape[1]] = self.c
        return out

    def __add__(self, other: QuasiPolynomial) -> QuasiPolynomial:
        d = max(self.degree, other.degree)
        h = max(self.half_width, other.half_width)
        return QuasiPolynomial(self._padded(d, h) + other._padded(d, h))

    def scaled(self, factor: float) -> QuasiPolynomial:
        return QuasiPolynomial(self.c * factor)

    def __mul__(self, other: QuasiPolynomial) -> QuasiPolynomial:
        f, g = (self, other) if self.c[..., 0].size <= other.c[..., 0].size else (other, self)
        fd, gd = f.c.shape[0], g.c.shape[0]
        fw, gw = f.c.shape[1], g.c.shape[1]
        dual = f.c.shape[2]
        out = np.zeros((fd + gd - 1, fw + gw - 1, dual), dtype=complex)
        g0 = g.c[..., 0]
        g1 = g.c[..., 1:]
        nz = np.argwhere(np.any(f.c != 0, axis=2))
        for p1, k1 in nz:
            fv = f.c[p1, k1]
            block = out[p1 : p1 + gd, k1 : k1 + gw]
            block[..., 0] += fv[0] * g0
            if dual > 1:
                block[..., 1:] += fv[0] * g1 + fv[1:][None, None, :] * g0[..., None]
        return QuasiPolynomial(out)

    def integral(self, omega: float) -> QuasiPolynomial:
        """``t ↦ ∫_0^t f(s) ds`` (closed form, see the module docstring)."""
        d, h = self.degree, self.half_width
        out = np.zeros((d + 2, 2 * h + 1, self.c.shape[2]), dtype=complex)
        ks = np.arange(-h, h + 1)
        nonzero = ks != 0
        lam = 1j * ks[nonzero] * omega
        for p in range(d + 1):
            cp = self.c[p]  # (2h+1, dual)
            # k = 0: t^p -> t^{p+1}/(p+1)
            out[p + 1, h] += cp[h] / (p + 1)
            if not nonzero.any():
                continue
            cpk = cp[nonzero]  # (K, dual)
            for q in range(p + 1):
                coef = (-1) ** (p - q) * math.factorial(p) / math.factorial(q) / lam ** (p - q + 1)
                out[q, nonzero] += coef[:, None] * cpk
            coef0 = (-1) ** p * math.factorial(p) / lam ** (p + 1)
            out[0, h] -= (coef0[:, None] * cpk).sum(axis=0)
        return QuasiPolynomial(out)

    def at(self, t: float, omega: float) -> np.ndarray:
        """``f(t)`` (value and derivatives, real part), shape ``(dual,)``."""
        h = self.half_width
        phase = np.exp(1j * omega * t * np.arange(-h, h + 1))
        powers = t ** np.arange(self.degree + 1)
        return np.einsum("p,k,pkd->d", powers, phase, self.c).real

    def at_many(self, times: np.ndarray, omega: float) -> np.ndarray:
        """Values (dual index 0) at several times, shape ``(len(times),)``."""
        times = np.asarray(times, dtype=float)
        h = self.half_width
        phase = np.exp(1j * omega * np.outer(times, np.arange(-h, h + 1)))
        powers = times[:, None] ** np.arange(self.degree + 1)[None, :]
        return np.einsum("tp,tk,pk->t", powers, phase, self.c[..., 0]).real


def input_quasipolynomials(
    segment: Segment, dual: int = 1, offsets: Sequence[int] | None = None
) -> list[QuasiPolynomial]:
    """The inputs of a segment as quasi-polynomials.

    With ``offsets`` (one per input) the coefficients of input ``i`` are
    parameters ``offsets[i] + (0: constant, 1..K: cos, K+1..2K: sin)`` of the
    dual axis (``K`` the input's number of harmonics, padded to the segment's).
    """
    harmonics = max((s.harmonics for s in segment.inputs), default=0)
    out = []
    for i, s in enumerate(segment.inputs):
        c = np.zeros((1, 2 * harmonics + 1, dual), dtype=complex)
        h = harmonics
        c[0, h, 0] = s.constant
        for k, a in enumerate(s.cos, start=1):
            c[0, h + k, 0] += a / 2
            c[0, h - k, 0] += a / 2
        for k, b in enumerate(s.sin, start=1):
            c[0, h + k, 0] += -1j * b / 2
            c[0, h - k, 0] += 1j * b / 2
        if offsets is not None:
            base = offsets[i]
            c[0, h, 1 + base] = 1.0
            for k in range(1, harmonics + 1):
                c[0, h + k, 1 + base + k] = 0.5
                c[0, h - k, 1 + base + k] = 0.5
                c[0, h + k, 1 + base + harmonics + k] = -0.5j
                c[0, h - k, 1 + base + harmonics + k] = 0.5j
        out.append(QuasiPolynomial(c))
    return out


def _segment_solution(
    system: TriangularSystem,
    y0: np.ndarray,
    inputs: list[QuasiPolynomial],
    omega: float,
) -> list[QuasiPolynomial]:
    """``y_j(t)`` as quasi-polynomials; ``y0`` has shape ``(n, dual)``."""
    n = system.n
    sol: list[QuasiPolynomial | None] = [None] * n
    monomials: dict[tuple[int, ...], QuasiPolynomial] = {}
    dual = y0.shape[1]

    def monomial(exps: tuple[int, ...]) -> QuasiPolynomial:
        if exps in monomials:
            return monomials[exps]
        total = sum(exps)
        if total == 0:
            one = np.zeros(dual)
            one[0] = 1.0
            res = QuasiPolynomial.constant(one)
        else:
            k = max(j for j, e in enumerate(exps) if e)
            lower = list(exps)
            lower[k] -= 1
            res = monomial(tuple(lower)) * sol[k]  # type: ignore[operator]
        monomials[exps] = res
        return res

    for j in system.order:
        integrand: QuasiPolynomial | None = None
        for i in range(system.m):
            poly = system.terms[i][j]
            if not poly:
                continue
            p_ij: QuasiPolynomial | None = None
            for coef, exps in poly:
                term = monomial(exps).scaled(coef)
                p_ij = term if p_ij is None else p_ij + term
            contrib = inputs[i] * p_ij  # type: ignore[operator]
            integrand = contrib if integrand is None else integrand + contrib
        y = QuasiPolynomial.constant(y0[j])
        if integrand is not None:
            y = y + integrand.integral(omega)
        sol[j] = y
    return sol  # type: ignore[return-value]


def endpoint(
    system: TriangularSystem, y0: Sequence[float] | State, segments: Sequence[Segment]
) -> np.ndarray:
    """The state reached from ``y0`` under ``segments`` (closed form)."""
    y = np.asarray(y0, dtype=float).reshape(-1, 1)
    for seg in segments:
        sol = _segment_solution(system, y, input_quasipolynomials(seg), seg.omega)
        y = np.array([s.at(seg.duration, seg.omega) for s in sol])
    return y[:, 0].copy()


def endpoint_and_jacobian(
    system: TriangularSystem,
    y0: Sequence[float] | State,
    segments: Sequence[Segment],
    harmonics: Sequence[int],
) -> tuple[np.ndarray, np.ndarray]:
    """Endpoint and its Jacobian with respect to every input coefficient.

    Segment ``s`` contributes ``m·(2·harmonics[s]+1)`` parameters, input by
    input: constant, ``cos`` 1..K, ``sin`` 1..K (coefficients beyond an input's
    own length count as 0).  Returns ``(y(T), J)`` with ``J`` of shape
    ``(n, P)``.
    """
    m = system.m
    sizes = [m * (2 * k + 1) for k in harmonics]
    total = int(sum(sizes))
    y = np.zeros((system.n, total + 1))
    y[:, 0] = np.asarray(y0, dtype=float)
    start = 0
    for seg, k, size in zip(segments, harmonics, sizes, strict=True):
        if max((s.harmonics for s in seg.inputs), default=0) > k:
            raise PlanningError(f"a segment has more harmonics than the {k} declared")
        padded = Segment(
            seg.duration,
            seg.omega,
            tuple(
                type(s)(s.constant, tuple(s.cos) + (0.0,) * (k - len(s.cos)),
                        tuple(s.sin) + (0.0,) * (k - len(s.sin)))
                for s in seg.inputs
            ),
        )
        offsets = [start + i * (2 * k + 1) for i in range(m)]
        sol = _segment_solution(
            system, y.astype(complex), input_quasipolynomials(padded, total + 1, offsets), seg.omega
        )
        y = np.array([s.at(seg.duration, seg.omega) for s in sol])
        start += size
    return y[:, 0].copy(), y[:, 1:].copy()


def sample(
    system: TriangularSystem,
    y0: Sequence[float],
    segments: Sequence[Segment],
    points_per_segment: int = 50,
) -> tuple[np.ndarray, np.ndarray]:
    """The exact trajectory sampled in every segment: ``(times, states)``, states ``(N, n)``."""
    y = np.asarray(y0, dtype=float).reshape(-1, 1)
    times = [np.zeros(1)]
    states = [y[:, 0][None, :]]
    t0 = 0.0
    for seg in segments:
        sol = _segment_solution(system, y, input_quasipolynomials(seg), seg.omega)
        ts = np.linspace(0.0, seg.duration, points_per_segment + 1)[1:]
        states.append(np.stack([s.at_many(ts, seg.omega) for s in sol], axis=1))
        times.append(t0 + ts)
        y = np.array([s.at(seg.duration, seg.omega) for s in sol])
        t0 += seg.duration
    return np.concatenate(times), np.concatenate(states)
