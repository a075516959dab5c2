r"""Shortest steering of nilpotent systems of any step: normal-geodesic shooting.

The metric makes ``X̂_1..X̂_m`` orthonormal (length ``∫‖u‖₂ dt``).  For a
nilpotent approximation in privileged coordinates (polynomial, triangular
fields, :class:`~nilpotent.planning.triangular.TriangularSystem`) the
**normal geodesics** are the projections of the trajectories of the
Hamiltonian (Pontryagin, Agrachev–Barilari–Boscain, *A Comprehensive
Introduction to Sub-Riemannian Geometry*, 2020, ch. 4)

.. math::

    H(y, p) = \tfrac12 \sum_i h_i^2,\quad h_i = \langle p, \hat X_i(y)\rangle,\qquad
    \dot y = \sum_i h_i \hat X_i(y),\quad
    \dot p = -\sum_i h_i\,(\partial \hat X_i/\partial y)^{\mathsf T} p,

with controls ``u_i = h_i``; ``H`` is constant, so on ``[0, 1]`` the length is
``‖u(0)‖ = √(2H)``.  The **boundary problem** ``y(1) = goal`` in the unknown
covector ``p(0)`` is solved by Levenberg–Marquardt (minimum-norm steps) with
the *exact* Jacobian ``∂y(1)/∂p(0)``: the variational equations
``Ψ̇ = A(y, p) Ψ`` (``A`` the Jacobian of the Hamiltonian field, polynomial,
differentiated exactly by sympy and compiled by
:func:`nilpotent.numeric.compile.compile_map`) are integrated alongside the
flow by a fixed-step Dormand–Prince 8 scheme (:data:`SEARCH_STEPS` steps for the
search, :data:`STEPS` — or twice that — for the final solve, to ``1e-11``).

**Starts.**  The problem is dilated to unit homogeneous size (``δ_λ`` maps
geodesics to geodesics, lengths times ``λ``, covectors ``p_j`` times
``λ^{2−w_j}``); then, in one batch, LM runs from the straight line (``p`` zero
in weights ≥ 2, which keeps the controls constant: exact when the goal is on
the line) and from :data:`RANDOM_STARTS` seeded random covectors of every
weight.  **Continuation in the goal** from the *lift* of the quotient's
shortest geodesic: the coordinates of weight ``< step`` form a nilpotent
system of their own (triangular), solved in closed form for step 2
(:func:`~nilpotent.planning.geodesic.shortest_geodesic`) or by this shooting;
with the top-weight covector zero its extremal is one of the whole system,
reaching the goal except in the top weight, and the goal is then followed
from there in steps (halved on failure).  If that branch is lost or nothing
converged, a **least-energy start** (SLSQP on Fourier controls under the
exact endpoint constraint; its multiplier is the final covector, flowed back
to ``p(0)``) and longer searches.  The shortest extremal found is kept (a
search error up to :data:`ACCEPT_TOL` is accepted where the final solve stalls,
as at conjugate points: the polish below reaches the goal).

**Controls.**  ``u(t)`` is not a trigonometric polynomial in general (elliptic
functions for the Engel group); it is written as :data:`PIECES` segments, each
a Fourier extension (``omega = π/duration``, ``cos``/``sin`` up to
:data:`HARMONICS`) fitted by least squares to the samples of the flow, then
polished by LM on the exact closed-form flow (:mod:`nilpotent.planning.exact_flow`)
until the goal is reached to rounding.  The polish moves the control by the fit
error only, so its length (``control_length``) is the geodesic's to about
``1e-9`` relative.

**Abnormal curves.**  The endpoint map's differential along the returned
control (its Jacobian in the segments' coefficients, a basis rich enough to
span the image of the differential) is computed; if its rank is below ``n``
(relative singular value ``≤`` :data:`ABNORMAL_RANK_TOL`) the curve is
singular (**abnormal**) and is reported so (:attr:`ShootingGeodesic.abnormal`).
On the Martinet system ``X̂₁ = ∂x + y²/2 ∂z, X̂₂ = ∂y`` the line to
``(a, 0, 0)`` is abnormal (and, in this flat case, also normal): the
straight-line start finds it with length ``|a|`` and it is reported abnormal.
Strictly abnormal minimisers (not normal, e.g. Liu–Sussmann's) are not found
by normal shooting; the straight line is the one abnormal candidate tried.

What is *not* claimed: that the shortest normal geodesic found is the global
minimiser (the multi-start may miss the shortest branch; minimisers may be
strictly abnormal).  ``length ≥ ‖B⁺ Δh‖`` (``B`` the constant weight-1
components, ``Δh`` the weight-1 displacement) is the certified lower bound of
the nilpotent system (:func:`weight_one_bound`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp

from nilpotent.errors import PlanningError
from nilpotent.numeric.compile import CompiledMap, compile_map
from nilpotent.numeric.signals import InputSignal, Segment
from nilpotent.numeric.tableaux import DOP853
from nilpotent.numeric.types import State
from nilpotent.planning import budget
from nilpotent.planning.exact_flow import endpoint, endpoint_and_jacobian
from nilpotent.planning.geodesic import control_length, shortest_geodesic
from nilpotent.planning.triangular import TriangularSystem

__all__ = [
    "ShootingGeodesic", "hamiltonian_flow", "shooting_segments", "shortest_normal_geodesic",
    "weight_one_bound",
]

#: Fixed Dormand–Prince 8 steps on ``[0, 1]`` of the search, and of the final solve.
SEARCH_STEPS = 12
STEPS = 48
#: Endpoint accuracy of the search and of the final solve, unit-size problem.
SEARCH_TOL = 1e-8
SHOOT_TOL = 1e-11
#: Search error of an extremal still accepted (unit size; the polish reaches the goal).
ACCEPT_TOL = 1e-4
#: Endpoint accuracy of the polished controls, unit-size problem (exact flow).
UNIT_TOL = 1e-13
#: Segments of the controls, and harmonics ``K`` of the Fourier extension of each.
PIECES = 4
HARMONICS = 5
#: Seeded random starts (besides the straight line).
RANDOM_STARTS = 8
#: Relative singular value below which the endpoint map's differential is rank deficient.
ABNORMAL_RANK_TOL = 1e-8
#: Continuation: number of goal steps first tried, and the least step before giving up.
CONTINUATION_STEPS = 4
_MIN_CONTINUATION_STEP = 1.0 / 256


@dataclass(frozen=True)
class ShootingGeodesic:
    """The shortest normal geodesic found by shooting, and its controls.

    Attributes
    ----------
    covector : tuple of float
        ``p(0)`` (controls on ``[0, 1]``: ``u(0) = X̂(y₀)ᵀ p(0)``).
    length : float
        ``√(2H) = ‖u(0)‖``, the geodesic's length.
    segments : tuple of Segment
        Its controls as one Fourier-extension segment, polished on the exact
        flow (empty for start = goal).
    control_length : float
        ``∫‖u‖ dt`` of ``segments`` (equal to ``length`` to the fit error).
    reached : tuple of float
        Endpoint of ``segments`` (exact flow).
    error : float
        ``‖reached − goal‖_∞``.
    shooting_error : float
        ``‖y(1) − goal‖_∞`` of the Hamiltonian flow from ``covector``.
    starts_converged : int
        How many starts converged (the shortest was kept).
    abnormal : bool
        Whether the endpoint map's differential along the control has rank
        ``< n`` (a singular curve).
    rank : int
        That rank.
    """

    covector: tuple[float, ...]
    length: float
    segments: tuple[Segment, ...]
    control_length: float
    reached: tuple[float, ...]
    error: float
    shooting_error: float
    starts_converged: int
    abnormal: bool
    rank: int


@dataclass(frozen=True, eq=False)
class HamiltonianFlow:
    """The compiled Hamiltonian field of a triangular system and its Jacobian.

    Attributes
    ----------
    system : TriangularSystem
        The fields.
    rhs : CompiledMap
        ``(y, p) ↦ (ẏ, ṗ, A)`` with ``A = ∂(ẏ, ṗ)/∂(y, p)`` row-major.
    controls : CompiledMap
        ``(y, p) ↦ h = X̂(y)ᵀ p``.
    """

    system: TriangularSystem
    rhs: CompiledMap
    controls: CompiledMap

    def flow(
        self, z0: np.ndarray, steps: int = STEPS, jacobian: bool = True, duration: float = 1.0
    ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """Integrate from ``z0 = (y₀, p₀)`` (shape ``(S, 2n)``) over ``[0, duration]``
        (``duration = −1``: backward).

        Returns ``z(1)``, ``∂z(1)/∂p₀`` (shape ``(S, 2n, n)``, or ``None``) and
        ``z`` at the ``steps + 1`` grid times (shape ``(steps + 1, S, 2n)``).
        """
        n = self.system.n
        tab = DOP853
        h = duration / steps
        z = np.array(z0, dtype=float)
        batch = z.shape[0]
        psi = None
        if jacobian:
            psi = np.zeros((batch, 2 * n, n))
            psi[:, n:, :] = np.eye(n)
        grid = [z.copy()]
        a_rows = [np.array(r) for r in tab.a]
        b = np.array(tab.b)
        ks = np.zeros((*z.shape, tab.stages))  # stages last: one matmul per stage
        kps = np.zeros((*psi.shape, tab.stages)) if psi is not None else None
        with np.errstate(all="ignore"):
            for _ in range(steps):
                for s, a in enumerate(a_rows):
                    out = self.rhs(z + h * (ks[..., :s] @ a) if s else z)
                    ks[..., s] = out[:, : 2 * n]
                    if psi is not None and kps is not None:
                        ps = psi + h * (kps[..., :s] @ a) if s else psi
                        kps[..., s] = out[:, 2 * n:].reshape(batch, 2 * n, 2 * n) @ ps
                z = z + h * (ks @ b)
                if psi is not None and kps is not None:
                    psi = psi + h * (kps @ b)
                grid.append(z.copy())
        return z, psi, np.array(grid)


_FLOWS: dict[int, tuple[TriangularSystem, HamiltonianFlow]] = {}


def hamiltonian_flow(system: TriangularSystem) -> HamiltonianFlow:
    """The compiled Hamiltonian field of ``system`` (memoised per system object).

    Parameters
    ----------
    system : TriangularSystem
        Polynomial triangular fields.

    Returns
    -------
    HamiltonianFlow
    """
    hit = _FLOWS.get(id(system))
    if hit is not None and hit[0] is system:
        return hit[1]
    n = system.n
    ys = sp.symbols(f"y1:{n + 1}")
    ps = sp.symbols(f"p1:{n + 1}")
    fields = [
        [sum((sp.Float(c) * sp.Mul(*(v**e for v, e in zip(ys, exps, strict=True)))
              for c, exps in system.terms[i][j]), sp.Integer(0)) for j in range(n)]
        for i in range(system.m)
    ]
    h = [sp.expand(sum((p * x for p, x in zip(ps, row, strict=True)), sp.Integer(0)))
         for row in fields]
    ham = sum((hi**2 for hi in h), sp.Integer(0)) / 2
    rhs = [sp.expand(sp.diff(ham, p)) for p in ps] + [sp.expand(-sp.diff(ham, y)) for y in ys]
    jac = [sp.diff(f, v) for f in rhs for v in (*ys, *ps)]
    coords = (*ys, *ps)
    flow = HamiltonianFlow(
        system,
        compile_map(coords, rhs + jac, name="hamiltonian", outputs=len(rhs) + len(jac)),
        compile_map(coords, h, name="hamiltonian-controls", outputs=len(h)),
    )
    if len(_FLOWS) > 64:
        _FLOWS.clear()
    _FLOWS[id(system)] = (system, flow)
    return flow


def weight_one_bound(system: TriangularSystem, y_start: np.ndarray, y_goal: np.ndarray) -> float:
    """``‖B⁺ Δh‖``: a certified lower bound of the nilpotent system's distance.

    The weight-1 components ``B`` of the fields are constant, so every control
    steering ``y_start → y_goal`` has ``B ∫u = Δh`` (the weight-1
    displacement) and ``∫‖u‖ ≥ ‖∫u‖ ≥ min{‖v‖ : Bv = Δh} = ‖B⁺Δh‖``.

    Parameters
    ----------
    system : TriangularSystem
        Privileged coordinates.
    y_start, y_goal : numpy.ndarray
        Points.

    Returns
    -------
    float
    """
    w1 = [j for j in range(system.n) if system.weights[j] == 1]
    delta = np.asarray(y_goal, dtype=float)[w1] - np.asarray(y_start, dtype=float)[w1]
    return float(np.linalg.norm(np.linalg.pinv(system.weight_one_matrix()) @ delta))


def _lm(
    flow: HamiltonianFlow, ys: np.ndarray, yg: np.ndarray, p0: np.ndarray, max_iter: int = 20,
    steps: int = SEARCH_STEPS, tol: float = SEARCH_TOL,
) -> tuple[np.ndarray, np.ndarray]:
    """Batched Levenberg–Marquardt on ``p₀ ↦ y(1)`` (minimum-norm steps); rows and errors."""
    n = ys.size
    p = p0.copy()

    def evaluate(pp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        z1, psi, _ = flow.flow(np.hstack([np.tile(ys, (len(pp), 1)), pp]), steps)
        assert psi is not None
        return yg[None, :] - z1[:, :n], psi[:, :n, :]

    res, jac = evaluate(p)
    err = np.max(np.abs(res), axis=1)
    err[~np.isfinite(err)] = np.inf
    mu = np.full(len(p), 1e-6)
    alive = np.isfinite(err)
    eye = np.eye(n)
    for it in range(max_iter):
        if it == max_iter // 2:
            alive &= err < 0.1  # far from converging at half time: dropped
        active = np.flatnonzero(alive & (err > tol))
        if active.size == 0:
            break
        budget.check("shooting a normal geodesic of the nilpotent approximation")
        j = jac[active]
        jjt = j @ np.transpose(j, (0, 2, 1)) + mu[active, None, None] * eye
        try:
            sol = np.linalg.solve(jjt, res[active][:, :, None])[:, :, 0]
        except np.linalg.LinAlgError:
            break
        cand = p[active] + np.einsum("sni,sn->si", j, sol)
        c_res, c_jac = evaluate(cand)
        c_err = np.max(np.abs(c_res), axis=1)
        good = np.isfinite(c_err) & np.all(np.isfinite(c_jac), axis=(1, 2)) & (c_err < err[active])
        take = active[good]
        p[take], res[take], jac[take], err[take] = cand[good], c_res[good], c_jac[good], c_err[good]
        mu[take] = np.maximum(mu[take] / 10, 1e-15)
        drop = active[~good]
        mu[drop] *= 10
        alive[drop[mu[drop] > 1e10]] = False
    return p, err


def _line_covector(system: TriangularSystem, ys: np.ndarray, yg: np.ndarray) -> np.ndarray:
    """``p₀`` of the straight line: weight-1 part with ``Bᵀp_h = B⁺Δh``, zero above."""
    w1 = [j for j in range(system.n) if system.weights[j] == 1]
    b = system.weight_one_matrix()
    u = np.linalg.pinv(b) @ (yg[w1] - ys[w1])
    p = np.zeros(system.n)
    p[w1] = np.linalg.pinv(b.T) @ u
    return p


def _starts(
    system: TriangularSystem, ys: np.ndarray, yg: np.ndarray, seed: int, times: int = 1
) -> np.ndarray:
    """The straight line's covector and ``times·RANDOM_STARTS`` seeded random ones (spread
    ``σ^{w−1}`` by weight, ``σ ∈ {2, 5, 10}``)."""
    rng = np.random.default_rng(seed)
    w = np.asarray(system.weights, dtype=float)
    rows = [_line_covector(system, ys, yg)]
    for k in range(RANDOM_STARTS * times):
        spread = (2.0, 5.0, 10.0)[k % 3]
        rows.append(rng.standard_normal(system.n) * spread ** (w - 1))
    return np.array(rows)


def _continuation(
    flow: HamiltonianFlow, ys: np.ndarray, yg: np.ndarray, p: np.ndarray
) -> tuple[np.ndarray, float] | None:
    """Follow the goal from the end of the extremal of ``p`` to ``yg`` (steps halved on failure)."""
    n = ys.size
    z1, _, _ = flow.flow(np.hstack([ys, p])[None, :], SEARCH_STEPS, jacobian=False)
    origin = z1[0, :n]
    if not np.all(np.isfinite(origin)):
        return None
    s, step = 0.0, 1.0 / CONTINUATION_STEPS
    err = float(np.max(np.abs(origin - yg)))
    if err <= SEARCH_TOL:
        return p, err
    while s < 1.0:
        t = min(1.0, s + step)
        rows, errs = _lm(flow, ys, origin + t * (yg - origin), p[None, :], max_iter=10)
        if errs[0] <= SEARCH_TOL:
            p, s, err = rows[0], t, float(errs[0])
            step = min(step * 2, 0.5)
        else:
            step /= 2
            if step < _MIN_CONTINUATION_STEP:
                return None
    return p, err


def _energy_start(
    system: TriangularSystem, ys: np.ndarray, yg: np.ndarray, flow: HamiltonianFlow, seed: int
) -> np.ndarray | None:
    """``p(0)`` of a least-energy control in a Fourier basis: the fallback start.

    SLSQP minimises ``½θᵀWθ`` (``θ``: constant and ``cos/sin 2πkt``,
    ``k ≤ 2·step``, an orthogonal basis: ``½θᵀWθ = ½∫‖u‖²``) under the exact
    endpoint constraint (:mod:`nilpotent.planning.exact_flow`, exact Jacobian).
    At its solution ``Wθ = Jᵀλ``: the truncated first-order condition, whose
    multiplier ``λ`` is the final covector ``p(1)``; the Hamiltonian flow
    backward from ``(goal, λ)`` gives ``p(0)``.  Robust where random covectors
    are not (goals of the top weight only, often conjugate points).
    """
    from scipy.optimize import minimize

    m, k = system.m, 2 * system.step
    weights = np.tile(np.r_[1.0, np.full(2 * k, 0.5)], m)
    memo: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def ends(th: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = th.tobytes()
        if key not in memo:
            budget.check("least-energy start of the geodesic shooting")
            memo.clear()
            memo[key] = endpoint_and_jacobian(system, ys, [_segment(th, m, k, 2 * math.pi)], [k])
        return memo[key]

    theta0 = 0.5 * np.random.default_rng(seed).standard_normal(weights.size)
    res = minimize(lambda th: (0.5 * th @ (weights * th), weights * th), theta0, jac=True,
                   method="SLSQP", options={"maxiter": 150, "ftol": 1e-14},
                   constraints={"type": "eq", "fun": lambda th: ends(th)[0] - yg,
                                "jac": lambda th: ends(th)[1]})
    val, jac = ends(res.x)
    if not np.max(np.abs(val - yg)) < 1e-6:
        return None
    lam = np.linalg.lstsq((jac / weights).T, res.x, rcond=None)[0]
    back, _, _ = flow.flow(np.hstack([yg, lam])[None, :], STEPS, False, -1.0)
    return back[0, system.n:] if np.all(np.isfinite(back)) else None


def _quotient(system: TriangularSystem, top: int) -> tuple[TriangularSystem, list[int]]:
    """The system on the coordinates of weight ``≤ top`` (closed: triangular), and their indices."""
    keep = [j for j in range(system.n) if system.weights[j] <= top]
    terms = tuple(
        tuple(tuple((c, tuple(e[k] for k in keep)) for c, e in system.terms[i][j]) for j in keep)
        for i in range(system.m)
    )
    names = tuple(system.names[j] for j in keep)
    return TriangularSystem(names, tuple(system.weights[j] for j in keep), terms), keep


def _lifted_covector(
    system: TriangularSystem, ys: np.ndarray, yg: np.ndarray, seed: int
) -> np.ndarray | None:
    """``p₀`` of the shortest geodesic of the quotient of weight ``≤ step − 1``, lifted.

    With the top-weight covector zero (no field depends on the top-weight
    coordinates, so it stays zero), an extremal of the quotient is one of the
    system: it reaches the goal except in the top weight, from where
    :func:`_continuation` takes over.  Step 2 quotients are solved in closed
    form (:func:`~nilpotent.planning.geodesic.shortest_geodesic`), higher ones
    by this shooting.
    """
    top = system.step - 1
    if top < 1:
        return None
    quo, keep = _quotient(system, top)
    p = np.zeros(system.n)
    if top == 1:
        return _line_covector(system, ys, yg)
    try:
        if top == 2:
            geo = shortest_geodesic(quo, ys[keep], yg[keep])
            v_idx = [keep[q] for q in range(len(keep)) if quo.weights[q] == 2]
            p[v_idx] = geo.covector
            u0 = np.array(geo.u0)
        else:
            sub = shortest_normal_geodesic(quo, ys[keep], yg[keep], seed)
            p[keep] = sub.covector
            return p
    except PlanningError:
        return None
    # weight-1 part: X̂(ys)ᵀ p = u0 with the higher parts fixed
    w1 = [j for j in range(system.n) if system.weights[j] == 1]
    fields = system.field_values(ys)  # (n, m)
    rest = fields.T @ p  # contribution of the weight-2 covector
    p[w1] = np.linalg.solve(fields[w1].T, u0 - rest)
    return p


def _basis(t: np.ndarray, k: int, omega: float) -> np.ndarray:
    """Columns ``1, cos(jωt) (j ≤ k), sin(jωt) (j ≤ k)``: the coefficient order of an input."""
    j = np.arange(1, k + 1)
    return np.hstack([np.ones((t.size, 1)), np.cos(omega * np.outer(t, j)),
                      np.sin(omega * np.outer(t, j))])


def _segment(theta: np.ndarray, m: int, k: int, omega: float, duration: float = 1.0) -> Segment:
    rows = theta.reshape(m, 2 * k + 1)
    return Segment(duration, omega, tuple(
        InputSignal(float(r[0]), tuple(float(v) for v in r[1: k + 1]),
                    tuple(float(v) for v in r[k + 1:])) for r in rows))


def _fit_and_polish(
    flow: HamiltonianFlow, ys: np.ndarray, yg: np.ndarray, p0: np.ndarray
) -> tuple[list[Segment], np.ndarray, np.ndarray]:
    """The geodesic's controls as :data:`PIECES` polished segments; endpoint and its Jacobian.

    Each piece (duration ``d = 1/PIECES``) is a Fourier extension with
    ``omega = π/d`` and :data:`HARMONICS` harmonics, fitted by least squares to
    ``u = X̂(y)ᵀp`` sampled along the flow.
    """
    system = flow.system
    n, m, k = system.n, system.m, HARMONICS
    per = 24
    _, _, grid = flow.flow(np.hstack([ys, p0])[None, :], steps=PIECES * per, jacobian=False)
    u = flow.controls(grid[:, 0, :])  # (T, m)
    d = 1.0 / PIECES
    omega = math.pi / d
    tau = np.linspace(0.0, d, per + 1)
    basis = _basis(tau, k, omega)
    theta = np.concatenate([
        np.linalg.lstsq(basis, u[q * per: (q + 1) * per + 1], rcond=None)[0].T.ravel()
        for q in range(PIECES)])
    harmonics = [k] * PIECES

    def segments(th: np.ndarray) -> list[Segment]:
        size = m * (2 * k + 1)
        return [_segment(th[q * size: (q + 1) * size], m, k, omega, d) for q in range(PIECES)]

    segs = segments(theta)
    val, jac = endpoint_and_jacobian(system, ys, segs, harmonics)
    err = float(np.max(np.abs(val - yg)))
    mu = 1e-12
    for _ in range(30):
        if err <= UNIT_TOL:
            break
        budget.check("polishing the geodesic's controls on the exact flow")
        step = jac.T @ np.linalg.solve(jac @ jac.T + mu * np.eye(n), yg - val)
        c_segs = segments(theta + step)
        c_val, c_jac = endpoint_and_jacobian(system, ys, c_segs, harmonics)
        c_err = float(np.max(np.abs(c_val - yg)))
        if c_err < err:
            theta, segs, val, jac, err = theta + step, c_segs, c_val, c_jac, c_err
            mu = max(mu / 10, 1e-16)
        else:
            mu *= 100
            if mu > 1e6:
                break
    return segs, val, jac


def _rank(jac: np.ndarray) -> int:
    sv = np.linalg.svd(jac, compute_uv=False)
    if sv.size == 0 or sv[0] == 0:
        return 0
    return int(np.sum(sv > ABNORMAL_RANK_TOL * sv[0]))


def shortest_normal_geodesic(
    system: TriangularSystem,
    y_start: Sequence[float] | State,
    y_goal: Sequence[float] | State,
    seed: int = 0,
) -> ShootingGeodesic:
    """The shortest normal geodesic found by shooting from ``y_start`` to ``y_goal``.

    Parameters
    ----------
    system : TriangularSystem
        A nilpotent system in privileged coordinates (any step).
    y_start, y_goal : sequence of float
        Points in those coordinates.
    seed : int
        Seed of the random starts (results are reproducible).

    Returns
    -------
    ShootingGeodesic
        Its ``length`` is that of the shortest converged normal extremal;
        ``abnormal`` says whether the returned curve is (also) singular.

    Raises
    ------
    PlanningError
        Points of the wrong size, or no start (nor the continuation) converged.

    Examples
    --------
    >>> import sympy as sp
    >>> y1, y2, y3, y4 = sp.symbols("y1:5")
    >>> engel = TriangularSystem.from_fields(
    ...     ((1, 0, 0, 0), (0, 1, y1, y1**2 / 2)), (y1, y2, y3, y4), (1, 1, 2, 3))
    >>> g = shortest_normal_geodesic(engel, (0, 0, 0, 0), (0.3, 0.4, 0.06, 0.006))
    >>> round(g.length, 10), g.error < 1e-12
    (0.5, True)
    """
    ys = np.asarray(y_start, dtype=float)
    yg = np.asarray(y_goal, dtype=float)
    n = system.n
    if ys.shape != (n,) or yg.shape != (n,):
        raise PlanningError(f"start and goal need {n} privileged coordinates")
    scale = max(system.quasi_norm(yg - ys), system.quasi_norm(ys))
    if scale == 0.0 or np.array_equal(ys, yg):
        zero = (0.0,) * n
        return ShootingGeodesic(zero, 0.0, (), 0.0, tuple(ys), 0.0, 0.0, 1, False, 0)
    try:
        return _shortest(system, ys, yg, scale, seed)
    except (np.linalg.LinAlgError, ValueError) as exc:  # a degenerate linear algebra step
        raise PlanningError(f"normal-geodesic shooting failed: {exc}") from None


def _shortest(
    system: TriangularSystem, ys: np.ndarray, yg: np.ndarray, scale: float, seed: int
) -> ShootingGeodesic:
    n = system.n
    w = np.asarray(system.weights, dtype=float)
    flow = hamiltonian_flow(system)
    # δ_{1/scale}: unit-size problem (divide once per unit of weight against underflow)
    us, ug = ys.copy(), yg.copy()
    for k in range(1, int(max(w)) + 1):
        us[w >= k] /= scale
        ug[w >= k] /= scale
    rows, errs = _lm(flow, us, ug, _starts(system, us, ug, seed))
    lifted = _lifted_covector(system, us, ug, seed)
    cont = _continuation(flow, us, ug, lifted) if lifted is not None else None
    if cont is not None:
        rows, errs = np.vstack([rows, cont[0]]), np.append(errs, cont[1])
    if cont is None or not np.any(errs <= SEARCH_TOL):
        # the lift's branch was lost, or nothing converged: the least-energy start, and
        # longer searches
        energy = _energy_start(system, us, ug, flow, seed)
        more = [rows[np.isfinite(errs)], _starts(system, us, ug, seed + 1)[1:]]
        rows, errs = _lm(flow, us, ug, np.vstack(more if energy is None else [energy, *more]), 40)
    ok = errs <= ACCEPT_TOL
    lengths = np.linalg.norm(flow.controls(np.hstack([np.tile(us, (len(rows), 1)), rows])), axis=1)
    lengths[~ok] = np.inf
    if not np.any(ok):
        raise PlanningError(
            "no normal geodesic of the nilpotent approximation found to the goal "
            f"(shooting from {len(rows)} starts and continuation in the goal did not converge)"
        )
    # the shortest, solved again with more steps (kept as found where the endpoint is a
    # conjugate point and Newton stalls: the polish on the exact flow reaches the goal)
    best = int(np.argmin(lengths))
    p_unit, final_err = rows[best], float(errs[best])
    for steps in (STEPS, 2 * STEPS):
        fine, fine_err = _lm(flow, us, ug, p_unit[None, :], 8, steps, SHOOT_TOL)
        if fine_err[0] <= SHOOT_TOL:
            p_unit, final_err = fine[0], float(fine_err[0])
            break
    length = float(np.linalg.norm(flow.controls(np.hstack([us, p_unit])[None, :])[0]))
    segs, _, jac = _fit_and_polish(flow, us, ug, p_unit)
    rank = _rank(jac)
    segments = [seg.scaled(scale) for seg in segs]
    reached = endpoint(system, ys, segments)
    covector = p_unit * scale ** (2.0 - w)
    return ShootingGeodesic(
        tuple(float(v) for v in covector),
        length * scale,
        tuple(segments),
        control_length(segments),
        tuple(float(v) for v in reached),
        float(np.max(np.abs(reached - yg))),
        final_err,
        int(np.sum(ok)),
        rank < n,
        rank,
    )


def shooting_segments(
    system: TriangularSystem, y_start: np.ndarray, y_goal: np.ndarray, seed: int = 0
) -> list[Segment]:
    """Shortest steering of any step as a :data:`nilpotent.planning.nilpotent.METHODS` entry.

    Parameters
    ----------
    system : TriangularSystem
        Any step.
    y_start, y_goal : numpy.ndarray
        Start and goal (already dilated to unit size by the caller).
    seed : int
        Seed of the random starts.

    Returns
    -------
    list of Segment

    Raises
    ------
    PlanningError
        As :func:`shortest_normal_geodesic`.
    """
    return list(shortest_normal_geodesic(system, y_start, y_goal, seed).segments)
