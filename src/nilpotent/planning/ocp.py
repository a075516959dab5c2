r"""Refinement of a local plan by direct optimal control of the true system (CasADi + IPOPT).

The nilpotent plan reaches the goal but is not the shortest motion of the *true*
system (its geodesics are those of the approximation, or loops).  This module
solves, on the true fields, the fixed-horizon energy problem

.. math::

    \min_u \int_0^1 \|u(t)\|_2^2\,dt \quad\text{s.t.}\quad
    \dot x = \sum_i u_i X_i(x),\; x(0) = \text{start},\; x(1) = \text{goal},\;
    \text{limits}(x(t)),

whose minimisers are the length minimisers parametrised at constant speed
(Cauchy–Schwarz: ``L² ≤ E`` on ``[0, 1]``, with equality exactly at constant
speed), so it minimises the sub-Riemannian length ``∫‖u‖ dt`` (``X_i``
orthonormal) without the non-smooth norm.

Discretisation: multiple shooting on ``N`` equal intervals (:data:`INTERVALS`),
controls piecewise constant (each interval becomes one segment of constant
inputs of the ``nilpotent/plan@1`` format), the flow of each interval by
:data:`SUBSTEPS` classical RK4 steps; the box limits (and relative limits) are
imposed, tightened by :data:`LIMIT_MARGIN`, at every node and every RK4 sub-step
state.  IPOPT (exact Hessian by CasADi's automatic differentiation) is started
from the nilpotent plan (its controls averaged on each interval, time rescaled to
``[0, 1]``, the states its RK4 roll-out).

RK4 is not the product's integrator: after IPOPT the endpoint is corrected by
minimum-norm Gauss–Newton steps whose residual is the product's own re-simulation
(adaptive DOP853 at rtol 1e-12, :func:`~nilpotent.planning.simulation.simulate_candidates`)
and whose Jacobian is the (exact) derivative of the RK4 roll-out, close to the
true one; at an optimum the energy gradient lies in the row space of that
Jacobian, so these steps change the length only to second order.  The result
is then verified exactly as every plan is
(:func:`~nilpotent.planning.verify.verify_segments`: dense re-simulation, the
goal within ``tol``, limits, obstacles, singular margin), and kept only if it
verifies and is shorter; otherwise the nilpotent plan stays, with the reason.

Obstacles and the singular margin are not constraints of the optimal control
problem (only the limits are): a refined motion that touches an obstacle is
refused by the verification.  Input bounds are not constraints either: the
system is driftless, so a refined path meets any speed bound by being re-timed
(slowed down), which changes neither the path nor its length.

The fields reach CasADi through :func:`to_casadi`, a walk of the sympy
expression tree with a fixed table of operations (an output target, like the
LaTeX printer, not a second numerical compiler of the product: CasADi needs its
own symbolic graph to differentiate for IPOPT, and nothing here generates or
evaluates source text).  CasADi is the optional extra ``ocp``
(``pip install "nilpotent[ocp]"``), imported only when a refinement is asked for.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import (
    ComputationLimitError,
    IntegrationError,
    MissingExtraError,
    OptionError,
)
from nilpotent.numeric.settings import IntegrationSettings
from nilpotent.planning import budget
from nilpotent.planning.controls import Segment, constant_segment
from nilpotent.planning.geodesic import control_length
from nilpotent.planning.simulation import PLANNING_SETTINGS, simulate_candidates
from nilpotent.planning.verify import Checker, Verification, verify_segments
from nilpotent.strict_json import json_object

__all__ = [
    "INTERVALS", "REFINEMENTS", "Refinement", "check_refine", "refine_route", "refine_segments",
    "to_casadi",
]

#: Values of ``refine`` (``--refine``): no refinement, or direct optimal control.
REFINEMENTS = ("none", "ocp")
#: Shooting intervals ``N`` of the horizon ``[0, 1]`` (piecewise-constant controls).
INTERVALS = 48
#: RK4 steps per interval.
SUBSTEPS = 4
#: Limits are imposed tightened by this (times ``max(1, hi − lo)``): room for the endpoint
#: correction and for the motion between RK4 sub-step states.
LIMIT_MARGIN = 1e-6
#: Most IPOPT iterations, and most Gauss–Newton steps of the endpoint correction.
IPOPT_ITERATIONS = 500
CORRECTIONS = 8
#: Samples per segment of the verification (as the global planner's).
VERIFY_POINTS = 100

_INSTALL = 'pip install "nilpotent[ocp]"'


@dataclass(frozen=True)
class Refinement:
    """What the optimal-control refinement did (the plan JSON's ``refinement`` object).

    Attributes
    ----------
    method : str
        ``"ocp"``.
    applied : bool
        Whether the refined controls replaced the plan's.
    reason : str
        Why not (``""`` when applied).
    length_before : float
        ``∫‖u‖ dt`` of the nilpotent plan.
    length_refined : float or None
        ``∫‖u‖ dt`` of the refined controls (``None`` when IPOPT gave none).
    intervals : int
        Shooting intervals ``N``.
    solver_status : str
        IPOPT's return status (``""`` when it did not run).
    solver_iterations : int
        IPOPT iterations.
    refined_error : float or None
        Distance to the goal of the re-simulated refined controls.
    seconds : float
        Wall-clock time of the refinement, verification included.
    verification : Verification or None
        The dense re-simulation of the refined controls when they were applied (the
        plan's own verification; not in :meth:`to_json`).
    """

    method: str
    applied: bool
    reason: str
    length_before: float
    length_refined: float | None = None
    intervals: int = INTERVALS
    solver_status: str = ""
    solver_iterations: int = 0
    refined_error: float | None = None
    seconds: float = 0.0
    verification: Verification | None = field(default=None, repr=False, compare=False)

    def to_json(self) -> dict[str, Any]:
        """The fields as a strict-JSON dict (:func:`nilpotent.strict_json.json_object`)."""
        return json_object({
            "method": self.method, "applied": self.applied, "reason": self.reason,
            "length_before": self.length_before, "length_refined": self.length_refined,
            "intervals": self.intervals, "solver_status": self.solver_status,
            "solver_iterations": self.solver_iterations, "refined_error": self.refined_error,
            "seconds": self.seconds,
        })


def _casadi() -> Any:
    try:
        import casadi  # pyright: ignore[reportMissingImports]  (the optional [ocp] extra)
    except ImportError:
        raise MissingExtraError(
            f"--refine ocp (refine='ocp') needs CasADi, which is not installed: {_INSTALL}"
        ) from None
    return casadi


def check_refine(refine: str) -> None:
    """Raise unless ``refine`` is one of :data:`REFINEMENTS` and what it needs is installed.

    Parameters
    ----------
    refine : str
        ``"none"`` or ``"ocp"``.

    Raises
    ------
    OptionError
        An unknown value.
    MissingExtraError
        ``"ocp"`` without CasADi (the ``ocp`` extra).
    """
    if refine not in REFINEMENTS:
        raise OptionError(
            f"--refine must be {' or '.join(REFINEMENTS)}; got {str(refine)[:60]!r}")
    if refine == "ocp":
        _casadi()


def _functions(ca: Any) -> dict[type, Any]:
    return {
        sp.sin: ca.sin, sp.cos: ca.cos, sp.tan: ca.tan, sp.exp: ca.exp, sp.log: ca.log,
        sp.atan: ca.atan, sp.asin: ca.asin, sp.acos: ca.acos, sp.sinh: ca.sinh,
        sp.cosh: ca.cosh, sp.tanh: ca.tanh, sp.Abs: ca.fabs, sp.sign: ca.sign,
        sp.sec: lambda a: 1 / ca.cos(a), sp.csc: lambda a: 1 / ca.sin(a),
        sp.cot: lambda a: 1 / ca.tan(a),
    }


def to_casadi(expr: sp.Basic | float, symbols: Mapping[sp.Symbol, Any]) -> Any:
    """The CasADi expression of a sympy expression (a walk of its tree, shared parts once).

    Parameters
    ----------
    expr : sympy.Basic or float
        Numbers, the symbols of ``symbols``, ``+``, ``*``, powers and the functions
        ``sin cos tan exp log atan atan2 asin acos sinh cosh tanh Abs sign sec csc cot
        Min Max``.
    symbols : mapping
        sympy symbol → CasADi expression (``SX`` or ``MX``).

    Returns
    -------
    casadi.SX or casadi.MX

    Raises
    ------
    OptionError
        A symbol not in ``symbols`` (an unsubstituted parameter) or an operation outside
        the table.
    MissingExtraError
        CasADi is not installed.
    TypeError
        ``expr`` is neither a sympy expression nor a number (text is never parsed here).
    """
    ca = _casadi()
    table = _functions(ca)
    memo: dict[sp.Basic, Any] = {}

    def walk(e: sp.Basic) -> Any:
        if e in memo:
            return memo[e]
        if isinstance(e, sp.Symbol):
            if e not in symbols:
                raise OptionError(f"--refine ocp: the fields use {e}, which is no coordinate")
            out = symbols[e]
        elif e.is_number and not e.free_symbols:
            value = complex(sp.N(e, 17))
            if value.imag != 0 or not math.isfinite(value.real):
                raise OptionError(f"--refine ocp: {e} is not a finite real number")
            out = value.real
        elif isinstance(e, sp.Add):
            parts = [walk(a) for a in e.args]
            out = parts[0]
            for p in parts[1:]:
                out = out + p
        elif isinstance(e, sp.Mul):
            parts = [walk(a) for a in e.args]
            out = parts[0]
            for p in parts[1:]:
                out = out * p
        elif isinstance(e, sp.Pow):
            base, exp = e.args
            if exp == sp.Rational(1, 2):
                out = ca.sqrt(walk(base))
            elif isinstance(exp, sp.Integer):
                out = ca.constpow(walk(base), int(exp))
            else:
                out = ca.power(walk(base), walk(exp))
        elif isinstance(e, sp.atan2):
            out = ca.atan2(walk(e.args[0]), walk(e.args[1]))
        elif isinstance(e, sp.Min | sp.Max):
            op = ca.fmin if isinstance(e, sp.Min) else ca.fmax
            parts = [walk(a) for a in e.args]
            out = parts[0]
            for p in parts[1:]:
                out = op(out, p)
        elif type(e) in table and len(e.args) == 1:
            out = table[type(e)](walk(e.args[0]))
        else:
            raise OptionError(
                f"--refine ocp: cannot translate {type(e).__name__} of the fields to CasADi")
        memo[e] = out
        return out

    if isinstance(expr, sp.Basic):
        return walk(expr)
    if isinstance(expr, int | float) and not isinstance(expr, bool):
        return walk(sp.Float(expr) if isinstance(expr, float) else sp.Integer(expr))
    # never text: user text reaches the fields only through the expression grammar
    raise TypeError(f"to_casadi takes a sympy expression or a number, not {type(expr).__name__}")


def _warm_controls(segments: Sequence[Segment], n_int: int, m: int) -> np.ndarray:
    """The controls of ``segments`` on the horizon ``[0, 1]``: their mean on each of
    ``n_int`` intervals (8 Gauss points), times the total duration; ``(m, N)``."""
    durations = np.array([s.duration for s in segments], dtype=float)
    total = float(durations.sum())
    ends = np.cumsum(durations)
    nodes, weights = np.polynomial.legendre.leggauss(8)
    out = np.zeros((m, n_int))
    for k in range(n_int):
        t = total * (k + (nodes + 1) / 2) / n_int
        idx = np.minimum(np.searchsorted(ends, t, side="right"), len(segments) - 1)
        local = t - (ends[idx] - durations[idx])
        vals = np.stack([segments[i].values(float(tl)) for i, tl in zip(idx, local, strict=True)])
        out[:, k] = total * (weights @ vals) / 2
    return out


def _segments(u: np.ndarray) -> list[Segment]:
    n_int = u.shape[1]
    return [constant_segment(u[:, k], 1.0 / n_int) for k in range(n_int)]


def _problem(ca: Any, system: ControlSystem, n_int: int) -> Any:
    """One interval's RK4 flow ``(x, u) ↦ (x⁺, sub-step states)`` (a CasADi Function)."""
    n, m = system.n, system.m
    x = ca.SX.sym("x", n)
    u = ca.SX.sym("u", m)
    symbols = {c: x[i] for i, c in enumerate(system.coordinates)}
    cols = [ca.vertcat(*[to_casadi(e, symbols) for e in field])
            for field in system.specialized_fields]
    f = ca.Function("f", [x, u], [sum((cols[i] * u[i] for i in range(1, m)), cols[0] * u[0])])
    h = 1.0 / (n_int * SUBSTEPS)
    z = x
    subs = []
    for _ in range(SUBSTEPS):
        k1 = f(z, u)
        k2 = f(z + h / 2 * k1, u)
        k3 = f(z + h / 2 * k2, u)
        k4 = f(z + h * k3, u)
        z = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        subs.append(z)
    return ca.Function("step", [x, u], [z, ca.horzcat(*subs)])


def _pads(lo: float, hi: float, ends: np.ndarray) -> tuple[float, float]:
    """How much the limits ``[lo, hi]`` are tightened: :data:`LIMIT_MARGIN` (times
    ``max(1, hi − lo)``), less where the start or the goal (values ``ends``) is closer to
    the limit (an end on a limit keeps it exactly, or the problem would be infeasible)."""
    pad = LIMIT_MARGIN * max(1.0, hi - lo)
    return (max(0.0, min(pad, float(np.min(ends)) - lo)),
            max(0.0, min(pad, hi - float(np.max(ends)))))


def _solve(
    ca: Any, system: ControlSystem, checker: Checker, x0: np.ndarray, xg: np.ndarray,
    u0: np.ndarray, n_int: int,
) -> tuple[np.ndarray | None, str, int, Any]:
    """IPOPT on the multiple-shooting problem: ``(u, status, iterations, step)``."""
    step = _problem(ca, system, n_int)
    limits = checker.limits
    assert limits is not None
    rel = None
    if limits.relative:
        x = ca.SX.sym("x", system.n)
        symbols = {c: x[i] for i, c in enumerate(system.coordinates)}
        rel = ca.Function("g", [x], [ca.vertcat(*[to_casadi(e, symbols)
                                                  for _, e, _, _ in limits.relative])])
    opti = ca.Opti()
    xs = opti.variable(system.n, n_int + 1)
    us = opti.variable(system.m, n_int)
    opti.minimize(ca.sumsqr(us) / n_int)
    nxt, subs = step.map(n_int)(xs[:, :n_int], us)
    opti.subject_to(xs[:, 0] == x0)
    opti.subject_to(xs[:, n_int] == xg)
    opti.subject_to(xs[:, 1:] == nxt)
    names = system.coordinate_names
    for name, lo, hi in limits.bounds:
        j = names.index(name)
        ends = np.array([x0[j], xg[j]])
        pad_lo, pad_hi = _pads(lo, hi, ends)
        opti.subject_to(opti.bounded(lo + pad_lo, subs[j, :], hi - pad_hi))
    if rel is not None:
        values = rel.map(subs.shape[1])(subs)
        at_ends = np.array(rel.map(2)(np.column_stack([x0, xg])), dtype=float)
        for r, (_, _, lo, hi) in enumerate(limits.relative):
            pad_lo, pad_hi = _pads(lo, hi, at_ends[r])
            opti.subject_to(opti.bounded(lo + pad_lo, values[r, :], hi - pad_hi))
    # warm start: the nilpotent plan's controls and their RK4 roll-out
    roll = step.mapaccum(n_int)(x0, u0)
    states = np.hstack([x0[:, None], np.array(roll[0])])
    if not np.all(np.isfinite(states)):
        return None, "the warm start's RK4 roll-out is not finite", 0, step
    opti.set_initial(us, u0)
    opti.set_initial(xs, states)
    left = budget.seconds_left()
    opts: dict[str, Any] = {"print_level": 0, "max_iter": IPOPT_ITERATIONS, "tol": 1e-10,
                            "sb": "yes"}
    if math.isfinite(left):
        opts["max_wall_time"] = max(0.1, 0.8 * left)
    opti.solver("ipopt", {"print_time": False}, opts)
    try:
        sol = opti.solve()
    except RuntimeError:
        stats = opti.stats()
        return None, str(stats.get("return_status", "failed")), int(stats.get("iter_count", 0)), \
            step
    stats = sol.stats()
    u = np.array(sol.value(us), dtype=float).reshape(system.m, n_int)
    return u, str(stats.get("return_status", "")), int(stats.get("iter_count", 0)), step


def _correct(
    ca: Any, system: ControlSystem, step: Any, x0: np.ndarray, xg: np.ndarray,
    u: np.ndarray, tol: float, settings: IntegrationSettings,
) -> tuple[np.ndarray, float]:
    """Gauss–Newton on the product's endpoint map, Jacobian of the RK4 roll-out."""
    m, n_int = u.shape
    us = ca.SX.sym("u", m, n_int)
    end = step.mapaccum(n_int)(ca.DM(x0), us)[0][:, -1]
    jac = ca.Function("endpoint_jacobian", [us], [ca.jacobian(end, ca.vec(us))])

    def error_of(v: np.ndarray) -> tuple[np.ndarray, float]:
        reached = simulate_candidates(system, x0, [_segments(v)], settings)[0]
        err = float(np.linalg.norm(reached - xg))
        return reached, err if math.isfinite(err) else math.inf

    reached, err = error_of(u)
    for _ in range(CORRECTIONS):
        if err <= tol / 10:
            break
        budget.check("correcting the endpoint of the refined controls")
        j = np.array(jac(u), dtype=float)
        delta, *_ = np.linalg.lstsq(j, reached - xg, rcond=None)
        trial = u - delta.reshape(n_int, m).T  # vec(u) is column-major
        r_trial, e_trial = error_of(trial)
        if not e_trial < err:
            break
        u, reached, err = trial, r_trial, e_trial
    return u, err


def refine_segments(
    checker: Checker,
    start: Sequence[float] | np.ndarray,
    goal: Sequence[float] | np.ndarray,
    segments: Sequence[Segment],
    tol: float,
    *,
    intervals: int = INTERVALS,
    settings: IntegrationSettings = PLANNING_SETTINGS,
) -> tuple[list[Segment], Refinement]:
    """Shorter controls from ``start`` to ``goal`` by direct optimal control, if they verify.

    Parameters
    ----------
    checker : Checker
        The system, its limits and world (what the refined motion must respect).
    start, goal : sequence of float
        Model coordinates.
    segments : sequence of Segment
        The plan to refine (the warm start), from ``start`` to within ``tol`` of ``goal``.
    tol : float
        The goal tolerance the refined plan must meet after re-simulation.
    intervals : int
        Shooting intervals ``N`` (the refined plan has ``N`` constant segments of
        duration ``1/N``).
    settings : IntegrationSettings
        How the true system is re-simulated (default
        :data:`~nilpotent.planning.simulation.PLANNING_SETTINGS`).

    Returns
    -------
    segments, refinement
        The refined controls if they verify (goal within ``tol``, admissible) and are
        shorter, else ``segments`` unchanged; and what was done (:class:`Refinement`).

    Raises
    ------
    MissingExtraError
        CasADi is not installed.
    OptionError
        ``intervals`` below 2, or fields CasADi cannot express.
    ComputationLimitError
        The time budget ran out.
    """
    ca = _casadi()
    if not (isinstance(intervals, int) and intervals >= 2):
        raise OptionError(f"intervals must be an integer >= 2, got {intervals!r}")
    t0 = time.perf_counter()
    system = checker.system
    x0 = np.asarray(start, dtype=float)
    xg = np.asarray(goal, dtype=float)
    before = control_length(segments)

    def keep(reason: str, **more: Any) -> tuple[list[Segment], Refinement]:
        return list(segments), Refinement("ocp", False, reason, before, intervals=intervals,
                                          seconds=time.perf_counter() - t0, **more)

    if not segments:
        return keep("the plan has no controls (the start is within tol of the goal)")
    budget.check("refining the plan by optimal control")
    u0 = _warm_controls(segments, intervals, system.m)
    u, status, its, step = _solve(ca, system, checker, x0, xg, u0, intervals)
    if u is None:
        return keep(f"IPOPT found no solution ({status})", solver_status=status,
                    solver_iterations=its)
    solved = {"solver_status": status, "solver_iterations": its}
    try:
        u, err = _correct(ca, system, step, x0, xg, u, tol, settings)
    except IntegrationError as exc:
        return keep(f"the refined controls cannot be re-simulated: {exc}", **solved)
    refined = _segments(u)
    after = control_length(refined)
    solved.update(length_refined=after, refined_error=err)
    if not err <= tol:
        return keep(f"the re-simulated refined controls miss the goal by {err:.3g} > tol "
                    f"{tol:g}", **solved)
    v = verify_segments(checker, x0, refined, xg, VERIFY_POINTS, settings)
    if not v.admissible:
        why = checker.why_invalid(v.states[int(np.argmin(
            checker.valid(v.states)))]) or "not admissible between samples"
        return keep(f"the refined motion is not admissible: {why}", **solved)
    if not v.error <= tol:
        return keep(f"the refined plan misses the goal by {v.error:.3g} > tol {tol:g} "
                    "(dense re-simulation)", **solved)
    if not after < before:
        return keep(f"not shorter: {after:.6g} against {before:.6g}", **solved)
    return refined, Refinement("ocp", True, "", before, intervals=intervals,
                               seconds=time.perf_counter() - t0, verification=v, **solved)


def refine_route(
    refine: str, checker: Checker, start: np.ndarray, goal: np.ndarray,
    segments: list[Segment], tol: float, settings: IntegrationSettings,
) -> tuple[list[Segment], Refinement] | None:
    """What :func:`~nilpotent.planning.global_planner.plan_global` does with ``refine``:
    ``None`` for ``"none"``, else :func:`refine_segments` of the whole plan; when the
    search's time runs out during the refinement, the segments unchanged and a refinement
    not applied, with the reason (the plan found is kept)."""
    if refine == "none":
        return None
    t0 = time.perf_counter()
    try:
        return refine_segments(checker, start, goal, segments, tol, settings=settings)
    except ComputationLimitError as exc:
        return list(segments), Refinement("ocp", False, f"stopped by the time limit: {exc}",
                                          control_length(segments),
                                          seconds=time.perf_counter() - t0)
