"""Closed-loop execution of a plan on a robot that is not exactly the model.

The *true* robot is the model with its parameters off by given fractions
(``--mismatch r=0.05,l=-0.05``: ``r_true = 1.05 r``, ``l_true = 0.95 l``)
and its state measured with Gaussian noise (``--noise SIGMA``, seeded).
Execution (feedback by re-planning, Laumond's "plan, execute a piece,
re-plan"):

1. for each piece of the plan (its end waypoint), steer the **model** from the
   *measured* state to the waypoint (iterated nilpotent steering, checked
   against the limits, obstacles and singular margin on the model; if that
   fails, the global planner from the measured state), apply the controls to
   the **true** robot, measure;
2. then correct: re-plan from the measured state to the goal and apply, until
   the measured error is at most ``tol`` or ``max_corrections`` rounds.

The motion of the true robot (its own outline, with the true parameters) is
checked at dense samples; every violation (limits, relative limits, contact,
self-collision, singular margin) is reported.  *Safety stop:* the executor never
drives the true robot outside them — before a sample of the true motion would be
inadmissible (the true robot's checker: limits, relative limits, obstacles,
self-collision, singular margin), the robot stops at the last admissible sample
(an ideal safety monitor on the true state), the controls applied so far are cut
there (``safety_stops`` counts the stops), and it re-plans from the measured state
toward the goal (as a correction).  So the closed-loop motion is admissible at
every sample; a robot stopped short of the goal reports ``success: false``.
The open-loop result — the plan's controls applied unchanged to
the true robot — is computed too, for comparison.

Everything runs within one time limit (:mod:`nilpotent.planning.budget`): when it
runs out while pieces of the plan remain, :class:`~nilpotent.errors.ComputationLimitError`;
when it runs out during the corrections, they stop there and the result says so
(``stopped_by_time_limit``).  Mismatch fractions are within
:data:`MISMATCH_RANGE` (a true robot of half to twice the model's sizes).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ComputationLimitError, OptionError, PlanningError
from nilpotent.numeric.settings import IntegrationSettings, resolve_settings
from nilpotent.planning import budget
from nilpotent.planning.controls import Segment
from nilpotent.planning.global_planner import (
    MID_TOL,
    GlobalPlan,
    plan_global,
    plan_json,
    steer_admissible,
)
from nilpotent.planning.simulation import PLANNING_SETTINGS, simulate_path
from nilpotent.planning.verify import Checker, Verification, verify_states

__all__ = ["Execution", "execute_plan", "perturbed_system"]

#: Samples per segment when the true robot's motion is checked.
SAMPLES = 100
#: Fractions ``--mismatch`` accepts: the true parameter is ``p (1 + f)``, half to twice ``p``.
MISMATCH_RANGE = (-0.5, 1.0)
#: Most corrections (``--max-corrections``).
MAX_CORRECTIONS = 1000


def perturbed_system(system: ControlSystem, mismatch: Mapping[str, float]) -> ControlSystem:
    """The model with each parameter ``p`` of ``mismatch`` replaced by ``p (1 + mismatch[p])``.

    Raises
    ------
    OptionError
        An unknown parameter, or a fraction outside :data:`MISMATCH_RANGE`.
    """
    values = system.parameter_values
    new = {}
    for name, frac in mismatch.items():
        if name not in values:
            known = ", ".join(values) or "none"
            raise OptionError(f"--mismatch: model {system.name} has no parameter {name!r} "
                              f"(parameters: {known})")
        lo, hi = MISMATCH_RANGE
        if not (math.isfinite(frac) and lo <= frac <= hi):
            raise OptionError(
                f"--mismatch {name}={frac:g}: the fraction must be between {lo:g} and {hi:g} "
                f"(the true {name} between {1 + lo:g} and {1 + hi:g} times the model's)")
        new[name] = float(values[name]) * (1.0 + frac)
    return system.with_parameters(new) if new else system


@dataclass(frozen=True, eq=False)
class Execution:
    """What happened when a plan was executed on the true robot.

    Attributes
    ----------
    closed_loop:
        Dense check of the true robot's motion under re-planning
        (``error``: true final distance to the goal).
    open_loop:
        The same for the plan's controls applied unchanged.
    measured_error:
        The last measured distance to the goal (what the feedback saw).
    replans:
        How many times controls were re-computed.
    violations, open_loop_violations:
        One sentence per kind of violation of the true motion (empty: none).
    mismatch, noise, seed, tol:
        The execution's settings.
    stopped_by_time_limit:
        The corrections stopped because the time limit ran out.
    safety_stops:
        How many times the true robot was stopped before leaving the admissible set
        (module doc).
    """

    plan: GlobalPlan
    closed_loop: Verification
    open_loop: Verification
    measured_error: float
    replans: int
    violations: tuple[str, ...]
    open_loop_violations: tuple[str, ...]
    mismatch: dict[str, float]
    noise: float
    seed: int
    tol: float
    segments: tuple[Segment, ...] = ()
    stopped_by_time_limit: bool = False
    safety_stops: int = 0

    @property
    def reached(self) -> bool:
        return self.closed_loop.error <= self.tol and not self.violations

    def to_json(self) -> dict[str, Any]:
        """``nilpotent/execution@1``: settings (``planner``: the holonomic stage of the plan
        and of every re-plan), closed- and open-loop errors and violations."""
        def block(v: Verification, violations: tuple[str, ...]) -> dict[str, Any]:
            return {"reached": list(v.reached), "error": v.error, "clearance": v.clearance,
                    "limits_ok": v.limits_ok, "limit_margin": v.limit_margin,
                    "self_clearance": v.self_clearance,
                    "self_collision_ok": v.self_collision_ok,
                    "min_singular_margin": v.min_singular_margin,
                    "violations": list(violations)}

        return plan_json({
            "schema": "nilpotent/execution@1",
            "model": self.plan.plan.system.name,
            "coordinates": list(self.plan.plan.system.coordinate_names),
            "from": list(self.plan.plan.start),
            "to": list(self.plan.plan.goal),
            "world": None if self.plan.world is None else self.plan.world.name,
            "planner": self.plan.planner,
            "mismatch": self.mismatch,
            "noise": self.noise,
            "seed": self.seed,
            "tol": self.tol,
            "success": self.reached,
            "stopped_by_time_limit": self.stopped_by_time_limit,
            "safety_stops": self.safety_stops,
            "closed_loop": {**block(self.closed_loop, self.violations),
                            "measured_error": self.measured_error, "replans": self.replans,
                            "segments": [s.to_dict() for s in self.segments]},
            "open_loop": block(self.open_loop, self.open_loop_violations),
        })


def _violations(checker: Checker, states: np.ndarray) -> tuple[str, ...]:
    clear, lim, sing = checker.measures(states)
    out = []
    if np.any(clear <= checker.clearance):
        k = int(np.argmin(clear))
        out.append(f"contact with an obstacle or the bounds (clearance {clear[k]:.3g} at "
                   f"sample {k})")
    if np.any(lim < 0):
        out.append(f"limits exceeded by up to {-lim.min():.3g}")
    self_clear = checker.self_clearance(states)
    if np.any(~(self_clear > 0)):
        k = int(np.argmin(self_clear))
        out.append(f"self-collision (two bodies that must not touch meet at sample {k})")
    if checker.margin_fn is not None and np.any(sing < checker.singular_margin):  # type: ignore[attr-defined]
        out.append(f"singular margin down to {sing.min():.3g} < {checker.singular_margin:g}")
    return tuple(out)


def execute_plan(
    glob: GlobalPlan,
    mismatch: Mapping[str, float] | None = None,
    noise: float = 0.0,
    seed: int = 0,
    tol: float = 1e-3,
    max_corrections: int = 10,
    time_limit: float = 60.0,
    settings: IntegrationSettings | None = None,
) -> Execution:
    """Execute ``glob`` on the perturbed robot with re-planning after each piece (module doc).

    Parameters
    ----------
    glob:
        A plan from :func:`~nilpotent.planning.global_planner.plan_global`.
    mismatch:
        Parameter name → relative error of the true robot.
    noise:
        Standard deviation of the measurement noise (every coordinate, model units).
    seed:
        Seed of the noise.
    tol:
        The measured error at which the corrections stop.
    max_corrections:
        Most re-plans toward the goal after the last piece (0 to :data:`MAX_CORRECTIONS`).
    time_limit:
        Seconds for the whole execution (within an enclosing budget, the earlier end).
    settings : IntegrationSettings or None
        How the model (re-planning) and the true robot are integrated (default
        :data:`~nilpotent.planning.simulation.PLANNING_SETTINGS`).

    Raises
    ------
    OptionError
        Bad mismatch, noise, number of corrections or ``settings``.
    PlanningError
        A re-plan from a measured state fails (model steering and global planner).
    ComputationLimitError
        The time limit ran out before every piece of the plan was executed.
    """
    if not (0 <= max_corrections <= MAX_CORRECTIONS):
        raise OptionError(
            f"--max-corrections must be between 0 and {MAX_CORRECTIONS}, got {max_corrections}")
    if not time_limit > 0:
        raise OptionError(f"--time-limit must be a positive number of seconds, got {time_limit}")
    chosen = resolve_settings(settings, PLANNING_SETTINGS)
    with budget.time_budget(time_limit):
        return _execute(glob, mismatch, noise, seed, tol, max_corrections, time_limit, chosen)


def _execute(
    glob: GlobalPlan,
    mismatch: Mapping[str, float] | None,
    noise: float,
    seed: int,
    tol: float,
    max_corrections: int,
    time_limit: float,
    settings: IntegrationSettings,
) -> Execution:
    if not (math.isfinite(noise) and noise >= 0):
        raise OptionError(f"--noise must be >= 0, got {noise}")
    if not (math.isfinite(tol) and tol > 0):
        raise OptionError(f"--tol must be > 0, got {tol}")
    mismatch = dict(mismatch or {})
    model = glob.plan.system
    true = perturbed_system(model, mismatch)
    rng = np.random.default_rng(seed)
    nominal = Checker(model, glob.world, glob.limits, glob.singular_margin,
                      glob.clearance_required)
    actual = Checker(true, glob.world, glob.limits, glob.singular_margin, glob.clearance_required)
    x0 = np.array(glob.plan.start)
    goal = np.array(glob.plan.goal)
    options = {"settings": settings, "anchor": "auto", "max_iterations": 30}

    def measure(x: np.ndarray) -> np.ndarray:
        return x + (rng.normal(0.0, noise, x.shape) if noise > 0 else 0.0)

    def controls(x_meas: np.ndarray, target: np.ndarray, piece_tol: float) -> list[Segment]:
        p = steer_admissible(model, nominal, x_meas, target, piece_tol, options)
        if p is not None:
            return list(p.segments)
        if not nominal.valid(x_meas[None, :])[0]:
            raise PlanningError(
                f"re-planning failed: the measured state is not admissible for the model "
                f"({nominal.why_invalid(x_meas)})"
            )
        g = plan_global(model, x_meas, target, piece_tol, world=glob.world, limits=glob.limits,
                        singular_margin=glob.singular_margin, time_limit=time_limit,
                        seed=seed, clearance=glob.clearance_required, settings=settings,
                        planner=glob.planner)
        return list(g.plan.segments)

    x = x0.copy()
    x_meas = measure(x)
    states = [x[None, :]]
    times = [np.zeros(1)]
    t_offset = 0.0
    applied: list[Segment] = []
    replans = 0
    stops = 0

    def apply(segs: list[Segment]) -> bool:
        """Drive the true robot; False: a safety stop cut the motion (module doc)."""
        nonlocal x, x_meas, t_offset, stops
        if not segs:
            return True
        t, q = simulate_path(true, x, segs, SAMPLES, settings, hard=True)
        bad = np.flatnonzero(~actual.valid(q))
        whole = not bad.size
        if not whole:
            last = max(int(bad[0]) - 1, 0)  # the last admissible sample (0: where it stood)
            t, q = t[: last + 1], q[: last + 1]
            segs = _cut(segs, float(t[-1]))
            stops += 1
        states.append(q[1:])
        times.append(t[1:] + t_offset)
        t_offset += float(t[-1])
        x = q[-1]
        x_meas = measure(x)
        applied.extend(segs)
        return whole

    corrections = max_corrections
    for k, piece in enumerate(glob.pieces):
        final = k == len(glob.pieces) - 1
        target = np.array(piece.target)
        replans += 1
        if not apply(controls(x_meas, target, glob.plan.tol if final else MID_TOL)):
            break  # stopped: re-plan from where it stands toward the goal
    stopped = False
    for _ in range(corrections):
        if float(np.linalg.norm(x_meas - goal)) <= tol:
            break
        try:
            apply(controls(x_meas, goal, min(glob.plan.tol, tol / 10)))
        except PlanningError:
            if not stops:
                raise
            break  # after a safety stop, no admissible re-plan: it stays (success false)
        except ComputationLimitError:
            stopped = True  # the robot stays where it is: the result says so
            break
        replans += 1
    closed = verify_states(actual, np.concatenate(times), np.vstack(states), goal)
    t_open, q_open = simulate_path(true, x0, list(glob.plan.segments), SAMPLES, settings,
                                   hard=True)
    opened = verify_states(actual, t_open, q_open, goal)
    return Execution(
        plan=glob, closed_loop=closed, open_loop=opened,
        measured_error=float(np.linalg.norm(x_meas - goal)), replans=replans,
        violations=_violations(actual, closed.states),
        open_loop_violations=_violations(actual, q_open),
        mismatch=mismatch, noise=noise, seed=seed, tol=tol, segments=tuple(applied),
        stopped_by_time_limit=stopped, safety_stops=stops,
    )


def _cut(segments: list[Segment], until: float) -> list[Segment]:
    """The controls ``segments`` up to time ``until`` (the last one shortened; a segment's
    inputs are functions of the time since its start, so a prefix is the same motion)."""
    from dataclasses import replace

    out: list[Segment] = []
    start = 0.0
    for seg in segments:
        if start + seg.duration >= until:
            if until > start:
                out.append(replace(seg, duration=until - start))
            break
        out.append(seg)
        start += seg.duration
    return out
