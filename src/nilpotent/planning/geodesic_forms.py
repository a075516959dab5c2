r"""Closed forms for the normal geodesics of step-2 systems with at most three inputs.

For ``m ≤ 3`` a skew matrix satisfies ``Ω³ = −θ²Ω`` with ``θ² = ½ Σ_ij Ω_ij²``
(Cayley–Hamilton; for ``m = 2``, ``Ω² = −θ²I``), so Rodrigues' formula

.. math::

    e^{tΩ} = I + f_1(t)\,Ω + f_2(t)\,Ω^2, \qquad
    f_1 = \frac{\sin θt}{θ}, \quad f_2 = \frac{1 − \cos θt}{θ^2},

gives the control ``u = e^{tΩ}u₀`` and its integral
``U(t) = g_0 u₀ + g_1 Ωu₀ + g_2 Ω²u₀`` (``g_0 = t``, ``g_1 = f_2``,
``g_2 = (θt − \sin θt)/θ^3``) in closed form, and with ``w_a = Ω^a u₀``

.. math::

    M = ∫_0^1 u\,U^T dt = \sum_{a,b=0}^{2} c_{ab}(θ)\, w_a w_b^T,
    \qquad c_{ab} = ∫_0^1 f_a g_b\,dt \quad (f_0 = 1),

nine scalar functions of ``s = θ²`` (entire in ``s``).  They are evaluated
by their Taylor series in ``s`` for ``|θ| < 2`` (no cancellation near 0) and
by their trigonometric closed forms above, which involve only ``s`` through
``θ = √s`` in even combinations and are therefore analytic in ``s`` too: the
complex-step derivatives of :class:`~nilpotent.planning.geodesic.Step2Structure`
stay exact.  This replaces a ``4m × 4m`` block matrix exponential (Van Loan)
per evaluation by a few elementwise operations (issue 19, speed).

For systems equivalent to the free (3,6) group the boundary problem itself is
reduced by the rotations to two scalar equations (:func:`free3_starts`,
:func:`reduced_free3_solutions`; derivation in the comment above them), whose
solutions give near-exact starts for the Levenberg–Marquardt polish of
:func:`~nilpotent.planning.geodesic.shortest_geodesic`.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["free3_maps", "free3_starts", "reduced_free3_solutions", "rodrigues_integrals"]

#: Below this ``|θ|`` the coefficient functions are summed as Taylor series in ``s = θ²``.
_SERIES_THETA = 2.0
#: Number of Taylor terms (at ``|s| = 4`` the terms fall below ``4^n/(2n)! < 1e-25`` well before).
_SERIES_TERMS = 20


def _factor_terms(index: int, integrated: bool) -> list[tuple[int, int, float]]:
    """``(power of s, power of t, coefficient)`` of ``f_index`` (or ``g_index`` if integrated)."""
    if index == 0:
        return [(0, 1, 1.0)] if integrated else [(0, 0, 1.0)]
    shift = index + (1 if integrated else 0)
    return [
        (k, 2 * k + shift, (-1.0) ** k / math.factorial(2 * k + shift))
        for k in range(_SERIES_TERMS)
    ]


def _coefficient_series() -> tuple[np.ndarray, np.ndarray]:
    """Taylor coefficients in ``s`` of ``c_ab`` (``(3, 3, K)``) and of ``g_b(1)`` (``(3, K)``)."""
    c = np.zeros((3, 3, _SERIES_TERMS))
    g = np.zeros((3, _SERIES_TERMS))
    for b in range(3):
        for ks, _, coef in _factor_terms(b, True):
            g[b, ks] += coef
    for a in range(3):
        for b in range(3):
            for ka, pa, ca in _factor_terms(a, False):
                for kb, pb, cb in _factor_terms(b, True):
                    if ka + kb < _SERIES_TERMS:
                        c[a, b, ka + kb] += ca * cb / (pa + pb + 1)
    return c, g


_C_SERIES, _G_SERIES = _coefficient_series()


def _closed_coefficients(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``c_ab`` (shape ``(B, 3, 3)``) and ``g_b(1)`` (``(B, 3)``) by their trigonometric forms."""
    x = np.sqrt(s)
    sn, cs = np.sin(x), np.cos(x)
    s2 = np.sin(2 * x)
    x2, x3, x4, x5 = s, s * x, s * s, s * s * x
    tcos = x * sn + cs - 1  # x·∫ t cos(xt) dt·x = x sin x + cos x − 1
    tsin = sn - x * cs  # x²·∫ t sin(xt) dt
    c = np.empty((*s.shape, 3, 3), dtype=s.dtype)
    c[..., 0, 0] = 0.5
    c[..., 0, 1] = (x - sn) / x3
    c[..., 0, 2] = (x2 / 2 - 1 + cs) / x4
    c[..., 1, 0] = tsin / x3
    c[..., 1, 1] = (1 - cs - sn * sn / 2) / x4
    c[..., 1, 2] = (tsin / x - 0.5 + s2 / (4 * x)) / x4
    c[..., 2, 0] = (0.5 - tcos / x2) / x2
    c[..., 2, 1] = (1.5 - 2 * sn / x + s2 / (4 * x)) / x4
    c[..., 2, 2] = (x / 2 - (1 - cs) / x - tcos / x + sn * sn / (2 * x)) / x5
    g = np.stack([np.ones_like(s), (1 - cs) / x2, (x - sn) / x3], axis=-1)
    return c, g


def coefficients(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``c_ab(s)`` (shape ``(B, 3, 3)``) and ``g_b(1)`` (shape ``(B, 3)``), ``s = θ²``, batched.

    Parameters
    ----------
    s : numpy.ndarray
        Shape ``(B,)``, real or complex.

    Returns
    -------
    c, g : numpy.ndarray
    """
    c = np.empty((s.size, 3, 3), dtype=s.dtype)
    g = np.empty((s.size, 3), dtype=s.dtype)
    small = np.abs(s) < _SERIES_THETA**2
    if np.any(small):
        powers = s[small][:, None] ** np.arange(_SERIES_TERMS)
        c[small] = np.einsum("abk,sk->sab", _C_SERIES, powers)
        g[small] = powers @ _G_SERIES.T
    if not np.all(small):
        c[~small], g[~small] = _closed_coefficients(s[~small])
    return c, g


def rodrigues_integrals(omega: np.ndarray, u0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``U(1) = ∫₀¹u`` and ``M = ∫₀¹ u Uᵀ`` for ``u = e^{tΩ}u₀``, ``m ≤ 3``, batched.

    Parameters
    ----------
    omega : numpy.ndarray
        Skew matrices, shape ``(B, m, m)``, ``m ≤ 3``.
    u0 : numpy.ndarray
        Shape ``(B, m)``, same dtype (complex for complex-step derivatives).

    Returns
    -------
    u_int, mm : numpy.ndarray
        Shapes ``(B, m)`` and ``(B, m, m)``.
    """
    w1 = np.einsum("bij,bj->bi", omega, u0)
    w = np.stack([u0, w1, np.einsum("bij,bj->bi", omega, w1)], axis=1)  # (B, 3, m)
    # θ² = ½ Σ Ω_ij² (no conjugation: analytic for the complex step)
    s = 0.5 * np.einsum("bij,bij->b", omega, omega)
    c, g = coefficients(s)
    u_int = np.einsum("bk,bki->bi", g, w)
    mm = np.einsum("bac,bai,bcj->bij", c, w, w)
    return u_int, mm


# --- the free (3, 6) case: the boundary problem reduced by the rotations ---------------------
#
# In the coordinates H = U(t) = ∫u (where the metric is Euclidean) the endpoint of a
# three-input step-2 system with invertible B and an invertible map from the areas to the
# vertical coordinates is (H(1), w) with w = ½∫ H × u dt the area vector (free (3,6)
# group).  A normal geodesic with Ω = θ[e]_× (axis e, angle θ ∉ 2πℤ) from 0 to
# x = H(1) is a straight motion α = x·e along e plus a circular arc of chord
# x_⊥ = x − αe in the plane ⊥ e, and
#
#     w = |x_⊥|² q(θ) e − ½ α κ(θ) x_⊥,   q = (θ − sin θ)/(8 sin²(θ/2)),   κ = 2/θ − cot(θ/2)
#
# (planar part: Dido's segment area; cross part: ½ α e × (c(1) − 2∫c) with c the arc).
# So w ∈ span{e, x}: the axis lies in the plane of x and w, and with e = cos φ p₁ + sin φ p₂
# (p₁ = x/|x|, p₂ ⊥ p₁ in that plane) the six equations reduce to two in (φ, θ):
#
#     w/|x|² = (sin²φ cos φ (q − κ/2),  sin³φ q + ½ sin φ cos²φ κ),
#
# of length |x|·(cos²φ + sin²φ (θ/(2 sin(θ/2)))²)^½.  The SO(3)-equivariance of the
# endpoint map is what removes the other unknowns.  Minimisers with θ beyond 2π occur
# (κ < 0 there; a goal with w ∥ x needs it), so θ ranges over (0, 4π).

#: Largest rotation angle of the reduced search.
_THETA_MAX = 4 * math.pi


def _q_kappa(theta: np.ndarray) -> tuple[np.ndarray, ...]:
    """``q, κ, q', κ'`` at ``θ`` (series below 0.05: ``θ/12 + θ³/360``, ``θ/6 + θ³/360``)."""
    small = theta < 0.05
    any_small = bool(np.any(small))
    t = np.where(small, 1.0, theta) if any_small else theta
    sn, half = np.sin(t), np.sin(t / 2)
    one_c = 2 * half * half  # 1 − cos θ without cancellation near 2πℤ
    q = (t - sn) / (4 * one_c)
    dq = (one_c * one_c - (t - sn) * sn) / (4 * one_c * one_c)
    kappa = 2 / t - np.cos(t / 2) / half
    dkappa = -2 / t**2 + 1 / one_c
    if not any_small:
        return q, kappa, dq, dkappa
    th2 = theta * theta
    return (
        np.where(small, theta / 12 + theta * th2 / 360, q),
        np.where(small, theta / 6 + theta * th2 / 360, kappa),
        np.where(small, 1 / 12 + th2 / 120, dq),
        np.where(small, 1 / 6 + th2 / 120, dkappa),
    )


def _tables() -> tuple[
    np.ndarray, np.ndarray, np.ndarray, tuple[tuple[np.ndarray, np.ndarray, np.ndarray], ...]
]:
    """``φ`` scan points, and ``(κ, θ, q)`` tables of the branches ``(0, 2π)``, ``(2π, 4π)``.

    ``κ`` increases on each branch (``κ' = 1/(2 sin²(θ/2)) − 2/θ² > 0``): from 0 to ∞
    on the first, from −∞ to ∞ on the second, so ``θ = κ⁻¹(·)`` is an interpolation.
    """
    near = 10.0 ** (-np.arange(6, 40) / 3)  # geometric towards the ends
    base = np.linspace(-math.pi, math.pi, 361)[1:-1]
    phi = np.unique(np.concatenate([
        base + math.pi / 720, near, -near, math.pi - near, near - math.pi,
        math.pi / 2 + near[:12], math.pi / 2 - near[:12], -math.pi / 2 + near[:12],
        -math.pi / 2 - near[:12],
    ]))
    unit = np.unique(np.concatenate([np.linspace(0, 1, 201)[1:-1], near, 1 - near]))
    tables: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    for lo in (0.0, 2 * math.pi):
        theta = lo + 2 * math.pi * unit
        q, kappa, _, _ = _q_kappa(theta)
        tables.append((kappa, theta, q))
    return phi, np.sin(phi), np.cos(phi), tuple(tables)


#: The φ scan (with its sines and cosines) and per branch the tables ``(κ, θ, q)``.
_SCAN_PHI, _SCAN_SIN, _SCAN_COS, _BRANCHES = _tables()
#: Offsets ``θ − 2πk`` of the seeds along the helix limit.
_HELIX_DELTAS = np.concatenate([10.0 ** (-np.arange(1, 31) / 3),
                                -(10.0 ** (-np.arange(1, 31) / 3))])


def _reduced(phi: np.ndarray, theta: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, ...]:
    """Residual of the reduced equations and its Jacobian in ``(φ, θ)``."""
    q, kappa, dq, dkappa = _q_kappa(theta)
    s, c = np.sin(phi), np.cos(phi)
    f1 = s * s * c * (q - kappa / 2) - target[0]
    f2 = s**3 * q + s * c * c * kappa / 2 - target[1]
    f1_p = (2 * s * c * c - s**3) * (q - kappa / 2)
    f2_p = 3 * s * s * c * q + (c**3 - 2 * s * s * c) * kappa / 2
    f1_t = s * s * c * (dq - dkappa / 2)
    f2_t = s**3 * dq + s * c * c * dkappa / 2
    return f1, f2, f1_p, f1_t, f2_p, f2_t


def reduced_free3_solutions(target: np.ndarray, newton_steps: int = 12) -> np.ndarray:
    """The solutions ``(φ, θ)`` of the reduced free (3,6) problem, shortest first.

    Parameters
    ----------
    target : numpy.ndarray
        ``w/|x|²`` in the basis ``(p₁, p₂)``, shape ``(2,)``.
    newton_steps : int
        Most damped Newton steps from every seed (the sign changes on the φ
        scan, the planar-arc, circle and helix limits).

    Returns
    -------
    numpy.ndarray
        Shape ``(K, 3)``: rows ``(φ, θ, length/|x|)`` of the solutions reached
        (residual ``≤ 1e-10·(1 + |target|)``, or ``1e-7`` for seeds still
        converging after the last step: starts to be polished), sorted by
        length; possibly empty.
    """
    w1, w2 = float(target[0]), float(target[1])
    # seeds: for a given φ the two equations are linear in (q, κ) —
    # q = (w₁ cos φ + w₂ sin φ)/sin²φ, κ = 2(w₂ cos φ − w₁ sin φ)/(sin φ cos φ) — so the
    # solutions are where q(κ⁻¹(κ(φ))) = q(φ) on a branch: sign changes on the φ scan
    sn, cs = _SCAN_SIN, _SCAN_COS
    q_goal = (w1 * cs + w2 * sn) / (sn * sn)
    k_goal = 2 * (w2 * cs - w1 * sn) / (sn * cs)
    seeds_p, seeds_t = [], []
    for kappa_table, theta_table, q_table in _BRANCHES:
        inside = (k_goal > kappa_table[0]) & (k_goal < kappa_table[-1])
        gap = np.where(inside, np.interp(k_goal, kappa_table, q_table) - q_goal, np.nan)
        flip = np.flatnonzero(gap[:-1] * gap[1:] <= 0)
        seeds_p.append((_SCAN_PHI[flip] + _SCAN_PHI[flip + 1]) / 2)
        seeds_t.append(np.interp((k_goal[flip] + k_goal[flip + 1]) / 2, kappa_table, theta_table))
    # φ = ±π/2 (e ⊥ x) is where that elimination divides by 0: w₁ = 0 and the planar
    # (Heisenberg) arc q(θ) = |w₂|, seeded on the first branch
    heis = float(np.interp(abs(w2), _BRANCHES[0][2], _BRANCHES[0][1]))
    seeds_p.append(np.array([math.copysign(math.pi / 2, w2 if w2 else 1.0)]))
    seeds_t.append(np.array([heis]))
    # |w| ≫ |x|²: the axis near w and a near-full circle of area ≈ |w| (q = |w|/sin²φ)
    along = math.atan2(w2, w1)
    big = math.hypot(w1, w2) / max(math.sin(along) ** 2, 1e-300)
    seeds_p.append(np.array([along]))
    seeds_t.append(np.array([float(np.interp(big, _BRANCHES[0][2], _BRANCHES[0][1]))]))
    # θ → 2πk, φ → 0 (or π) with φ/(θ − 2πk) = ρ: the straight motion along x plus k full
    # circles (the helices), reached on the parabola w₂² = |w₁|/(kπ), w₁ = kπρ², w₂ = −ρ,
    # where the elimination above is singular: seeds along that limit
    for sign, base in ((1.0, 0.0), (-1.0, math.pi)):
        v1, v2 = sign * w1, sign * w2
        for k in (1, 2):
            if v1 > 0:
                rho = -math.copysign(math.sqrt(v1 / (k * math.pi)), v2)
                deltas = _HELIX_DELTAS if k == 1 else -_HELIX_DELTAS[_HELIX_DELTAS > 0]
                seeds_p.append(base + rho * deltas)
                seeds_t.append(2 * math.pi * k + deltas)
    p, t = np.concatenate(seeds_p), np.concatenate(seeds_t)
    p = np.mod(p + math.pi, 2 * math.pi) - math.pi
    scale = 1 + float(np.hypot(*target))
    done_p, done_t = [], []
    previous = np.full(p.shape, np.inf)
    with np.errstate(all="ignore"):
        for step in range(newton_steps + 1):
            f1, f2, a, b, c, d = _reduced(p, t, target)
            r = np.hypot(f1, f2)
            # finished: converged (kept, polished afterwards) or not converging (dropped)
            conv = r <= 1e-10 * scale
            done_p.append(p[conv])
            done_t.append(t[conv])
            # (after a damped start, Newton's steps are expected to halve the residual)
            go = ~conv & (r < previous * (1.0 if step < 4 else 0.5))
            if not np.any(go):
                break
            p, t, f1, f2, a, b, c, d = (z[go] for z in (p, t, f1, f2, a, b, c, d))
            previous = r[go]
            det = a * d - b * c
            dp = -(d * f1 - b * f2) / det
            dt = -(-c * f1 + a * f2) / det
            # damped: θ stays inside its interval between multiples of 2π (at most
            # halfway to its ends), |Δφ| ≤ 0.3
            k = np.floor(t / (2 * math.pi))
            room = np.where(dt > 0, 2 * math.pi * (k + 1) - t, t - 2 * math.pi * k) / 2
            factor = np.minimum(1.0, np.minimum(room / np.abs(dt), 0.3 / np.abs(dp)))
            factor = np.where(np.isfinite(factor), factor, 0.0)
            p = p + np.where(factor > 0, factor * dp, 0.0)
            t = t + np.where(factor > 0, factor * dt, 0.0)
        # the last iterates not yet at 1e-10 but close enough to be polished
        near = previous <= 1e-7 * scale if p.size == previous.size else np.zeros(p.size, bool)
        p = np.concatenate([*done_p, p[near]])
        t = np.concatenate([*done_t, t[near]])
        ok = (t > 0) & (t < _THETA_MAX)
        p, t = p[ok], t[ok]
        stretch = t / (2 * np.sin(t / 2))
        length = np.sqrt(np.cos(p) ** 2 + np.sin(p) ** 2 * stretch**2)
    order = np.argsort(length)
    return np.stack([p[order], t[order], length[order]], axis=-1)


def _cross_matrix(e: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]])


def _vee(x: np.ndarray) -> np.ndarray:
    return np.array([x[..., 2, 1], x[..., 0, 2], x[..., 1, 0]]).T


#: Condition number above which a structure is not treated as the free (3,6) group.
_MAX_CONDITION = 1e8


def free3_maps(b: np.ndarray, skew: np.ndarray) -> tuple[np.ndarray, ...] | None:
    """``B⁻¹``, the inverse area map and the inverse covector map of a free (3,6)-type system.

    Parameters
    ----------
    b, skew : numpy.ndarray
        ``B`` (``3×3``) and the skew brackets (``3×3×3``) of
        :class:`~nilpotent.planning.geodesic.Step2Structure`.

    Returns
    -------
    tuple of numpy.ndarray or None
        ``None`` unless ``m = n₁ = n₂ = 3`` with all three maps well conditioned.
    """
    if b.shape != (3, 3) or skew.shape != (3, 3, 3):
        return None
    area_map = np.stack([np.einsum("kij,ij->k", skew, _cross_matrix(e)) for e in np.eye(3)], 1)
    covector_map = _vee(skew).T  # column k: the axis vector of skew_k
    maps = (b, area_map, covector_map)
    if max(float(np.linalg.cond(x)) for x in maps) > _MAX_CONDITION:
        return None
    return tuple(np.linalg.inv(x) for x in maps)


def free3_starts(
    maps: tuple[np.ndarray, ...], a: np.ndarray, t: np.ndarray,
    y0: tuple[np.ndarray, np.ndarray], y1: tuple[np.ndarray, np.ndarray], count: int = 3,
) -> np.ndarray | None:
    """Near-exact starts ``(u₀, λ)`` for a system equivalent to the free (3,6) group.

    The goal is mapped to ``(x, w)`` (``x = B⁻¹Δh``, ``w`` the area vector the
    vertical displacement asks for, after the part fixed by ``x`` and the start),
    the reduced problem is solved (:func:`reduced_free3_solutions`) and its
    ``count`` shortest solutions are mapped back:
    ``Ω = θ[e]_×``, ``λ`` from ``Σ_k λ_k skew_k = Ω``, ``u₀ = Φ(Ω)⁻¹x`` with
    ``Φ = ∫₀¹e^{sΩ}ds``.  ``x = 0`` (a full circle in the plane ⊥ w, length
    ``√(4π|w|)``) and ``w = 0`` (the straight segment) are handled directly;
    for ``|x|² ≤ 10⁻¹²|w|`` that circle is a start too.

    Parameters
    ----------
    maps : tuple of numpy.ndarray
        :func:`free3_maps` of the system.
    a, t : numpy.ndarray
        The arrays of :class:`~nilpotent.planning.geodesic.Step2Structure`.
    y0, y1 : tuple of numpy.ndarray
        ``(h, v)`` of the start and the goal (unit-size problem).
    count : int
        Most starts returned.

    Returns
    -------
    numpy.ndarray or None
        Rows ``(u₀, λ)``; ``None`` when the reduced problem has no solution found.
    """
    b_inv, area_inv, covector_inv = maps
    (h0, v0), (h1, v1) = y0, y1
    x = b_inv @ (h1 - h0)
    sym = (t + np.transpose(t, (0, 2, 1))) / 2
    rhs = v1 - v0 - np.einsum("kil,l,i->k", a, h0, x) - 0.5 * np.einsum("i,kij,j->k", x, sym, x)
    # Σ_ij t_kij M_ij = ½xᵀS_k x + ½ Σ_ij skew_kij [w]_×ij  (M's skew part is [w]_×)
    w = 2 * area_inv @ rhs
    nx, nw = float(np.linalg.norm(x)), float(np.linalg.norm(w))
    if nw <= 1e-15 * nx * nx:
        return np.concatenate([x, np.zeros(3)])[None, :]
    circle = None
    if nx * nx <= 1e-12 * nw:  # (near) x = 0: the circle of area |w| in the plane ⊥ w
        axis = w / nw
        # the arc of angle θ → 2π starts against its chord (rotated by −θ/2): u₀ ∥ −x_⊥
        side = axis * (x @ axis) - x
        if not np.linalg.norm(side) > 1e-300:
            side = np.cross(axis, np.eye(3)[int(np.argmin(np.abs(axis)))])
        u0 = math.sqrt(4 * math.pi * nw) * side / np.linalg.norm(side)
        circle = np.concatenate([u0, covector_inv @ (2 * math.pi * axis)])[None, :]
        if nx == 0.0:
            return circle
    p1 = x / nx
    w_perp = w - (w @ p1) * p1
    if np.linalg.norm(w_perp) > 1e-12 * nw:
        p2 = w_perp / np.linalg.norm(w_perp)
    else:  # w ∥ x: every plane through x is one (rotations about x)
        p2 = np.cross(p1, np.eye(3)[int(np.argmin(np.abs(p1)))])
        p2 /= np.linalg.norm(p2)
    sols = reduced_free3_solutions(np.array([w @ p1, w @ p2]) / (nx * nx))
    if sols.size == 0:
        return circle
    keep = [0]
    for r in range(1, len(sols)):
        if len(keep) < count and abs(sols[r, 2] - sols[keep[-1], 2]) > 1e-9 * sols[r, 2]:
            keep.append(r)
    phi, theta = sols[keep, 0], sols[keep, 1]
    axes = np.cos(phi)[:, None] * p1 + np.sin(phi)[:, None] * p2
    omega = theta[:, None, None] * np.array([_cross_matrix(e) for e in axes])
    _, g = coefficients(theta * theta)
    flow = np.eye(3) + g[:, 1, None, None] * omega + g[:, 2, None, None] * (omega @ omega)
    u0 = np.linalg.solve(flow, np.broadcast_to(x, (len(keep), 3))[:, :, None])[:, :, 0]
    starts = np.concatenate([u0, (theta[:, None] * axes) @ covector_inv.T], axis=1)
    # for |x|² ≪ |w| the reduced equations are ill-conditioned (θ within ~|x| of 2π):
    # the circle is offered as well, Levenberg–Marquardt takes it to the goal
    return starts if circle is None else np.concatenate([circle, starts])
