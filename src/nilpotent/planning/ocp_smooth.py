r"""Smooth controls for the optimal-control refinement (:mod:`nilpotent.planning.ocp`).

The refinement's controls are piecewise constant on ``N`` intervals: their inputs jump
at every interval boundary, so a trajectory re-timed under acceleration bounds
(:mod:`nilpotent.planning.timing`) stops at each of them.  With ``smooth`` (option
:attr:`~nilpotent.planning.ocp.OcpRefine.smooth`) each candidate is solved once more
with every input a cosine series on the horizon ``[0, 1]``,

.. math::

    u_i(t) = c_{i,0} + \sum_{k=1}^{K} c_{i,k} \cos(k \pi t),

a complete orthogonal basis of the square-integrable functions on ``[0, 1]`` (the
series of the even extension: no periodicity is imposed, the values at ``t = 0`` and
``t = 1`` are free).  The weighted energy is exactly
``Σ_i w_i² (c_{i,0}² + ½ Σ_k c_{i,k}²)`` (Parseval).  IPOPT starts from the projection
of the piecewise-constant solution and its states, on the same multiple-shooting grid
(RK4 with the inputs evaluated at each stage's time), with the same limits; the endpoint
is then corrected by Gauss–Newton on the product's re-simulation.  The result is one
segment of the ``nilpotent/plan@1`` format (``duration`` 1, ``omega`` ``π``, the
``cos`` coefficients): inputs continuous inside the plan, so a re-timed trajectory
rests only at the two ends and where an input's sign change makes it (a reversal).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from nilpotent.core.model.system import ControlSystem
from nilpotent.numeric.settings import IntegrationSettings
from nilpotent.numeric.signals import InputSignal
from nilpotent.planning import budget
from nilpotent.planning.casadi_tree import to_casadi
from nilpotent.planning.controls import Segment
from nilpotent.planning.simulation import simulate_candidates
from nilpotent.planning.verify import Checker

__all__ = ["HARMONICS", "correct_endpoint", "cosine_segment", "limit_constraints", "project",
           "rk4_interval", "smooth_controls"]

#: Harmonics ``K`` of the cosine series of each input.
HARMONICS = 16


def limit_constraints(ca: Any, opti: Any, system: ControlSystem, checker: Checker,
                      x0: np.ndarray, xg: np.ndarray, subs: Any, margin: float) -> None:
    """Impose the box and relative limits on the states ``subs`` (``n × S``), tightened by
    ``margin × max(1, hi − lo)``, less where the start or the goal is nearer the limit (an
    end on a limit keeps it exactly, else the problem would be infeasible)."""
    limits = checker.limits
    assert limits is not None

    def pads(lo: float, hi: float, ends: np.ndarray) -> tuple[float, float]:
        pad = margin * max(1.0, hi - lo)
        return (max(0.0, min(pad, float(np.min(ends)) - lo)),
                max(0.0, min(pad, hi - float(np.max(ends)))))

    names = system.coordinate_names
    for name, lo, hi in limits.bounds:
        j = names.index(name)
        pad_lo, pad_hi = pads(lo, hi, np.array([x0[j], xg[j]]))
        opti.subject_to(opti.bounded(lo + pad_lo, subs[j, :], hi - pad_hi))
    if limits.relative:
        x = ca.SX.sym("x", system.n)
        symbols = {c: x[i] for i, c in enumerate(system.coordinates)}
        rel = ca.Function("g", [x], [ca.vertcat(*[to_casadi(e, symbols)
                                                  for _, e, _, _ in limits.relative])])
        values = rel.map(subs.shape[1])(subs)
        at_ends = np.array(rel.map(2)(np.column_stack([x0, xg])), dtype=float)
        for r, (_, _, lo, hi) in enumerate(limits.relative):
            pad_lo, pad_hi = pads(lo, hi, at_ends[r])
            opti.subject_to(opti.bounded(lo + pad_lo, values[r, :], hi - pad_hi))


def correct_endpoint(system: ControlSystem, x0: np.ndarray, xg: np.ndarray,
                     params: np.ndarray, jac: Any, to_segments: Any, tol: float,
                     settings: IntegrationSettings, corrections: int,
                     what: str) -> tuple[np.ndarray, float]:
    """Gauss–Newton on the endpoint of the controls ``to_segments(params)``: the residual
    is the product's re-simulation (adaptive, the planning settings), the Jacobian
    ``jac(params)`` that of a model of it (the RK4 roll-out) with respect to
    ``vec(params)`` (column-major); at most ``corrections`` steps, each kept only if it
    reduces the error, until the error is ``tol / 10``.  Returns ``(params, error)``."""
    def error_of(c: np.ndarray) -> tuple[np.ndarray, float]:
        reached = simulate_candidates(system, x0, [to_segments(c)], settings)[0]
        err = float(np.linalg.norm(reached - xg))
        return reached, err if math.isfinite(err) else math.inf

    reached, err = error_of(params)
    rows, cols = params.shape
    for _ in range(corrections):
        if err <= tol / 10:
            break
        budget.check(what)
        j = np.array(jac(params), dtype=float)
        delta, *_ = np.linalg.lstsq(j, reached - xg, rcond=None)
        trial = params - delta.reshape(cols, rows).T  # vec() is column-major
        r_trial, e_trial = error_of(trial)
        if not e_trial < err:
            break
        params, reached, err = trial, r_trial, e_trial
    return params, err


def project(u: np.ndarray, harmonics: int = HARMONICS) -> np.ndarray:
    """Cosine-series coefficients ``(m, K + 1)`` of piecewise-constant controls ``u (m, N)``
    on ``N`` equal intervals of ``[0, 1]`` (exact integrals: ``c_0`` the mean,
    ``c_k = 2 ∫ u cos(kπt) dt``)."""
    m, n_int = u.shape
    edges = np.linspace(0.0, 1.0, n_int + 1)
    out = np.zeros((m, harmonics + 1))
    out[:, 0] = u.mean(axis=1)
    for k in range(1, harmonics + 1):
        w = np.diff(np.sin(k * math.pi * edges)) / (k * math.pi)  # ∫ cos(kπt) per interval
        out[:, k] = 2.0 * (u @ w)
    return out


def cosine_segment(coeffs: np.ndarray) -> Segment:
    """One segment of duration 1, ``omega = π``: input ``i`` is ``coeffs[i, 0] + Σ_k
    coeffs[i, k] cos(kπt)``."""
    return Segment(1.0, math.pi, tuple(InputSignal(float(c[0]), tuple(float(v) for v in c[1:]))
                                       for c in coeffs))


def rk4_interval(ca: Any, system: ControlSystem, x: Any, inputs: Any, t0: Any, h: float,
                 substeps: int) -> tuple[Any, list[Any]]:
    """``substeps`` classical RK4 steps of ``h`` of ``ẋ = Σ u_i X_i(x)`` from the CasADi
    state ``x`` at time ``t0``, the inputs ``inputs(t)`` evaluated at each stage's time
    (constant inputs: a function that ignores ``t``); ``(end state, sub-step states)``."""
    n, m = system.n, system.m
    xf, v = ca.SX.sym("xf", n), ca.SX.sym("v", m)
    symbols = {s: xf[i] for i, s in enumerate(system.coordinates)}
    cols = [ca.vertcat(*[to_casadi(e, symbols) for e in fld])
            for fld in system.specialized_fields]
    f = ca.Function("f", [xf, v], [sum((cols[i] * v[i] for i in range(1, m)), cols[0] * v[0])])
    z, subs = x, []
    for j in range(substeps):
        t = t0 + j * h
        u0, uh, u1 = inputs(t), inputs(t + h / 2), inputs(t + h)
        k1 = f(z, u0)
        k2 = f(z + h / 2 * k1, uh)
        k3 = f(z + h / 2 * k2, uh)
        k4 = f(z + h * k3, u1)
        z = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        subs.append(z)
    return z, subs


def _cosine_flow(ca: Any, system: ControlSystem, n_int: int, harmonics: int,
                 substeps: int) -> Any:
    """One interval's RK4 flow ``(x, C, t0) ↦ (x⁺, sub-step states)`` with the inputs
    ``C · (1, cos πt, …, cos Kπt)`` evaluated at each stage's time."""
    x = ca.SX.sym("x", system.n)
    c = ca.SX.sym("c", system.m, harmonics + 1)
    t0 = ca.SX.sym("t0")

    def inputs(t: Any) -> Any:
        return c @ ca.vertcat(1, *[ca.cos(k * math.pi * t) for k in range(1, harmonics + 1)])

    z, subs = rk4_interval(ca, system, x, inputs, t0, 1.0 / (n_int * substeps), substeps)
    return ca.Function("cosine_step", [x, c, t0], [z, ca.horzcat(*subs)])


def smooth_controls(
    ca: Any, checker: Checker, x0: np.ndarray, xg: np.ndarray, u: np.ndarray,
    states: np.ndarray | None, weights: np.ndarray, tol: float, settings: IntegrationSettings,
    *, substeps: int, margin: float, iterations: int, corrections: int, share: float,
    harmonics: int = HARMONICS,
) -> tuple[Segment | None, float, str]:
    """The cosine-series controls nearest in energy to the piecewise-constant ``u (m, N)``.

    Returns ``(segment, error, reason)``: the one-segment controls and their re-simulated
    distance to ``xg`` (the product's integrator), or ``(None, inf, why)`` when IPOPT found
    no solution or the roll-out is not finite.  ``states (n, N + 1)``: the warm start's
    states (default: the roll-out of the projection).
    """
    system = checker.system
    m, n_int = u.shape
    step = _cosine_flow(ca, system, n_int, harmonics, substeps)
    times = np.arange(n_int) / n_int
    c0 = project(u, harmonics)
    opti = ca.Opti()
    xs = opti.variable(system.n, n_int + 1)
    cs = opti.variable(m, harmonics + 1)
    scale = np.concatenate([[1.0], np.full(harmonics, 0.5)])
    opti.minimize(ca.sum1(ca.sum2((ca.DM(weights[:, None] ** 2 * scale[None, :])) * cs ** 2)))
    nxt, subs = step.map(n_int)(xs[:, :n_int], cs, ca.DM(times).T)
    opti.subject_to(xs[:, 0] == x0)
    opti.subject_to(xs[:, n_int] == xg)
    opti.subject_to(xs[:, 1:] == nxt)
    limit_constraints(ca, opti, system, checker, x0, xg, subs, margin)
    if states is None:
        roll = step.mapaccum(n_int)(x0, c0, ca.DM(times).T)
        states = np.hstack([x0[:, None], np.array(roll[0])])
    if not np.all(np.isfinite(states)):
        return None, math.inf, "the cosine series' warm start is not finite"
    opti.set_initial(cs, c0)
    opti.set_initial(xs, states)
    opts: dict[str, Any] = {"print_level": 0, "max_iter": iterations, "tol": 1e-10, "sb": "yes"}
    left = budget.seconds_left()
    if math.isfinite(left):
        opts["max_wall_time"] = max(0.1, share * left)
    opti.solver("ipopt", {"print_time": False}, opts)
    try:
        sol = opti.solve()
    except RuntimeError:
        status = str(opti.stats().get("return_status", "failed"))
        return None, math.inf, f"IPOPT found no cosine-series controls ({status})"
    coeffs = np.array(sol.value(cs), dtype=float).reshape(m, harmonics + 1)
    # endpoint correction: Gauss–Newton, residual from the product's re-simulation
    sym = ca.SX.sym("c", m, harmonics + 1)
    end = step.mapaccum(n_int)(ca.DM(x0), sym, ca.DM(times).T)[0][:, -1]
    jac = ca.Function("cosine_endpoint_jacobian", [sym], [ca.jacobian(end, ca.vec(sym))])
    coeffs, err = correct_endpoint(
        system, x0, xg, coeffs, jac, lambda c: [cosine_segment(c)], tol, settings, corrections,
        "correcting the endpoint of the smooth refined controls")
    return cosine_segment(coeffs), err, ""
