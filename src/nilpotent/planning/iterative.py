"""Iterative steering of the true system with nilpotent approximations (MATH.md §7).

Algorithm (Bellaïche–Jean–Risler; Vendittelli–Oriolo–Jean–Laumond), from
``x_0 = start``:

1. at the anchor point (``"current"``: the iterate ``x_k``, re-approximating
   every time; ``"goal"``: the goal, approximated once) build the nilpotent
   approximation and its privileged coordinates ``y``
   (:mod:`nilpotent.planning.local_model`);
2. steer the *nilpotent* system exactly from ``y(x_k)`` to ``y(goal)``
   (:func:`~nilpotent.planning.nilpotent.steer_nilpotent`);
3. apply the same inputs to the true system from ``x_k`` (numerical
   integration, :mod:`nilpotent.planning.simulation`), reaching ``x_{k+1}``.

The approximation error is of higher weighted order, so near the goal the
distance shrinks superlinearly.  Far from it a step can overshoot: then the
target is pulled toward the anchor by dilations (``δ_s`` with
``s = 1/2, 1/4, …``, in the privileged coordinates) and the first candidate
that reduces the error is kept (all candidates are integrated as one batch).
The iteration stops when ``‖x_k − goal‖ ≤ tol`` (Euclidean, model
coordinates), or raises :class:`~nilpotent.errors.PlanningError` when no
candidate makes progress or ``max_iterations`` is exhausted.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from nilpotent.core.system import ControlSystem
from nilpotent.errors import NilpotentError, PlanningError, SingularPointError
from nilpotent.planning.controls import Segment
from nilpotent.planning.local_model import BUILDERS, LocalModel, check_regular, choose_builder
from nilpotent.planning.nilpotent import steer_nilpotent
from nilpotent.planning.simulation import simulate_candidates, simulate_path

ANCHORS = ("current", "goal")
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
    """

    error: float
    damping: float
    segments: int
    nilpotent_error: float
    seconds: float


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Samples of the true system under the plan: ``times (N,)``, ``states (N, n)``."""

    times: np.ndarray
    states: np.ndarray


@dataclass(frozen=True, eq=False)
class Plan:
    """Controls steering a system from ``start`` to ``goal``, with what they reach.

    Attributes
    ----------
    system:
        The system steered (its parameter values included).
    start, goal:
        Float points in the model's coordinates.
    segments:
        The controls (INTERFACE.md plan segments), in order from ``start``.
    reached:
        The state the true system reaches under ``segments`` (numerical
        integration, DOP853 at rtol 1e-12).
    error:
        ``‖reached − goal‖`` (Euclidean).
    iterations:
        One :class:`Iteration` per nilpotent step.
    trajectory:
        Samples of the true trajectory (for plots and animations).
    tol:
        The tolerance asked for; ``converged`` says whether ``error ≤ tol``.
    anchor, builder:
        Where the approximations were taken and how they were built.
    initial_error:
        ``‖start − goal‖``.
    seconds:
        Wall-clock time of the planning.
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
    converged: bool = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "converged", bool(self.error <= self.tol))

    @property
    def duration(self) -> float:
        """Total duration of the controls."""
        return float(sum(s.duration for s in self.segments))

    def to_json(self) -> dict[str, Any]:
        """The ``nilpotent/plan@1`` object of INTERFACE.md (plus extra fields)."""
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
                }
                for it in self.iterations
            ],
            "segments": [s.to_dict() for s in self.segments],
        }


def _as_floats(point: Sequence[object], n: int, what: str) -> np.ndarray:
    try:
        arr = np.array([float(v) for v in point], dtype=float)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise PlanningError(f"the {what} must be numeric (got {point!r})") from None
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise PlanningError(f"the {what} needs {n} finite coordinates, got {point!r}")
    return arr


def _dilated_targets(model: LocalModel, y_from: np.ndarray, y_to: np.ndarray, anchor: str):
    tri = model.nilpotent
    for s in DAMPING:
        if anchor == "current":
            yield s, y_from, tri.dilate(y_to, s)
        else:
            yield s, y_from, tri.dilate(y_from, 1.0 - s)


def plan(
    sys: ControlSystem,
    start: Sequence[object],
    goal: Sequence[object],
    tol: float = 1e-8,
    *,
    max_iterations: int = 30,
    anchor: str = "current",
    builder: str = "auto",
    method: str = "auto",
    raise_on_failure: bool = True,
    trajectory_points: int = 40,
) -> Plan:
    """Steer ``sys`` from ``start`` to ``goal`` by iterated nilpotent steering.

    Parameters
    ----------
    sys:
        A bracket-generating system (parameters substituted from its values).
    start, goal:
        Points in the model's coordinates (numbers; exact values are converted
        to floats).
    tol:
        Stop when ``‖x_k − goal‖`` (Euclidean) is at most ``tol``.
    max_iterations:
        Largest number of nilpotent steps.
    anchor:
        ``"current"`` (re-approximate at every iterate, MATH.md §7) or
        ``"goal"`` (one approximation, at the goal).
    builder:
        ``"numeric"`` (step ≤ 2, float linear adapted coordinates),
        ``"symbolic"`` (:func:`nilpotent.core.approximation.approximate`) or
        ``"auto"`` (numeric where fields and first brackets span the space).
    method:
        Nilpotent steering method (:data:`nilpotent.planning.nilpotent.METHODS`
        or ``"auto"``).
    raise_on_failure:
        Raise :class:`PlanningError` when the tolerance is not met (default);
        with ``False`` return the best plan found (``converged`` is False).
    trajectory_points:
        Samples per segment of :attr:`Plan.trajectory`.

    Raises
    ------
    SingularPointError
        The start, the goal or an iterate is a singular point.
    PlanningError
        No progress, or the tolerance not met within ``max_iterations``.

    Examples
    --------
    >>> from nilpotent.models import get_model
    >>> p = plan(get_model("unicycle"), (0, 0, 0), (0.1, 0.05, -0.1))
    >>> p.error <= 1e-8
    True
    """
    t_start = time.perf_counter()
    if anchor not in ANCHORS:
        raise PlanningError(f"unknown anchor {anchor!r} (choose from {', '.join(ANCHORS)})")
    if builder != "auto" and builder not in BUILDERS:
        known = ", ".join(BUILDERS)
        raise PlanningError(f"unknown builder {builder!r} (choose from auto, {known})")
    if not (tol > 0 and math.isfinite(tol)):
        raise PlanningError(f"tol must be a positive number, got {tol}")
    if max_iterations < 1:
        raise PlanningError(f"max_iterations must be >= 1, got {max_iterations}")
    system = sys
    x = _as_floats(start, system.n, "start")
    xg = _as_floats(goal, system.n, "goal")
    if builder == "auto":
        builder = choose_builder(system, xg)
    if builder == "numeric":
        check_regular(system, x, "start")
        check_regular(system, xg, "goal")
    build = BUILDERS[builder]

    error = float(np.linalg.norm(x - xg))
    initial_error = error
    segments: list[Segment] = []
    history: list[Iteration] = []
    goal_model = build(system, xg) if anchor == "goal" else None
    failure = ""
    while error > tol and len(history) < max_iterations:
        t_it = time.perf_counter()
        try:
            model = goal_model if goal_model is not None else build(system, x)
        except SingularPointError as exc:
            raise SingularPointError(f"the path meets a singular point: {exc}") from None
        y_from = model.forward(x)
        y_to = model.forward(xg)
        trials: list[tuple[float, list[Segment], float]] = []
        if anchor == "current" and model.nilpotent.quasi_norm(y_from) <= 1e-15:
            # from the origin, δ_s of the target is reached by the inputs scaled by s
            try:
                steering = steer_nilpotent(model.nilpotent, np.zeros_like(y_to), y_to,
                                           method=method)
                trials = [
                    (s, [seg.scaled(s) for seg in steering.segments], steering.error)
                    for s in DAMPING
                ]
            except NilpotentError:
                trials = []
        else:
            for s, ya, yb in _dilated_targets(model, y_from, y_to, anchor):
                try:
                    steering = steer_nilpotent(model.nilpotent, ya, yb, method=method)
                except NilpotentError:
                    continue
                trials.append((s, list(steering.segments), steering.error))
        if not trials:
            failure = "the nilpotent system could not be steered"
            break
        ends = simulate_candidates(system, x, [segs for _, segs, _ in trials])
        errors = np.linalg.norm(ends - xg, axis=1)
        errors[~np.isfinite(errors)] = np.inf
        pick = next((i for i, e in enumerate(errors) if e < error), None)
        if pick is None:
            failure = (
                f"no progress at iteration {len(history) + 1}: every nilpotent step "
                f"(damped down to {trials[-1][0]}) leaves the error at or above {error:.3g}"
            )
            break
        s, segs, nil_err = trials[pick]
        x = ends[pick]
        error = float(errors[pick])
        segments.extend(segs)
        history.append(
            Iteration(error, s, len(segs), nil_err, time.perf_counter() - t_it)
        )
    if error > tol and not failure:
        failure = f"tolerance {tol:g} not reached in {max_iterations} iterations"
    times, states = simulate_path(system, _as_floats(start, system.n, "start"), segments,
                                  trajectory_points)
    result = Plan(
        system=system,
        start=tuple(float(v) for v in _as_floats(start, system.n, "start")),
        goal=tuple(float(v) for v in xg),
        segments=tuple(segments),
        reached=tuple(float(v) for v in x),
        error=error,
        iterations=tuple(history),
        trajectory=Trajectory(times, states),
        tol=tol,
        anchor=anchor,
        builder=builder,
        initial_error=initial_error,
        seconds=time.perf_counter() - t_start,
    )
    if failure and raise_on_failure:
        raise PlanningError(
            f"steering {system.name} failed: {failure} (error {error:.3g} after "
            f"{len(history)} iterations, from {initial_error:.3g})"
        )
    return result
