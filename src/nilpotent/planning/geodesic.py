r"""Shortest steering of step-2 nilpotent systems: normal sub-Riemannian geodesics.

The metric makes ``X̂_1..X̂_m`` orthonormal: the length of a control is
``∫‖u(t)‖₂ dt``.  A step-2 nilpotent approximation in privileged coordinates
``y = (h, v)`` (weights 1 and 2) has the form

.. math::

    \dot h = B u, \qquad \dot v = \sum_i u_i A_i h,

``B`` (``n₁×m``) the constant weight-1 components, ``A_i`` (``n₂×n₁``) the
linear weight-2 components of ``X̂_i`` (the mathematics page, §5: ``P_ij`` is homogeneous of
weighted degree ``w_j − 1``).

**Normal geodesics** (Pontryagin, ``H = ½Σ_i u_i²``, ``u_i = ⟨p, X̂_i(y)⟩``):
``v`` does not enter ``H``, so the vertical covector ``p_v = λ`` is constant, and

.. math::

    \dot u_i = \dot p_h\cdot b_i + λ\cdot A_i\dot h
             = \sum_k λ\cdot(A_i b_k - A_k b_i)\,u_k,

i.e. ``u(t) = e^{tΩ}u₀`` with the skew matrix ``Ω_ik = λ·(A_i b_k − A_k b_i)``
(``A_i b_k − A_k b_i`` is the weight-2 part of the bracket ``[X̂_k, X̂_i]`` in the
convention ``[X,Y] = DY·X − DX·Y``).  ``‖u(t)‖ = ‖u₀‖``: on ``[0, 1]`` the length
is ``‖u₀‖``.

**Endpoint in closed form.** With ``U(t) = ∫₀ᵗ u``, ``h(1) = h₀ + B U(1)`` and
``v(1) = v₀ + Σ_i U_i(1) A_i h₀ + Σ_{ij} M_ij A_i b_j``, ``M_ij = ∫₀¹ u_i U_j dt``.
``z = (u, U)`` solves the linear ODE ``ż = F z``, ``F = [[Ω, 0], [I, 0]]``, so
``M`` is a block of ``G = ∫₀¹ e^{tF} z₀z₀ᵀ e^{tFᵀ} dt``, which Van Loan's block
exponential gives exactly: ``exp([[−F, z₀z₀ᵀ], [0, Fᵀ]]) = [[e^{−F}, e^{−F}G], [0, e^{Fᵀ}]]``.
No time stepping.  For ``m ≤ 3`` the same ``U(1)`` and ``M`` come in closed form
from Rodrigues' formula (:mod:`nilpotent.planning.geodesic_forms`: nine scalar
functions of ``θ²``), much cheaper than the block exponential, which is kept
for ``m ≥ 4``.  The Jacobian in ``(u₀, λ)`` is exact too (complex step: the map
is real-analytic and built without conjugation), batched.

**Boundary problem.**  Find ``(u₀, λ)`` with ``y(1) = goal``: Levenberg–Marquardt
(minimum-norm steps) on the problem dilated to unit size (``δ_λ`` maps
geodesics to geodesics, lengths scale by ``λ``), from near-exact starts where a
closed form exists:

* two inputs and one vertical coordinate (Heisenberg up to a linear change:
  the unicycle's and the Heisenberg system's approximations): the minimiser is
  a circular arc whose area with the chord gives the vertical displacement;
* three inputs and three vertical coordinates spanning the brackets (the free
  (3,6) group up to a linear change: the trident snake's approximation): the
  rotations reduce the six equations to two in the axis angle and the rotation
  angle, whose solutions are all sought (a scan, the helix limit, Newton) and
  the three shortest polished
  (:func:`~nilpotent.planning.geodesic_forms.free3_starts`).

Otherwise, or if those do not converge, a multi-start: the straight segment
``u₀ = B⁺Δh, λ = 0`` (exact when the goal's vertical part is what the straight
line gives), and covectors along ``±`` the remaining vertical displacement with
rotation angles ``‖Ω‖ ∈ {π, 1.9π}``.  The shortest converged extremal is kept.

Its controls ``e^{tΩ}u₀`` are harmonic: for
``m ≤ 3`` the skew ``Ω`` has one frequency ``θ`` and, by Rodrigues' formula,
``u(t) = (u₀ + Ω²u₀/θ²) − cos(θt)·Ω²u₀/θ² + sin(θt)·Ωu₀/θ``: one
:class:`~nilpotent.numeric.signals.Segment` of duration 1 and ``omega = θ``,
carried exactly by the plan format.  (``m ≥ 4`` with several frequencies is
refused.)

What is *not* claimed: that a normal extremal found is the global minimiser in
every step-2 group (strictly abnormal minimisers exist in some step-2 Carnot
groups, Golé–Karidi 1995).  For the Heisenberg group the result is checked
against the closed-form distance, for the free (3,6) group against closed forms
(goals with ``x ⊥ w``, vertical goals) and a brute multi-start (tests).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from nilpotent.errors import PlanningError
from nilpotent.numeric.signals import InputSignal, Segment
from nilpotent.numeric.types import State
from nilpotent.planning.geodesic_forms import free3_maps, free3_starts, rodrigues_integrals
from nilpotent.planning.triangular import TriangularSystem

__all__ = [
    "Geodesic", "Step2Structure", "control_length", "geodesic_segments", "shortest_geodesic",
]

#: Endpoint accuracy asked of the boundary problem, relative to the unit-size dilated problem.
UNIT_TOL = 1e-13
#: Complex-step size (exact derivatives to rounding for analytic maps).
_CSTEP = 1e-30
#: Rotation angles ``‖Ω‖`` of the curved starting guesses.
_START_ANGLES = (math.pi, 1.9 * math.pi)


@dataclass(frozen=True)
class Step2Structure:
    """The matrices of a step-2 nilpotent system ``ḣ = Bu, v̇ = Σ u_i A_i h``.

    Attributes
    ----------
    h_index, v_index : tuple of int
        Indices of the weight-1 and weight-2 coordinates in ``y``.
    b : numpy.ndarray
        ``B``, shape ``(n₁, m)``.
    a : numpy.ndarray
        ``a[k, i, l]``: coefficient of ``h_l`` in the ``v_k``-component of ``X̂_i``.
    t : numpy.ndarray
        ``t[k, i, j] = (A_i b_j)_k``.
    skew : numpy.ndarray
        ``skew[k] = t[k] − t[k]ᵀ``: ``Ω = Σ_k λ_k skew[k]``.
    """

    h_index: tuple[int, ...]
    v_index: tuple[int, ...]
    b: np.ndarray
    a: np.ndarray
    t: np.ndarray
    skew: np.ndarray

    @functools.cached_property
    def free3_maps(self) -> tuple[np.ndarray, ...] | None:
        """:func:`~nilpotent.planning.geodesic_forms.free3_maps` (``None``: not of that type)."""
        return free3_maps(self.b, self.skew)

    @property
    def m(self) -> int:
        """Number of inputs."""
        return int(self.b.shape[1])

    @classmethod
    def from_triangular(cls, system: TriangularSystem) -> Step2Structure:
        """Read ``B`` and ``A_i`` from the polynomial fields.

        Parameters
        ----------
        system : TriangularSystem
            Weights 1 and 2 only; weight-1 components constant, weight-2 ones
            linear in the weight-1 coordinates.

        Returns
        -------
        Step2Structure

        Raises
        ------
        PlanningError
            The system is not of step ≤ 2, or a component is not of the
            homogeneous form above.
        """
        if system.step > 2:
            raise PlanningError(
                f"shortest steering (objective 'length') is implemented for step <= 2; "
                f"this nilpotent approximation has step {system.step}"
            )
        h_index = tuple(j for j in range(system.n) if system.weights[j] == 1)
        v_index = tuple(j for j in range(system.n) if system.weights[j] == 2)
        pos = {j: q for q, j in enumerate(h_index)}
        n1, n2, m = len(h_index), len(v_index), system.m
        b = np.zeros((n1, m))
        a = np.zeros((n2, m, n1))
        for i in range(m):
            for q, j in enumerate(h_index):
                for c, e in system.terms[i][j]:
                    if any(e):
                        raise PlanningError("a weight-1 component is not constant")
                    b[q, i] += c
            for k, j in enumerate(v_index):
                for c, e in system.terms[i][j]:
                    if sum(e) != 1 or any(e[jj] for jj in v_index):
                        raise PlanningError(
                            "a weight-2 component is not linear in the weight-1 coordinates"
                        )
                    a[k, i, pos[e.index(1)]] += c
        t = np.einsum("kil,lj->kij", a, b)
        return cls(h_index, v_index, b, a, t, t - np.transpose(t, (0, 2, 1)))

    def endpoints(self, y0: np.ndarray, u0: np.ndarray, lam: np.ndarray) -> np.ndarray:
        """``y(1)`` of the extremals ``u = e^{tΩ(λ)}u₀`` from ``y0``, batched.

        Parameters
        ----------
        y0 : numpy.ndarray
            Start, shape ``(n,)``.
        u0 : numpy.ndarray
            Shape ``(B, m)``, real or complex.
        lam : numpy.ndarray
            Shape ``(B, n₂)``, same dtype.

        Returns
        -------
        numpy.ndarray
            Shape ``(B, n)``.
        """
        omega = np.einsum("bk,kij->bij", lam, self.skew)
        integrals = rodrigues_integrals if self.m <= 3 else _van_loan_integrals
        u_int, mm = integrals(omega, u0)
        h0 = y0[list(self.h_index)]
        out = np.tile(y0.astype(u0.dtype), (u0.shape[0], 1))
        out[:, list(self.h_index)] += u_int @ self.b.T
        out[:, list(self.v_index)] += np.einsum("kil,l,bi->bk", self.a, h0, u_int)
        out[:, list(self.v_index)] += np.einsum("kij,bij->bk", self.t, mm)
        return out

    def endpoint_and_jacobian(
        self, y0: np.ndarray, params: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """``y(1)`` and its exact Jacobian in ``params = (u₀, λ)`` (complex step), batched.

        Parameters
        ----------
        y0 : numpy.ndarray
            Start, shape ``(n,)``.
        params : numpy.ndarray
            Rows ``(u₀, λ)``, shape ``(S, m + n₂)``.

        Returns
        -------
        value, jacobian : numpy.ndarray
            Shapes ``(S, n)`` and ``(S, n, m + n₂)``.
        """
        n_s, d = params.shape
        pts = np.repeat(params.astype(complex)[:, None, :], d + 1, axis=1)
        pts[:, 1:, :] += 1j * _CSTEP * np.eye(d)
        pts = pts.reshape(n_s * (d + 1), d)
        ends = self.endpoints(y0, pts[:, : self.m], pts[:, self.m :]).reshape(n_s, d + 1, -1)
        return np.real(ends[:, 0]), np.transpose(np.imag(ends[:, 1:]) / _CSTEP, (0, 2, 1))


@dataclass(frozen=True)
class Geodesic:
    """A normal geodesic of a step-2 nilpotent system on ``[0, 1]``.

    Attributes
    ----------
    u0 : tuple of float
        Initial control; the length is ``‖u₀‖``.
    covector : tuple of float
        The vertical covector ``λ`` (``Ω = Σ_k λ_k [X̂_·, X̂_·]_k``).
    length : float
        ``‖u₀‖`` (the control has constant norm).
    reached : tuple of float
        Endpoint (closed form).
    error : float
        ``‖reached − goal‖_∞``.
    starts_converged : int
        How many starting guesses converged (the shortest was kept).
    """

    u0: tuple[float, ...]
    covector: tuple[float, ...]
    length: float
    reached: tuple[float, ...]
    error: float
    starts_converged: int


def _van_loan_integrals(omega: np.ndarray, u0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``U(1) = ∫₀¹u`` and ``M = ∫₀¹ u Uᵀ`` for ``u = e^{tΩ}u₀`` (any m): Van Loan's block
    exponential of ``[[−F, z₀z₀ᵀ], [0, Fᵀ]]``, ``F = [[Ω, 0], [I, 0]]``."""
    m = omega.shape[-1]
    batch = u0.shape[0]
    f = np.zeros((batch, 2 * m, 2 * m), dtype=u0.dtype)
    f[:, :m, :m] = omega
    f[:, m:, :m] = np.eye(m)
    z0 = np.zeros((batch, 2 * m), dtype=u0.dtype)
    z0[:, :m] = u0
    # the off-diagonal block enters linearly: scaled to unit size, it does not
    # inflate the norm (hence the squarings) of the block exponential
    q = z0[:, :, None] * z0[:, None, :]
    q_scale = max(float(np.max(np.abs(q))), 1e-300)
    c = np.zeros((batch, 4 * m, 4 * m), dtype=u0.dtype)
    c[:, : 2 * m, : 2 * m] = -f
    c[:, : 2 * m, 2 * m :] = q / q_scale
    c[:, 2 * m :, 2 * m :] = np.transpose(f, (0, 2, 1))
    e = _expm(c)
    ef = np.transpose(e[:, 2 * m :, 2 * m :], (0, 2, 1))  # e^{F}
    g = (ef @ e[:, : 2 * m, 2 * m :]) * q_scale
    return np.einsum("bij,bj->bi", ef, z0)[:, m:], g[:, :m, m:]


def _lm(
    st: Step2Structure, y0: np.ndarray, yg: np.ndarray, params: np.ndarray, max_iter: int = 40
) -> tuple[np.ndarray, np.ndarray]:
    """Levenberg–Marquardt from every row of ``params`` at once (minimum-norm steps).

    Returns the final rows and their errors ``‖y(1) − goal‖_∞``.
    """
    params = params.copy()
    val, jac = st.endpoint_and_jacobian(y0, params)
    res = yg[None, :] - val
    err = np.max(np.abs(res), axis=1)
    mu = np.full(len(params), 1e-6)
    alive = np.ones(len(params), dtype=bool)
    eye = np.eye(yg.size)
    for _ in range(max_iter):
        active = np.flatnonzero(alive & (err > UNIT_TOL))
        if active.size == 0:
            break
        j = jac[active]
        jjt = j @ np.transpose(j, (0, 2, 1)) + mu[active, None, None] * eye
        step = np.einsum("sni,sn->si", j, np.linalg.solve(jjt, res[active][:, :, None])[:, :, 0])
        cand = params[active] + step
        c_val, c_jac = st.endpoint_and_jacobian(y0, cand)
        c_res = yg[None, :] - c_val
        c_err = np.max(np.abs(c_res), axis=1)
        good = np.isfinite(c_err) & (c_err < err[active])
        take = active[good]
        params[take], val[take], jac[take] = cand[good], c_val[good], c_jac[good]
        res[take], err[take] = c_res[good], c_err[good]
        mu[take] = np.maximum(mu[take] / 10, 1e-16)
        drop = active[~good]
        mu[drop] *= 10
        alive[drop[mu[drop] > 1e12]] = False
    return params, err


def _first_guess(st: Step2Structure, ys: np.ndarray, yg: np.ndarray) -> np.ndarray | None:
    """Near-exact starts ``(u₀, λ)`` where a closed form exists (``None``: n/a).

    Two inputs, one vertical coordinate: :func:`_contact_starts` (the better
    sense); three inputs and three vertical coordinates spanning the brackets
    (the free (3,6) group up to a linear change):
    :func:`~nilpotent.planning.geodesic_forms.free3_starts`.
    """
    hi, vi = list(st.h_index), list(st.v_index)
    if st.m == 3:
        maps = st.free3_maps
        return None if maps is None else free3_starts(
            maps, st.a, st.t, (ys[hi], ys[vi]), (yg[hi], yg[vi]))
    if not (st.m == 2 and len(vi) == 1 and st.b.shape == (2, 2) and st.skew[0, 1, 0] != 0):
        return None
    u_line = np.linalg.solve(st.b, yg[hi] - ys[hi])
    line_end = st.endpoints(ys, u_line[None, :], np.zeros((1, 1)))[0]
    resid = float(yg[vi[0]] - line_end[vi[0]])
    if resid == 0.0:
        return np.concatenate([u_line, [0.0]])[None, :]
    guesses = np.array(_contact_starts(st, u_line, resid))
    ends = st.endpoints(ys, guesses[:, :2], guesses[:, 2:])
    return guesses[[int(np.argmin(np.max(np.abs(ends - yg), axis=1)))]]


def _starts(st: Step2Structure, ys: np.ndarray, yg: np.ndarray) -> list[np.ndarray]:
    """Starting guesses ``(u₀, λ)`` for the unit-size problem (general step 2)."""
    hi, vi = list(st.h_index), list(st.v_index)
    m, n2 = st.m, len(vi)
    u_line = np.linalg.lstsq(st.b, yg[hi] - ys[hi], rcond=None)[0]
    line_end = st.endpoints(ys, u_line[None, :], np.zeros((1, n2)))[0]
    resid = yg[vi] - line_end[vi]
    starts = [np.concatenate([u_line, np.zeros(n2)])]
    if not np.any(resid):
        return starts
    # covector directions: ± the residual and ± G⁺-weighted versions of it
    directions = [resid / np.linalg.norm(resid)]
    for lam_dir in directions:
        spec = float(np.linalg.norm(np.einsum("k,kij->ij", lam_dir, st.skew), 2))
        if spec == 0:
            continue
        for sign in (1.0, -1.0):
            for angle in _START_ANGLES:
                lam = sign * lam_dir * angle / spec
                # horizontal part: u₀ so that h(1) is right for this λ (least squares),
                # plus a component of unit size when that is too small to make any area
                omega = np.einsum("k,kij->ij", lam, st.skew)
                phi = _phi(omega)
                u0 = np.linalg.lstsq(st.b @ phi, yg[hi] - ys[hi], rcond=None)[0]
                if np.linalg.norm(u0) < 1.0:
                    kick = np.zeros(m)
                    kick[int(np.argmin(np.abs(u0)))] = 1.0
                    u0 = u0 + kick * (1.0 if np.linalg.norm(u0) < 0.5 else 0.5)
                starts.append(np.concatenate([u0, lam]))
    return starts


def _theta_minus_sin(theta: float) -> float:
    """``θ − sin θ`` without cancellation (its Taylor series below 0.5: ``θ³/6 − θ⁵/120 + …``).

    In doubles ``θ − sin θ`` is 0 for ``θ ≲ 1e-8``, which made :func:`_arc_angle`
    return ~1e-8 for goals with a tiny vertical displacement (``θ ≈ 12q``).
    """
    if abs(theta) >= 0.5:
        return theta - math.sin(theta)
    t2, term, total = theta * theta, theta**3 / 6, 0.0
    for k in range(1, 12):  # θ^(2k+1)/(2k+1)! with alternating signs; 0.5^25/25! ~ 1e-33
        total += term
        term *= -t2 / ((2 * k + 2) * (2 * k + 3))
    return total


def _arc_angle(q: float) -> float:
    """``θ ∈ (0, 2π)`` with ``(θ − sin θ) / (8 sin²(θ/2)) = q > 0`` (increasing in θ)."""
    lo, hi = 0.0, 2 * math.pi
    for _ in range(60):
        mid = (lo + hi) / 2
        val = _theta_minus_sin(mid) / (8 * math.sin(mid / 2) ** 2) if mid > 0 else 0.0
        lo, hi = (mid, hi) if val < q else (lo, mid)
    return (lo + hi) / 2


def _contact_starts(st: Step2Structure, u_line: np.ndarray, resid: float) -> list[np.ndarray]:
    """Near-exact guesses for ``m = 2``, one vertical coordinate (Heisenberg up to a linear map).

    In the plane ``(∫u₁, ∫u₂)`` (where the metric is Euclidean) a geodesic is a
    circular arc; a loop of signed area ``a`` moves ``v`` by ``a·κ``,
    ``κ = [X̂₁, X̂₂]_v`` (the mathematics page, §1).  The area ``a = resid/κ`` between arc
    and chord (``ρ = ‖u_line‖``) fixes the arc's angle θ:
    ``|a|/ρ² = (θ − sin θ)/(8 sin²(θ/2))``; the length is ``ρθ / (2 sin(θ/2))``
    (``√(4π|a|)`` for ``ρ = 0``).  Both rotation senses are offered; the
    Levenberg–Marquardt polish decides (and corrects any start off the origin).
    """
    kappa = float(st.skew[0, 1, 0])  # Ω = λ·skew[0]; [X̂₁, X̂₂]_v = t[0,1,0] − t[0,0,1]
    area = resid / kappa
    rho = float(np.linalg.norm(u_line))
    if rho == 0.0:
        theta, length, chord = 2 * math.pi, math.sqrt(4 * math.pi * abs(area)), np.array([1.0, 0])
    else:
        theta = _arc_angle(abs(area) / rho**2)
        length = rho * theta / (2 * math.sin(theta / 2))
        chord = u_line / rho
    out = []
    for sense in (1.0, -1.0):
        half = -sense * theta / 2
        rot = np.array([[math.cos(half), -math.sin(half)], [math.sin(half), math.cos(half)]])
        # Ω = sense·θ·J with J = [[0, −1], [1, 0]]; Ω = λ·skew[0] gives λ
        lam = sense * theta / kappa
        out.append(np.concatenate([length * (rot @ chord), [lam]]))
    return out


def _phi(omega: np.ndarray) -> np.ndarray:
    """``∫₀¹ e^{sΩ} ds`` (block exponential)."""
    m = omega.shape[0]
    c = np.zeros((2 * m, 2 * m))
    c[:m, :m] = omega
    c[:m, m:] = np.eye(m)
    return _expm(c[None])[0, :m, m:]


#: Taylor degree of :func:`_expm` (after scaling to norm ≤ 1/2: truncation ≤ 2^-14/14! ≈ 7e-16).
_TAYLOR_DEGREE = 13


def _expm(a: np.ndarray) -> np.ndarray:
    """Batched matrix exponential, shape ``(B, k, k)``: scaling and squaring with Taylor.

    ``scipy.linalg.expm`` costs about 20 ms per small matrix here (its
    dispatch), far too slow for a steering function; the matrices here are
    small (``4m × 4m``) and of moderate norm, where a degree-13 Taylor
    polynomial (Horner) on ``A/2^s`` with ``‖A/2^s‖₁ ≤ 1/2`` is accurate to
    rounding (``2^-14/14! ≈ 7e-16`` truncation, relative), followed by ``s``
    squarings.
    Checked against :func:`scipy.linalg.expm` in the tests.
    """
    norm = float(np.max(np.sum(np.abs(a), axis=-2))) if a.size else 0.0
    s = max(0, math.ceil(math.log2(norm / 0.5))) if norm > 0.5 else 0
    x = a / (2.0**s)
    eye = np.broadcast_to(np.eye(a.shape[-1], dtype=a.dtype), a.shape)
    out = eye + x / _TAYLOR_DEGREE
    for k in range(_TAYLOR_DEGREE - 1, 0, -1):
        out = eye + (x @ out) / k
    for _ in range(s):
        out = out @ out
    return out


def shortest_geodesic(
    system: TriangularSystem | Step2Structure,
    y_start: Sequence[float] | State,
    y_goal: Sequence[float] | State,
) -> Geodesic:
    """The shortest normal geodesic found from ``y_start`` to ``y_goal`` (controls on ``[0,1]``).

    Parameters
    ----------
    system : TriangularSystem or Step2Structure
        A step-2 (or step-1) nilpotent system in privileged coordinates.
    y_start, y_goal : sequence of float
        Points in those coordinates.

    Returns
    -------
    Geodesic
        Its ``length`` is the sub-Riemannian distance of the nilpotent system
        when the geodesic found is minimising (checked against the closed form
        for the Heisenberg group).

    Raises
    ------
    PlanningError
        The system is not of step ≤ 2, the points have the wrong size, or no
        start converged to ``1e-12`` (relative to the unit-size problem).

    Examples
    --------
    >>> import sympy as sp
    >>> y1, y2, y3 = sp.symbols("y1 y2 y3")
    >>> h = TriangularSystem.from_fields(((1, 0, -y2/2), (0, 1, y1/2)), (y1, y2, y3), (1, 1, 2))
    >>> g = shortest_geodesic(h, (0, 0, 0), (0, 0, 1))
    >>> abs(g.length - (4 * 3.141592653589793) ** 0.5) < 1e-10
    True
    """
    st = system if isinstance(system, Step2Structure) else Step2Structure.from_triangular(system)
    weights = np.zeros(len(st.h_index) + len(st.v_index))
    weights[list(st.h_index)] = 1.0
    weights[list(st.v_index)] = 2.0
    ys = np.asarray(y_start, dtype=float)
    yg = np.asarray(y_goal, dtype=float)
    if ys.shape != weights.shape or yg.shape != weights.shape:
        raise PlanningError(f"start and goal need {weights.size} privileged coordinates")
    n2 = len(st.v_index)
    # dilate so that the displacement has unit size.  Dilations are automorphisms
    # of the homogeneous system; the start is kept as it is (general start).
    disp = yg - ys
    scale = float(np.max(np.abs(disp) ** (1.0 / weights))) if disp.size else 0.0
    scale = max(scale, float(np.max(np.abs(ys) ** (1.0 / weights))))
    if scale == 0.0 or np.array_equal(ys, yg):
        return Geodesic((0.0,) * st.m, (0.0,) * n2, 0.0, tuple(ys), 0.0, 1)
    # divide once per unit of weight: scale**2 underflows to 0 for a scale below
    # ~1e-154 (a goal 1e-200 away), while each quotient stays at most 1 in size
    us, ug = ys / scale, yg / scale
    us[list(st.v_index)] /= scale
    ug[list(st.v_index)] /= scale
    best: tuple[float, np.ndarray, float] | None = None
    converged = 0
    first = _first_guess(st, us, ug)
    finals, errs = _lm(st, us, ug, first) if first is not None else ([], [])
    if not any(e <= UNIT_TOL * 10 for e in errs):  # the general multi-start
        starts = np.array(_starts(st, us, ug))
        if first is not None:
            starts = np.concatenate([starts, first])
        finals, errs = _lm(st, us, ug, starts)
    for params, err in zip(finals, errs, strict=True):
        if err <= UNIT_TOL * 10:
            converged += 1
            length = float(np.linalg.norm(params[: st.m]))
            if best is None or length < best[0] - 1e-12:
                best = (length, params, float(err))
    if best is None:
        raise PlanningError(
            "no normal geodesic found to the goal (Levenberg–Marquardt did not converge "
            "from any start)"
        )
    _, params, _ = best
    # undo the dilation: δ_s maps the extremal of (s·u₀, Ω) to that of (u₀, Ω): Ω (the
    # rotation over the unit time) and hence λ are unchanged
    u0 = params[: st.m] * scale
    lam = params[st.m :]
    reached = st.endpoints(ys, u0[None, :], lam[None, :])[0]
    err = float(np.max(np.abs(reached - yg)))
    return Geodesic(
        tuple(float(v) for v in u0),
        tuple(float(v) for v in lam),
        float(np.linalg.norm(params[: st.m])) * scale,  # (‖u₀‖ itself underflows below 1e-154)
        tuple(float(v) for v in reached),
        err,
        converged,
    )


def geodesic_controls(st: Step2Structure, geodesic: Geodesic) -> list[Segment]:
    """The controls ``u(t) = e^{tΩ}u₀`` on ``[0, 1]`` as exact harmonic segments.

    Parameters
    ----------
    st : Step2Structure
        The system the geodesic belongs to.
    geodesic : Geodesic
        As returned by :func:`shortest_geodesic`.

    Returns
    -------
    list of Segment
        One segment (none for a zero control).

    Raises
    ------
    PlanningError
        ``Ω`` has more than one non-zero frequency (``m ≥ 4``): not one
        harmonic segment.
    """
    u0 = np.array(geodesic.u0)
    if not np.any(u0):
        return []
    omega = np.einsum("k,kij->ij", np.array(geodesic.covector), st.skew)
    freqs = np.abs(np.linalg.eigvals(omega).imag)
    theta = float(np.max(freqs)) if freqs.size else 0.0
    if theta <= 1e-14 * max(1.0, float(np.max(np.abs(omega)))):
        return [Segment(1.0, 2 * math.pi, tuple(InputSignal(float(v)) for v in u0))]
    nonzero = freqs[freqs > 1e-9 * theta]
    if np.any(np.abs(nonzero - theta) > 1e-9 * theta):
        raise PlanningError(
            "the geodesic's controls have several incommensurate frequencies (m >= 4); "
            "not representable as one harmonic segment"
        )
    w = omega / theta
    sin_c = w @ u0
    cos_c = -(w @ sin_c)
    const = u0 - cos_c
    return [
        Segment(
            1.0,
            theta,
            tuple(
                InputSignal(float(const[i]), (float(cos_c[i]),), (float(sin_c[i]),))
                for i in range(st.m)
            ),
        )
    ]


def geodesic_segments(
    system: TriangularSystem, y_start: np.ndarray, y_goal: np.ndarray, seed: int = 0
) -> list[Segment]:
    """Shortest steering as a :data:`nilpotent.planning.nilpotent.METHODS` entry.

    Parameters
    ----------
    system : TriangularSystem
        Step ≤ 2.
    y_start, y_goal : numpy.ndarray
        Start and goal (already dilated to unit size by the caller).
    seed : int
        Unused (the starts are deterministic); part of the method signature.

    Returns
    -------
    list of Segment

    Raises
    ------
    PlanningError
        As :func:`shortest_geodesic` and :func:`geodesic_controls`.
    """
    del seed
    st = _structure(system)
    return geodesic_controls(st, shortest_geodesic(st, y_start, y_goal))


_STRUCTURES: dict[int, tuple[TriangularSystem, Step2Structure]] = {}


def _structure(system: TriangularSystem) -> Step2Structure:
    hit = _STRUCTURES.get(id(system))
    if hit is not None and hit[0] is system:
        return hit[1]
    st = Step2Structure.from_triangular(system)
    if len(_STRUCTURES) > 64:
        _STRUCTURES.clear()
    _STRUCTURES[id(system)] = (system, st)
    return st


def control_length(segments: Sequence[Segment]) -> float:
    """The sub-Riemannian length ``∫‖u(t)‖₂ dt`` of a control (``X_i`` orthonormal).

    Adaptive Gauss–Legendre quadrature (8 nodes per piece; pieces of at most a
    quarter period of the highest harmonic, at least 4 per segment, halved, up to
    40 times, while an estimate and its two halves' differ by more than their
    share of ``1e-12`` of the length): where ``u`` nearly vanishes, ``‖u‖`` has a
    near-kink that a fixed rule resolves badly (5e-4 relative on a Cartan plan).

    Parameters
    ----------
    segments : sequence of Segment
        The control.

    Returns
    -------
    float
    """
    nodes, weights = np.polynomial.legendre.leggauss(8)

    def rule(seg: Segment, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        half = (b - a) / 2
        t = (a[:, None] + half[:, None] * (nodes[None, :] + 1)).ravel()
        return half * (np.linalg.norm(seg.values(t), axis=0).reshape(len(a), -1) @ weights)

    total = 0.0
    for seg in segments:
        k = max((s.harmonics for s in seg.inputs), default=0)
        pieces = max(4, math.ceil(4 * k * seg.omega * seg.duration / (2 * math.pi)))
        edges = np.linspace(0.0, seg.duration, pieces + 1)
        a, b = edges[:-1], edges[1:]
        whole = rule(seg, a, b)
        scale = 1e-12 * max(float(np.sum(whole)), 1e-300) / seg.duration
        for level in range(41):
            mid = (a + b) / 2
            left, right = rule(seg, a, mid), rule(seg, mid, b)
            done = (np.abs(left + right - whole) <= scale * (b - a)) | (level == 40)
            total += float(np.sum((left + right)[done]))
            if done.all():
                break
            a, b = np.concatenate([a[~done], mid[~done]]), np.concatenate([mid[~done], b[~done]])
            whole = np.concatenate([left[~done], right[~done]])
    return total
