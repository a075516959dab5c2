"""Iterative steering of the true system with nilpotent approximations (the mathematics page, §7).

Algorithm (Bellaïche–Jean–Risler; Vendittelli–Oriolo–Jean–Laumond), from
``x_0 = start``:

1. at the anchor point (``"current"``: the iterate ``x_k``, re-approximating
   every time; ``"goal"``: the goal, approximated once; ``"start"``: the
   start, approximated once, the plan being computed backwards from the goal
   and reversed) build the nilpotent approximation and its privileged
   coordinates ``y`` (:mod:`nilpotent.planning.local_model`);
2. steer the *nilpotent* system exactly from ``y(x_k)`` to ``y(goal)``
   (:func:`~nilpotent.planning.nilpotent.steer_nilpotent`);
3. apply the same inputs to the true system from ``x_k`` (numerical
   integration, :mod:`nilpotent.planning.simulation`), reaching ``x_{k+1}``.

The approximation error is of higher weighted order, so near the goal the
distance shrinks superlinearly.  Far from it a step can overshoot: then the
target is pulled toward the anchor by dilations (``δ_s`` with
``s = 1/2, 1/4, …``, in the privileged coordinates; these candidates are
integrated as one batch) and the one that most reduces the homogeneous
distance to the goal is kept.
The iteration stops when ``‖x_k − goal‖ ≤ tol`` (Euclidean, model
coordinates), or raises :class:`~nilpotent.errors.PlanningError` when no
candidate makes progress or ``max_iterations`` is exhausted.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import NilpotentError, OptionError, PlanningError, SingularPointError
from nilpotent.numeric.settings import IntegrationSettings, resolve_settings
from nilpotent.numeric.types import State
from nilpotent.planning import budget
from nilpotent.planning.controls import (
    Segment,
    coefficients,
    from_coefficients,
    reverse_segments,
)
from nilpotent.planning.length import length_report, method_for
from nilpotent.planning.local_model import BUILDERS, LocalModel, check_regular, choose_builder
from nilpotent.planning.nilpotent import StepTooHighError, steer_nilpotent
from nilpotent.planning.simulation import (
    PLANNING_SETTINGS,
    simulate_candidates,
    simulate_plan,
    single_engine,
)
from nilpotent.simulation.trajectory import Trajectory
from nilpotent.strict_json import json_object

ANCHORS = ("current", "goal", "start")
#: Relative finite-difference step of the shooting refinement's Jacobian.
FD_STEP = 1e-7
#: Default error below which high-step systems hand over to the shooting refinement.
HANDOVER = 1e-3
#: Most Newton steps of the shooting refinement.
REFINE_STEPS = 20

#: Dilation factors tried, in order, when the full nilpotent step does not reduce the error.
DAMPING = (1.0, 0.5, 0.25, 0.125, 0.0625)


@dataclass(frozen=True)
class Iteration:
    """One iteration of the iterative steering.

    Attributes
    ----------
    error:
        ``‖x_{k+1} − goal‖`` (Euclidean) after this iteration.
    damping:
        The dilation factor ``s`` of the target that was used (1 = full step).
    segments:
        Number of segments this iteration added.
    nilpotent_error:
        How exactly the nilpotent system reached its target (``∞``-norm in ``y``).
    seconds:
        Wall-clock time of the iteration.
    distance:
        Homogeneous distance estimate to the goal after the iteration,
        ``max_j |z_j|^{1/w_j}`` in privileged coordinates ``z`` at the goal.
    kind:
        ``"nilpotent"`` (a nilpotent step) or ``"newton"`` (a step of the
        shooting refinement, see :func:`plan`).
    """

    error: float
    damping: float
    segments: int
    nilpotent_error: float
    seconds: float
    distance: float = math.nan
    kind: str = "nilpotent"


class PlanFigure:
    """The ``.plot()`` of plans (:class:`Plan` and
    :class:`~nilpotent.planning.global_planner.GlobalPlan`): one figure for both."""

    def plot(self, snapshots: int = 12) -> Any:
        """The plan's figure (:func:`nilpotent.viz.plan_world.plot_plan_world`, the one
        of ``nilpotent plan --plot``): the motion (in its world, with the robot's
        outline at ``snapshots`` times), the coordinates against their limits, the
        inputs; a matplotlib ``Figure``."""
        from nilpotent.viz.plan_world import plot_plan_world

        return plot_plan_world(self, snapshots)


@dataclass(frozen=True, eq=False)
class Plan(PlanFigure):
    """Controls steering a system from ``start`` to ``goal``, with what they reach.

    Attributes
    ----------
    system:
        The system steered (its parameter values included).
    start, goal:
        Float points in the model's coordinates.
    segments:
        The controls (the segments of ``nilpotent/plan@1``, the interface page), in
        order from ``start``.
    reached:
        The state the true system reaches under ``segments`` (numerical
        integration, DOP853 at rtol 1e-12).
    error:
        ``‖reached − goal‖`` (Euclidean).
    iterations:
        One :class:`Iteration` per nilpotent step.
    trajectory:
        The true system's :class:`~nilpotent.simulation.trajectory.Trajectory`
        under ``segments`` (samples for plots and animations).
    tol:
        The tolerance asked for; ``converged`` says whether ``error ≤ tol``.
    converged:
        Whether ``error ≤ tol`` (computed from them, not an argument).
    anchor, builder:
        Where the approximations were taken and how they were built.
    initial_error:
        ``‖start − goal‖``.
    seconds:
        Wall-clock time of the planning.
    objective:
        The local steering's objective (``"reach"`` or ``"length"``).
    """

    system: ControlSystem
    start: tuple[float, ...]
    goal: tuple[float, ...]
    segments: tuple[Segment, ...]
    reached: tuple[float, ...]
    error: float
    iterations: tuple[Iteration, ...]
    trajectory: Trajectory
    tol: float = 1e-8
    anchor: str = "current"
    builder: str = "numeric"
    initial_error: float = 0.0
    seconds: float = 0.0
    objective: str = "reach"
    converged: bool = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "converged", bool(self.error <= self.tol))

    @property
    def duration(self) -> float:
        """Total duration of the controls."""
        return float(sum(s.duration for s in self.segments))

    def to_json(self) -> dict[str, Any]:
        """The ``nilpotent/plan@1`` object of the interface page (plus extra fields), strict JSON.

        Numbers that are not finite (the homogeneous ``distance`` of a Newton
        refinement step, which computes none) are ``null`` and listed under
        ``"undefined"`` (:func:`nilpotent.strict_json.json_object`), so
        ``json.dumps(plan.to_json(), allow_nan=False)`` always works.
        """
        return json_object(self.json_fields())

    def json_fields(self) -> dict[str, Any]:
        """The fields of :meth:`to_json` before the strict encoding (floats may be NaN):
        what :class:`~nilpotent.planning.global_planner.GlobalPlan` extends."""
        return {
            "schema": "nilpotent/plan@1",
            "model": self.system.name,
            "coordinates": list(self.system.coordinate_names),
            "parameters": {k: float(v) for k, v in self.system.parameters},
            "from": list(self.start),
            "to": list(self.goal),
            "reached": list(self.reached),
            "error": self.error,
            "tol": self.tol,
            "converged": self.converged,
            "initial_error": self.initial_error,
            "anchor": self.anchor,
            "approximation": self.builder,
            "duration": self.duration,
            "iterations": [
                {
                    "error": it.error,
                    "damping": it.damping,
                    "segments": it.segments,
                    "nilpotent_error": it.nilpotent_error,
                    "seconds": it.seconds,
                    "distance": it.distance,
                    "kind": it.kind,
                }
                for it in self.iterations
            ],
            "segments": [s.to_dict() for s in self.segments],
            **self.length_fields[0],
            **({"null_reasons": self.length_fields[1]} if self.length_fields[1] else {}),
        }

    @cached_property
    def length_fields(self) -> tuple[dict[str, Any], dict[str, str]]:
        """``length`` (``∫‖u‖ dt``), ``lower_bound``, ``lower_bound_kind``, ``length_ratio``
        and the reasons for the null ones (:func:`nilpotent.planning.length.length_report`)."""
        return length_report(self.system, self.start, self.goal, self.segments, self.objective)

    @property
    def length(self) -> float:
        """The sub-Riemannian length ``∫‖u(t)‖₂ dt`` of the controls (``X_i`` orthonormal)."""
        return float(self.length_fields[0]["length"])

    # --- display (nilpotent.typeset) -------------------------------------------------
    def to_latex(self) -> str:
        """Start, goal, the point reached and the iterations as LaTeX (``align*``)."""
        from nilpotent import typeset

        return typeset.plan_display(self).latex()

    def _repr_latex_(self) -> str:
        return self.to_latex()

    def _repr_html_(self) -> str:
        from nilpotent import typeset

        return typeset.plan_display(self).html()


def _as_floats(point: Sequence[object] | State, n: int, what: str) -> np.ndarray:
    try:
        arr = np.array([float(v) for v in point], dtype=float)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise PlanningError(f"the {what} must be numeric (got {point!r})") from None
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise PlanningError(f"the {what} needs {n} finite coordinates, got {point!r}")
    return arr


def _candidates(
    model: LocalModel, y_from: np.ndarray, y_to: np.ndarray, method: str
) -> Iterator[tuple[float, list[Segment], float]]:
    """Nilpotent steerings toward ``y_to``, then toward damped versions of it (lazily).

    From the origin, ``δ_s`` of the target is reached by the inputs scaled by
    ``s`` (homogeneity), so one steering serves every damping; otherwise
    (``y_to`` is then the anchor, 0) the start's image is pulled toward it,
    ``δ_{1−s} y_from``, and steered to separately.
    """
    tri = model.nilpotent
    if tri.quasi_norm(y_from) <= 1e-15:
        budget.check("steering the nilpotent approximation")
        try:
            steering = steer_nilpotent(tri, np.zeros_like(y_to), y_to, method=method)
        except StepTooHighError:
            raise
        except NilpotentError:
            return
        for s in DAMPING:
            yield s, [seg.scaled(s) for seg in steering.segments], steering.error
        return
    for s in DAMPING:
        target = y_to if s == 1.0 else y_to + tri.dilate(y_from - y_to, 1.0 - s)
        budget.check("steering the nilpotent approximation")
        try:
            steering = steer_nilpotent(tri, y_from, target, method=method)
        except StepTooHighError:
            raise
        except NilpotentError:
            continue
        yield s, list(steering.segments), steering.error


def _iterate(
    system: ControlSystem,
    x0: np.ndarray,
    xg: np.ndarray,
    model_at: Callable[[np.ndarray], LocalModel],
    target_model: LocalModel,
    tol: float,
    max_iterations: int,
    method: str,
    settings: IntegrationSettings,
    handover: float = 0.0,
    guess: list[Segment] | None = None,
) -> tuple[list[Segment], np.ndarray, float, list[Iteration], str]:
    """Nilpotent steps from ``x0`` toward ``xg``; ``model_at(x_k)`` gives the local model.

    If the very first step makes no progress, its (full) controls are appended
    to ``guess``, as an initial guess for the shooting refinement.

    A step is accepted when it decreases the homogeneous distance estimate
    ``‖z(x)‖ = max_j |z_j(x)|^{1/w_j}`` in the privileged coordinates ``z`` of
    ``target_model`` (centred at ``xg``): the Euclidean error is dominated by
    the slow weight-2 directions and does not see progress in them.
    """

    def merit(x: np.ndarray) -> float:
        z = target_model.forward(x)
        return target_model.nilpotent.quasi_norm(z) if np.all(np.isfinite(z)) else math.inf

    if guess is None:
        guess = []
    x = x0.copy()
    error = float(np.linalg.norm(x - xg))
    distance = merit(x)
    segments: list[Segment] = []
    history: list[Iteration] = []
    while error > max(tol, handover) and len(history) < max_iterations:
        budget.check(f"nilpotent step {len(history) + 1}")
        t_it = time.perf_counter()
        try:
            model = model_at(x)
        except SingularPointError as exc:
            raise SingularPointError(f"the path meets a singular point: {exc}") from None
        candidates = _candidates(model, model.forward(x), model.forward(xg), method)
        trials = list(itertools.islice(candidates, 1))
        if not trials:
            return segments, x, error, history, "the nilpotent system could not be steered"
        # the full step first; the damped ones (one batch) only if it makes no progress
        ends = simulate_candidates(system, x, [trials[0][1]], settings)
        merits = np.array([merit(e) if np.all(np.isfinite(e)) else math.inf for e in ends])
        if not merits[0] < distance:
            trials.extend(candidates)
            if len(trials) > 1:
                more = simulate_candidates(system, x, [segs for _, segs, _ in trials[1:]], settings)
                ends = np.vstack([ends, more])
                merits = np.array(
                    [merit(e) if np.all(np.isfinite(e)) else math.inf for e in ends]
                )
        pick = int(np.argmin(merits))
        if not merits[pick] < distance:
            if not history:
                guess.extend(trials[0][1])
            return segments, x, error, history, (
                f"no progress at iteration {len(history) + 1}: every nilpotent step "
                f"(damped down to {trials[-1][0]}) leaves the distance to the goal at or "
                f"above {distance:.3g}"
            )
        s, segs, nil_err = trials[pick]
        x = ends[pick]
        distance = float(merits[pick])
        error = float(np.linalg.norm(x - xg))
        segments.extend(segs)
        history.append(
            Iteration(error, s, len(segs), nil_err, time.perf_counter() - t_it, distance)
        )
    failure = ""
    if error > tol:
        failure = (
            f"handed over to the shooting refinement at {error:.3g}"
            if error <= handover
            else f"tolerance {tol:g} not reached in {max_iterations} iterations"
        )
    return segments, x, error, history, failure


def _refine(
    system: ControlSystem,
    x0: np.ndarray,
    segments: list[Segment],
    xg: np.ndarray,
    tol: float,
    settings: IntegrationSettings,
    max_steps: int = REFINE_STEPS,
) -> tuple[list[Segment], np.ndarray, float, list[Iteration]]:
    """Shooting refinement: Newton on the true endpoint map over the last step's coefficients.

    At most ``max_steps`` Newton steps (and :data:`REFINE_STEPS`).

    The coefficients of the last (at most two) segments are corrected by
    minimum-norm Gauss–Newton steps, ``θ ← θ − α J⁺ (x(θ) − goal)``, with the
    Jacobian ``J`` by forward finite differences (all ``P + 1`` trajectories
    integrated as one batch) and ``α ∈ {1, 1/2, 1/4}``.  Started from the
    nilpotent solution, whose loops make ``J`` of full rank, it converges
    quadratically (up to the finite-difference error).
    """
    m = system.m
    tail = segments[-2:]
    prefix = segments[: len(segments) - len(tail)]
    x_before = simulate_candidates(system, x0, [prefix], settings)[0] if prefix else x0
    harmonics = [max((i.harmonics for i in seg.inputs), default=0) for seg in tail]
    theta = coefficients(tail, harmonics)
    end = simulate_candidates(system, x_before, [tail], settings)[0]
    error = float(np.linalg.norm(end - xg))
    history: list[Iteration] = []
    for k in range(min(REFINE_STEPS, max_steps)):
        if error <= tol:
            break
        budget.check(f"Newton step {k + 1} of the shooting refinement")
        t_it = time.perf_counter()
        h = FD_STEP * max(1.0, float(np.max(np.abs(theta))))
        probes = [from_coefficients(theta + h * e, tail, harmonics, m) for e in np.eye(theta.size)]
        ends = simulate_candidates(system, x_before, probes, settings)
        jac = (ends - end[None, :]).T / h
        if not np.all(np.isfinite(jac)):
            break
        step, *_ = np.linalg.lstsq(jac, end - xg, rcond=None)
        tries = [theta - a * step for a in (1.0, 0.5, 0.25)]
        tried = simulate_candidates(
            system, x_before, [from_coefficients(t, tail, harmonics, m) for t in tries], settings
        )
        errs = np.linalg.norm(tried - xg, axis=1)
        errs[~np.isfinite(errs)] = np.inf
        best = int(np.argmin(errs))
        if not errs[best] < error:
            break
        theta, end, error = tries[best], tried[best], float(errs[best])
        history.append(Iteration(error, (1.0, 0.5, 0.25)[best], len(tail), math.nan,
                                 time.perf_counter() - t_it, math.nan, "newton"))
    return prefix + from_coefficients(theta, tail, harmonics, m), end, error, history


def plan(
    sys: ControlSystem,
    start: Sequence[object] | State,
    goal: Sequence[object] | State,
    tol: float = 1e-8,
    *,
    max_iterations: int = 30,
    anchor: str = "auto",
    builder: str = "auto",
    method: str = "auto",
    raise_on_failure: bool = True,
    trajectory_points: int = 40,
    settings: IntegrationSettings | None = None,
    engine: str | None = None,
    refine: bool = True,
    handover: float | None = None,
    time_limit: float = math.inf,
    objective: str = "reach",
) -> Plan:
    """Steer ``sys`` from ``start`` to ``goal`` by iterated nilpotent steering.

    Parameters
    ----------
    sys:
        A bracket-generating system (parameters substituted from its values).
    start, goal:
        Points in the model's coordinates (sympy numbers or floats; exact
        rational values are kept exact for the symbolic approximation, other
        exact values such as ``pi/2`` are used as floats after an exact check
        of regularity: :func:`~nilpotent.planning.local_model.symbolic_model`).
    tol:
        Stop when ``‖x_k − goal‖`` (Euclidean) is at most ``tol``.
    max_iterations:
        Largest number of nilpotent steps (and of Newton steps of the refinement).
    anchor:
        Where the approximations are taken:

        * ``"current"``: at every iterate (the mathematics page, §7);
        * ``"goal"``: once, at the goal;
        * ``"start"``: once, at the start: the plan is computed *backwards*
          from the goal to the start (anchored at its goal, the start) and
          reversed (``u(t) → −u(T−t)``: a driftless system retraces its path);
          the backward pass aims at ``tol/100`` so that the reversed controls
          still meet ``tol``, and the forward error is checked by simulation;
        * ``"auto"``: ``"current"`` with the numeric builder where fields and
          first brackets span the space (step ≤ 2), else ``"start"``.
    builder:
        ``"numeric"`` (step ≤ 2, float linear adapted coordinates),
        ``"symbolic"`` (:func:`nilpotent.core.coordinates.approximation.approximate`,
        exact) or ``"auto"`` (numeric where possible).
    method:
        Nilpotent steering method (:data:`nilpotent.planning.nilpotent.METHODS`
        or ``"auto"``).
    raise_on_failure:
        Raise :class:`PlanningError` when the tolerance is not met (default);
        with ``False`` return the best plan found (``converged`` is False).
    trajectory_points:
        Samples per segment of :attr:`Plan.trajectory`.
    settings : IntegrationSettings or None
        How the true system is integrated (default
        :data:`~nilpotent.planning.simulation.PLANNING_SETTINGS`: adaptive DOP853 at
        ``rtol = 1e-12``; its ``max_steps`` counts per segment of the controls).
    engine : str or None
        The loose form of ``settings.engine`` (kept for one release; pass
        ``settings=IntegrationSettings(engine=...)`` instead): an integration engine
        (:data:`nilpotent.numeric.engines.ENGINES`, or ``"auto"``).
    refine:
        When the nilpotent iterations stop short of ``tol`` (no progress or
        ``max_iterations``), finish with the shooting refinement of the last
        step (Newton on the true endpoint map, finite-difference Jacobian;
        reported as iterations of kind ``"newton"``).  ``False``: nilpotent
        steps only.
    handover:
        Hand over from the nilpotent steps to the shooting refinement once the
        error is below this value (0: never).  Default: :data:`HANDOVER` for
        systems of step ≥ 3 (their nilpotent convergence order ``1 + 1/r`` is
        slow, Newton's is quadratic) when the compiled integrator is used (a
        refinement step integrates ``P + 1`` trajectories), else 0.
    time_limit : float
        Seconds the whole plan may take (default: no limit); every step, the
        integrations included, is bounded by it
        (:func:`nilpotent.planning.budget.time_budget`).
    objective : str
        What the local steering optimises (:data:`nilpotent.planning.length.OBJECTIVES`):
        ``"reach"`` (default: straight segment and loops, or Newton) or
        ``"length"`` (the shortest normal geodesic of each approximation: closed
        form for step 2, shooting above, :mod:`nilpotent.planning.shooting`).

    Raises
    ------
    OptionError
        A bad option, ``settings`` included (:class:`IntegrationSettings`).
    SingularPointError
        The start, the goal or an iterate is a singular point.
    PlanningError
        No progress, or the tolerance not met within ``max_iterations``.
    ComputationLimitError
        The time limit ran out (every step, the integrations included, is bounded by it).

    Examples
    --------
    >>> from nilpotent.models import get_model
    >>> p = plan(get_model("unicycle"), (0, 0, 0), (0.1, 0.05, -0.1))
    >>> p.error <= 1e-8
    True
    """
    if not time_limit > 0:
        raise OptionError(f"time limit must be a positive number of seconds, got {time_limit}")
    chosen = resolve_settings(settings, PLANNING_SETTINGS, engine=engine)
    with budget.time_budget(time_limit):
        return _plan(sys, start, goal, tol, max_iterations=max_iterations, anchor=anchor,
                     builder=builder, method=method, raise_on_failure=raise_on_failure,
                     trajectory_points=trajectory_points, settings=chosen, refine=refine,
                     handover=handover, objective=objective)


def _plan(
    sys: ControlSystem,
    start: Sequence[object] | State,
    goal: Sequence[object] | State,
    tol: float,
    *,
    max_iterations: int,
    anchor: str,
    builder: str,
    method: str,
    raise_on_failure: bool,
    trajectory_points: int,
    settings: IntegrationSettings,
    refine: bool,
    handover: float | None,
    objective: str,
) -> Plan:
    t_start = time.perf_counter()
    method = method_for(objective, method)
    if anchor != "auto" and anchor not in ANCHORS:
        raise OptionError(f"unknown anchor {anchor!r} (choose from auto, {', '.join(ANCHORS)})")
    if builder != "auto" and builder not in BUILDERS:
        known = ", ".join(BUILDERS)
        raise OptionError(f"unknown builder {builder!r} (choose from auto, {known})")
    if not (tol > 0 and math.isfinite(tol)):
        raise OptionError(f"tol must be a positive number, got {tol}")
    if max_iterations < 1:
        raise OptionError(f"max_iterations must be >= 1, got {max_iterations}")
    system = sys
    x0 = _as_floats(start, system.n, "start")
    xg = _as_floats(goal, system.n, "goal")
    if builder == "auto":
        builder = choose_builder(system, x0)
    if anchor == "auto":
        anchor = "current" if builder == "numeric" else "start"
    if builder == "numeric":
        check_regular(system, x0, "start")
        check_regular(system, xg, "goal")
    build = BUILDERS[builder]
    initial_error = float(np.linalg.norm(x0 - xg))
    guess: list[Segment] = []  # first nilpotent step, if it made no progress
    if handover is None:
        fast = refine and single_engine(settings, system) == "numba"
        high_step = choose_builder(system, x0) == "symbolic"  # step >= 3 near the start
        handover = HANDOVER if fast and high_step else 0.0
    elif not (handover >= 0 and math.isfinite(handover)):
        raise OptionError(f"handover must be a number >= 0, got {handover}")
    elif handover > 0 and not refine:
        raise OptionError("handover > 0 hands the end over to the refinement: needs refine=True")

    budget.check("building the local nilpotent model")
    if anchor == "start":
        fixed = build(system, start)
        back, _, _, history, failure = _iterate(
            system, xg, x0, lambda x: fixed, fixed, max(tol / 100, 1e-13), max_iterations,
            method, settings, handover, guess,
        )
        segments = list(reverse_segments(back or (guess if refine else [])))
        x = simulate_candidates(system, x0, [segments], settings, hard=True)[0]
        error = float(np.linalg.norm(x - xg))
        if error <= tol:
            failure = ""
        elif not failure:
            failure = f"the reversed backward plan misses the goal by {error:.3g}"
    else:
        at_goal = build(system, goal)
        if anchor == "goal":

            def model_at(x: np.ndarray) -> LocalModel:
                return at_goal
        else:

            def model_at(x: np.ndarray) -> LocalModel:
                return build(system, x)

        segments, x, error, history, failure = _iterate(
            system, x0, xg, model_at, at_goal, tol, max_iterations, method, settings, handover,
            guess,
        )
        if refine and not segments and guess:
            segments = list(guess)
            x = simulate_candidates(system, x0, [segments], settings)[0]
            error = float(np.linalg.norm(x - xg))

    if refine and error > tol and segments:
        before = error
        refined, x_ref, err_ref, more = _refine(system, x0, segments, xg, tol, settings,
                                                max_iterations)
        if more:  # keep the refinement only if it improved anything
            segments, x, error = refined, x_ref, err_ref
            history.extend(more)
        elif guess and not history:  # the failed first step is no plan: drop it
            segments, x, error = [], x0.copy(), initial_error
        if error <= tol:
            failure = ""
        else:
            failure = (
                f"{failure}; the shooting refinement then went from {before:.3g} to {error:.3g}"
            )
    trajectory = simulate_plan(system, x0, segments, trajectory_points, settings, hard=True)
    result = Plan(
        system=system,
        start=tuple(float(v) for v in x0),
        goal=tuple(float(v) for v in xg),
        segments=tuple(segments),
        reached=tuple(float(v) for v in x),
        error=error,
        iterations=tuple(history),
        trajectory=trajectory,
        tol=tol,
        anchor=anchor,
        builder=builder,
        initial_error=initial_error,
        seconds=time.perf_counter() - t_start,
        objective=objective,
    )
    if failure and raise_on_failure:
        raise PlanningError(
            f"steering {system.name} failed: {failure} (error {error:.3g} after "
            f"{len(history)} iterations, from {initial_error:.3g})"
        )
    return result
