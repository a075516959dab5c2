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

Options (:class:`OcpRefine`): ``input_weights`` ``w`` make the energy
``∫ Σ (w_i u_i)² dt`` (the metric in which the ``X_i / w_i`` are orthonormal: a small
weight makes an input cheap, e.g. the car's steering rate, so that the length
approaches the distance driven); ``starts`` runs IPOPT from the nilpotent plan and
from ``starts − 1`` more, generic guesses (the straight line of states from start to
goal, then seeded perturbations of it), each endpoint-corrected, the best verified
one kept; ``reversal_cost`` adds ``C`` per reversal of a vehicle's drive input to the
cost by which those candidates and the nilpotent plan are compared (a cost of the
choice, not a term of the IPOPT objective, which stays smooth).

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
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import (
    ComputationLimitError,
    IntegrationError,
    OptionError,
)
from nilpotent.numeric.settings import IntegrationSettings
from nilpotent.numeric.signals import InputSignal
from nilpotent.planning import budget
from nilpotent.planning.casadi_tree import casadi_module
from nilpotent.planning.casadi_tree import to_casadi as to_casadi
from nilpotent.planning.controls import Segment, constant_segment
from nilpotent.planning.geodesic import control_length
from nilpotent.planning.ocp_smooth import (
    correct_endpoint,
    limit_constraints,
    rk4_interval,
    smooth_controls,
)
from nilpotent.planning.simulation import PLANNING_SETTINGS
from nilpotent.planning.timing import drive_reversals
from nilpotent.planning.verify import Checker, Verification, verify_segments
from nilpotent.strict_json import json_object

__all__ = [
    "INTERVALS", "MAX_STARTS", "REFINEMENTS", "OcpRefine", "Refinement", "check_refine",
    "refine_route", "refine_segments", "to_casadi",
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
#: The same for smooth controls (:attr:`OcpRefine.smooth`): a cosine series rings between
#: the states the limits are imposed at (measured: 2e-4 past a steering limit at 1e-6).
SMOOTH_LIMIT_MARGIN = 2e-3
IPOPT_ITERATIONS = 500
CORRECTIONS = 8
#: Samples per segment of the verification (as the global planner's).
VERIFY_POINTS = 100

#: Range of an input weight (:attr:`OcpRefine.input_weights`): the problem is solved with
#: the weights divided by the largest, so a common factor changes nothing; their ratios
#: within 1e12 keep IPOPT's scaling sane.
MIN_WEIGHT, MAX_WEIGHT = 1e-6, 1e6
#: Most IPOPT starts of one refinement (:attr:`OcpRefine.starts`).
MAX_STARTS = 32
#: Standard deviation of the seeded perturbations of the straight-line state guess (model
#: units, times ``sin(πt)`` so that the ends stay put) and of the control guess.
START_SPREAD = 0.5

_INSTALL = 'pip install "nilpotent[ocp]"'


@dataclass(frozen=True)
class OcpRefine:
    """How the refinement by direct optimal control runs (``refine=`` of
    :func:`~nilpotent.planning.global_planner.plan_global`; ``"ocp"`` is ``OcpRefine()``).

    Attributes
    ----------
    input_weights : tuple of float or None
        Positive weights ``w_i``, one per input: the energy is ``∫ Σ (w_i u_i)² dt`` and
        the lengths compared and reported are ``∫ ‖w ∘ u‖ dt``; ``None``: all 1.
    starts : int
        IPOPT starts (1 to :data:`MAX_STARTS`): the nilpotent plan, then the straight
        line of states, then seeded perturbations of it (:data:`START_SPREAD`).
    reversal_cost : float
        ``C ≥ 0`` added per reversal of the drive input (vehicle models only) to the
        cost by which the candidates and the nilpotent plan are compared.
    seed : int
        Seed of the perturbed starts (the plan's ``seed``).
    smooth : bool
        Solve each candidate once more with every input a cosine series of
        :data:`~nilpotent.planning.ocp_smooth.HARMONICS` harmonics
        (:mod:`nilpotent.planning.ocp_smooth`): one segment whose inputs are continuous,
        so that a re-timed trajectory rests only at the ends and at reversals; where that
        fails the piecewise-constant candidate stays (``smooth_reason`` says why).

    Raises
    ------
    OptionError
        A weight not positive and finite, ``starts`` outside ``1..MAX_STARTS``, a
        negative or non-finite ``reversal_cost``.
    """

    input_weights: tuple[float, ...] | None = None
    starts: int = 1
    reversal_cost: float = 0.0
    seed: int = 0
    smooth: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.smooth, bool):
            raise OptionError(f"smooth must be True or False; got {self.smooth!r}")
        if self.input_weights is not None:
            bad = [w for w in self.input_weights if not MIN_WEIGHT <= w <= MAX_WEIGHT]
            if bad or not self.input_weights:
                raise OptionError(f"--input-weights must be numbers from {MIN_WEIGHT:g} to "
                                  f"{MAX_WEIGHT:g}, one per input; got "
                                  f"{list(self.input_weights)[:8]}")
        if not (isinstance(self.starts, int) and 1 <= self.starts <= MAX_STARTS):
            raise OptionError(f"--refine-starts must be an integer from 1 to {MAX_STARTS}; "
                              f"got {self.starts!r}")
        if not (math.isfinite(self.reversal_cost) and self.reversal_cost >= 0):
            raise OptionError(f"--reversal-cost must be a number >= 0; got {self.reversal_cost}")

    def weights(self, m: int) -> np.ndarray:
        """The weights as an ``(m,)`` array (ones when none were given).

        Raises
        ------
        OptionError
            ``input_weights`` does not have ``m`` entries.
        """
        if self.input_weights is None:
            return np.ones(m)
        if len(self.input_weights) != m:
            raise OptionError(f"--input-weights: {len(self.input_weights)} weights for {m} "
                              "inputs")
        return np.array(self.input_weights, dtype=float)


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
    input_weights : tuple of float or None
        The weights of the metric of ``length_before``/``length_refined`` (``None``: 1).
    starts : int
        IPOPT starts asked for.
    starts_run : int
        IPOPT starts run (fewer than ``starts`` when the time limit ran out first).
    candidates : int
        Starts whose controls, re-simulated, reached the goal within ``tol``.
    reversal_cost : float
        The cost per reversal of the drive input in the comparison.
    cost_before, cost_refined : float or None
        Length plus ``reversal_cost`` times the drive reversals, of the nilpotent plan
        and of the refined controls (``None`` when there are none).
    controls : str
        ``"piecewise constant"`` (``intervals`` constant segments) or ``"cosine series"``
        (one segment, :attr:`OcpRefine.smooth`).
    smooth_reason : str
        Why smooth controls were asked for and not kept (``""`` otherwise).
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
    input_weights: tuple[float, ...] | None = None
    starts: int = 1
    starts_run: int = 0
    candidates: int = 0
    reversal_cost: float = 0.0
    cost_before: float | None = None
    cost_refined: float | None = None
    controls: str = "piecewise constant"
    smooth_reason: str = ""
    verification: Verification | None = field(default=None, repr=False, compare=False)

    def to_json(self) -> dict[str, Any]:
        """The fields as a strict-JSON dict (:func:`nilpotent.strict_json.json_object`)."""
        return json_object({
            "method": self.method, "applied": self.applied, "reason": self.reason,
            "length_before": self.length_before, "length_refined": self.length_refined,
            "intervals": self.intervals, "solver_status": self.solver_status,
            "solver_iterations": self.solver_iterations, "refined_error": self.refined_error,
            "seconds": self.seconds,
            "input_weights": None if self.input_weights is None else list(self.input_weights),
            "starts": self.starts, "starts_run": self.starts_run,
            "candidates": self.candidates,
            "reversal_cost": self.reversal_cost, "cost_before": self.cost_before,
            "cost_refined": self.cost_refined, "controls": self.controls,
            "smooth_reason": self.smooth_reason,
        })


def _casadi() -> Any:
    return casadi_module()


def check_refine(refine: str | OcpRefine) -> None:
    """Raise unless ``refine`` is one of :data:`REFINEMENTS` and what it needs is installed.

    Parameters
    ----------
    refine : str or OcpRefine
        ``"none"``, ``"ocp"``, or the options of an ``"ocp"`` refinement.

    Raises
    ------
    OptionError
        An unknown value.
    MissingExtraError
        ``"ocp"`` without CasADi (the ``ocp`` extra).
    """
    if isinstance(refine, OcpRefine):
        _casadi()
        return
    if refine not in REFINEMENTS:
        raise OptionError(
            f"--refine must be {' or '.join(REFINEMENTS)}; got {str(refine)[:60]!r}")
    if refine == "ocp":
        _casadi()


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
    x = ca.SX.sym("x", system.n)
    u = ca.SX.sym("u", system.m)
    z, subs = rk4_interval(ca, system, x, lambda t: u, 0.0, 1.0 / (n_int * SUBSTEPS),
                           SUBSTEPS)
    return ca.Function("step", [x, u], [z, ca.horzcat(*subs)])


def _scaled(segments: Sequence[Segment], w: np.ndarray) -> list[Segment]:
    """``segments`` with input ``i`` multiplied by ``w[i]`` (their weighted length is
    :func:`~nilpotent.planning.geodesic.control_length` of these)."""
    return [Segment(seg.duration, seg.omega, tuple(
        InputSignal(s.constant * float(wi), tuple(c * float(wi) for c in s.cos),
                    tuple(c * float(wi) for c in s.sin))
        for s, wi in zip(seg.inputs, w, strict=True))) for seg in segments]


def _guesses(checker: Checker, x0: np.ndarray, xg: np.ndarray, n_int: int,
             options: OcpRefine) -> list[tuple[np.ndarray, np.ndarray]]:
    """The generic starts after the nilpotent plan: ``(controls (m, N), states (n, N+1))``:
    the straight line of states with seeded controls, then seeded perturbations of the
    line (:data:`START_SPREAD` times ``sin(πt)``), clipped into the box limits."""
    system = checker.system
    t = np.linspace(0.0, 1.0, n_int + 1)
    line = x0[:, None] + (xg - x0)[:, None] * t[None, :]
    assert checker.limits is not None
    names = system.coordinate_names
    out = []
    for k in range(1, options.starts):
        rng = np.random.default_rng([options.seed, k])
        states = line + (0.0 if k == 1 else rng.normal(0.0, START_SPREAD, line.shape)
                         * np.sin(np.pi * t)[None, :])
        for name, lo, hi in checker.limits.bounds:
            j = names.index(name)
            states[j] = np.clip(states[j], lo, hi)
        out.append((rng.normal(0.0, 1.0, (system.m, n_int)), states))
    return out


def _solve(
    ca: Any, system: ControlSystem, checker: Checker, x0: np.ndarray, xg: np.ndarray,
    u0: np.ndarray, n_int: int, weights: np.ndarray | None = None,
    states0: np.ndarray | None = None, share: float = 0.8, step: Any = None,
) -> tuple[np.ndarray | None, str, int, Any]:
    """IPOPT on the multiple-shooting problem: ``(u, status, iterations, step)``; started
    from controls ``u0`` and states ``states0`` (default: the RK4 roll-out of ``u0``),
    with at most ``share`` of the time left; ``step``: the interval flow of
    :func:`_problem`, built once per refinement (built here when ``None``)."""
    if step is None:
        step = _problem(ca, system, n_int)
    opti = ca.Opti()
    xs = opti.variable(system.n, n_int + 1)
    us = opti.variable(system.m, n_int)
    w = np.ones(system.m) if weights is None else weights
    opti.minimize(ca.sumsqr(ca.DM(np.repeat(w[:, None], n_int, axis=1)) * us) / n_int)
    nxt, subs = step.map(n_int)(xs[:, :n_int], us)
    opti.subject_to(xs[:, 0] == x0)
    opti.subject_to(xs[:, n_int] == xg)
    opti.subject_to(xs[:, 1:] == nxt)
    limit_constraints(ca, opti, system, checker, x0, xg, subs, LIMIT_MARGIN)
    # warm start: the nilpotent plan's controls and their RK4 roll-out (or given states)
    if states0 is None:
        roll = step.mapaccum(n_int)(x0, u0)
        states = np.hstack([x0[:, None], np.array(roll[0])])
    else:
        states = states0
    if not np.all(np.isfinite(states)):
        return None, "the warm start's RK4 roll-out is not finite", 0, step
    opti.set_initial(us, u0)
    opti.set_initial(xs, states)
    left = budget.seconds_left()
    opts: dict[str, Any] = {"print_level": 0, "max_iter": IPOPT_ITERATIONS, "tol": 1e-10,
                            "sb": "yes"}
    if math.isfinite(left):
        opts["max_wall_time"] = max(0.1, share * left)
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

    return correct_endpoint(system, x0, xg, u, jac, _segments, tol, settings, CORRECTIONS,
                            "correcting the endpoint of the refined controls")


def refine_segments(
    checker: Checker,
    start: Sequence[float] | np.ndarray,
    goal: Sequence[float] | np.ndarray,
    segments: Sequence[Segment],
    tol: float,
    *,
    intervals: int = INTERVALS,
    settings: IntegrationSettings = PLANNING_SETTINGS,
    options: OcpRefine | None = None,
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
    options : OcpRefine or None
        Input weights, starts, reversal cost (default ``OcpRefine()``: weights 1, the
        nilpotent plan as the only start, no reversal cost).

    Returns
    -------
    segments, refinement
        The cheapest refined controls that verify (goal within ``tol``, admissible) and
        cost less than ``segments`` (cost: the weighted length plus the reversal cost),
        else ``segments`` unchanged; and what was done (:class:`Refinement`).

    Raises
    ------
    MissingExtraError
        CasADi is not installed.
    OptionError
        ``intervals`` below 2, fields CasADi cannot express, weights not one per input,
        a reversal cost for a model without a drive input.
    ComputationLimitError
        The time budget ran out before any candidate was found.
    """
    ca = _casadi()
    if not (isinstance(intervals, int) and intervals >= 2):
        raise OptionError(f"intervals must be an integer >= 2, got {intervals!r}")
    opts = OcpRefine() if options is None else options
    t0 = time.perf_counter()
    system = checker.system
    w = opts.weights(system.m)
    wn = w / float(w.max())  # what IPOPT sees: a common factor of the weights changes nothing
    if opts.reversal_cost > 0 and drive_reversals(system, ()) is None:
        raise OptionError(f"--reversal-cost: model {system.name} has no drive input (vehicle "
                          "models only)")
    x0 = np.asarray(start, dtype=float)
    xg = np.asarray(goal, dtype=float)

    def length_of(segs: Sequence[Segment]) -> float:
        return control_length(segs if opts.input_weights is None else _scaled(segs, w))

    def cost_of(segs: Sequence[Segment], length: float) -> float:
        reversals = drive_reversals(system, segs) if opts.reversal_cost > 0 else 0
        return length + opts.reversal_cost * (reversals or 0)

    before = length_of(segments)
    common: dict[str, Any] = {"input_weights": opts.input_weights, "starts": opts.starts,
                              "reversal_cost": opts.reversal_cost,
                              "cost_before": cost_of(segments, before)}

    def keep(reason: str, **more: Any) -> tuple[list[Segment], Refinement]:
        return list(segments), Refinement("ocp", False, reason, before, intervals=intervals,
                                          seconds=time.perf_counter() - t0, **common, **more)

    if not segments:
        return keep("the plan has no controls (the start is within tol of the goal)")
    budget.check("refining the plan by optimal control")
    starts = [(_warm_controls(segments, intervals, system.m), None),
              *_guesses(checker, x0, xg, intervals, opts)]
    found: list[tuple[float, float, float, list[Segment], dict[str, Any], np.ndarray]] = []
    reasons: list[str] = []
    solved: dict[str, Any] = {}
    flow = _problem(ca, system, intervals)  # the CasADi graph once, for every start
    for k, (u0, states0) in enumerate(starts):
        try:
            budget.check("refining the plan by optimal control")
            common["starts_run"] = k + 1
            u, status, its, step = _solve(ca, system, checker, x0, xg, u0, intervals, wn,
                                          states0, share=0.8 / (len(starts) - k),
                                          step=flow)
            solved = {"solver_status": status, "solver_iterations": its}
            if u is None:
                reasons.append(f"IPOPT found no solution ({status})")
                continue
            u, err = _correct(ca, system, step, x0, xg, u, tol, settings)
        except IntegrationError as exc:
            reasons.append(f"the refined controls cannot be re-simulated: {exc}")
            continue
        except ComputationLimitError:
            if not found:
                raise
            break  # the time left goes to the candidates found
        refined = _segments(u)
        after = length_of(refined)
        solved.update(length_refined=after, refined_error=err)
        if not err <= tol:
            reasons.append(f"the re-simulated refined controls miss the goal by {err:.3g} > "
                           f"tol {tol:g}")
            continue
        found.append((cost_of(refined, after), after, err, refined, dict(solved), u))
    common["candidates"] = len(found)
    if not found:
        return keep(reasons[0] if len(set(reasons)) == 1 else
                    f"no start gave a candidate: {'; '.join(dict.fromkeys(reasons))}"[:400],
                    **solved)
    found.sort(key=lambda c: c[0])
    for cost, _after, _err, refined, info, u in found:
        variants = [(refined, cost, info)]
        if opts.smooth:  # the cosine series first, the piecewise-constant candidate after
            variants[:0] = _smoothed(ca, checker, x0, xg, u, wn, tol, settings, info,
                                     length_of, cost_of)
        for segs, c, inf in variants:
            inf["cost_refined"] = c
            v = verify_segments(checker, x0, segs, xg, VERIFY_POINTS, settings)
            if not v.admissible:
                why = checker.why_invalid(v.states[int(np.argmin(
                    checker.valid(v.states)))]) or "not admissible between samples"
                reasons = [f"the refined motion is not admissible: {why}"]
            elif not v.error <= tol:
                reasons = [f"the refined plan misses the goal by {v.error:.3g} > tol {tol:g} "
                           "(dense re-simulation)"]
            elif not c < common["cost_before"]:  # the cheapest admissible is not cheaper
                what = "shorter" if opts.reversal_cost == 0 else "cheaper (length + reversals)"
                return keep(f"not {what}: {c:.6g} against {common['cost_before']:.6g}", **inf)
            else:
                return segs, Refinement("ocp", True, "", before, intervals=intervals,
                                        seconds=time.perf_counter() - t0, verification=v,
                                        **common, **inf)
            if inf is not info:  # the smooth variant failed: the piecewise one says why
                info["smooth_reason"] = reasons[0]
            solved = inf
    return keep(reasons[0], **solved)


def _smoothed(ca: Any, checker: Checker, x0: np.ndarray, xg: np.ndarray, u: np.ndarray,
              w: np.ndarray, tol: float, settings: IntegrationSettings, info: dict[str, Any],
              length_of: Any, cost_of: Any) -> list[tuple[list[Segment], float, dict[str, Any]]]:
    """The cosine-series variant ``[(segments, cost, info)]`` of a candidate
    (:func:`smooth_controls`; limits tightened by :data:`SMOOTH_LIMIT_MARGIN`: a series
    rings between the grid's states), or ``[]`` with ``info["smooth_reason"]`` set."""
    seg, err, why = smooth_controls(
        ca, checker, x0, xg, u, None, w, tol, settings, substeps=SUBSTEPS,
        margin=SMOOTH_LIMIT_MARGIN, iterations=IPOPT_ITERATIONS, corrections=CORRECTIONS,
        share=0.5)
    if seg is None or not err <= tol:
        info["smooth_reason"] = why or (f"the re-simulated cosine-series controls miss the "
                                        f"goal by {err:.3g} > tol {tol:g}")
        return []
    length = length_of([seg])
    return [([seg], cost_of([seg], length),
             {**info, "controls": "cosine series", "length_refined": length,
              "refined_error": err, "smooth_reason": ""})]


def refine_route(
    refine: str | OcpRefine, checker: Checker, start: np.ndarray, goal: np.ndarray,
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
        return refine_segments(checker, start, goal, segments, tol, settings=settings,
                               options=refine if isinstance(refine, OcpRefine) else None)
    except ComputationLimitError as exc:
        opts = refine if isinstance(refine, OcpRefine) else OcpRefine()
        weighted = segments if opts.input_weights is None else _scaled(
            segments, opts.weights(checker.system.m))
        return list(segments), Refinement("ocp", False, f"stopped by the time limit: {exc}",
                                          control_length(weighted),
                                          seconds=time.perf_counter() - t0,
                                          input_weights=opts.input_weights,
                                          starts=opts.starts,
                                          reversal_cost=opts.reversal_cost)
