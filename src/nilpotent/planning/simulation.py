"""Simulation of the true system under plan controls (through :mod:`nilpotent.numeric`).

Segments (:class:`~nilpotent.planning.controls.Segment`) are converted to the
numeric layer's :class:`~nilpotent.numeric.signals.Signal` (``Signal.stack``; the same
format: constant plus ``cos``/``sin`` harmonics, time restarting in every
segment) and integrated with adaptive DOP853 at tight tolerances.  Several
candidate controls from the same state are integrated as one batch.

Every integration is bounded (:mod:`nilpotent.planning.budget`): at most
:data:`MAX_STEPS` steps per segment of a trajectory, and no more steps than the time left
in the budget allows at the cost per step measured so far; a trajectory cut by
the budget raises :class:`~nilpotent.errors.ComputationLimitError` once the
deadline has passed (before it, it is retried with the steps the new estimate
allows).  A candidate that needs more than :data:`MAX_STEPS` steps (it runs
into a singularity of the fields) is given up (NaN), never integrated for
minutes.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Sequence

import numpy as np

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import IntegrationError
from nilpotent.numeric.engines import choose_engine
from nilpotent.numeric.integrate import Status, integrate
from nilpotent.numeric.settings import DEFAULT_SETTINGS, IntegrationSettings
from nilpotent.numeric.signals import Signal
from nilpotent.numeric.types import State
from nilpotent.planning import budget
from nilpotent.planning.controls import Segment
from nilpotent.planning.local_model import compiled_system
from nilpotent.simulation.trajectory import Trajectory, simulate, stationary

#: Most steps of one trajectory per segment of its controls (accepted and rejected);
#: more: given up.
MAX_STEPS = 20_000
#: The integration of the true system (adaptive DOP853): the one default
#: (:data:`nilpotent.numeric.settings.DEFAULT_SETTINGS`) with ``rtol = 1e-12``,
#: ``atol = 1e-13`` (a documented override: a plan is checked against its goal
#: tolerance, far below the default's) and ``max_steps = MAX_STEPS``.  In planning,
#: ``max_steps`` counts the steps *per segment of the controls* (a trajectory of
#: ``k`` segments may take ``k * max_steps``), and fewer are allowed when the time
#: budget is short (module doc); ``engine="auto"`` means :func:`single_engine`.
PLANNING_SETTINGS = DEFAULT_SETTINGS.replace(rtol=1e-12, atol=1e-13, max_steps=MAX_STEPS)
#: First guess of the wall-clock cost of one step per trajectory, by engine (seconds),
#: replaced by what is measured.
_STEP_COST: dict[str, float] = {"scipy": 2e-3, "numba": 2e-5, "heyoka": 2e-5, "numpy": 1e-4}


def _step_cap(engine: str, batch: int, hard: bool, most: int = MAX_STEPS) -> int:
    """Steps per trajectory the time left allows (at most ``most``)."""
    left = budget.seconds_left(hard)
    if math.isinf(left):
        return most
    cost = _STEP_COST.get(engine, 1e-3) * max(1, batch if engine in ("scipy", "numpy") else 1)
    return int(min(most, max(1, left / cost)))


def _learn(engine: str, seconds: float, steps: float, batch: int) -> None:
    if steps > 50:
        per = seconds / steps / max(1, batch if engine in ("scipy", "numpy") else 1)
        _STEP_COST[engine] = 0.5 * _STEP_COST.get(engine, per) + 0.5 * per


def _bounded_integrate(compiled, xs: np.ndarray, inputs: Signal, settings: IntegrationSettings,
                       engine: str, what: str, hard: bool = False, most: int = MAX_STEPS):
    """:func:`integrate` within the budget; returns ``(final, ok)``.

    Raises
    ------
    ComputationLimitError
        The budget ran out before the trajectories ended.
    """
    batch = xs.shape[0]
    while True:
        budget.check(what, hard)
        cap = _step_cap(engine, batch, hard, most)
        t0 = time.perf_counter()
        sol = integrate(compiled, xs, inputs,
                        settings=settings.replace(engine=engine, max_steps=cap))
        spent = time.perf_counter() - t0
        steps = np.asarray(sol.steps, dtype=float) + np.asarray(sol.rejected, dtype=float)
        _learn(engine, spent, float(steps.sum()) / max(1, batch), batch)
        cut = np.asarray(sol.status) == int(Status.MAX_STEPS)
        if cap >= most or not cut.any():
            return np.array(sol.final), np.asarray(sol.ok)
        budget.check(what, hard)  # cut by the time left: retried while time remains


def single_engine(settings: IntegrationSettings, system: ControlSystem) -> str:
    """The engine (:mod:`nilpotent.numeric.engines`) that ``settings.engine`` means for one
    trajectory of ``system``: with ``"auto"``, numba when its kernels for the system are
    already compiled, else scipy (one plan costs less than a compilation)."""
    return choose_engine(compiled_system(system), settings.method, settings.engine, 1).name


def simulate_candidates(
    system: ControlSystem,
    x0: Sequence[float] | State,
    candidates: Sequence[Sequence[Segment]],
    settings: IntegrationSettings = PLANNING_SETTINGS,
    hard: bool = False,
) -> np.ndarray:
    """End states ``(len(candidates), n)`` of the true system from ``x0``; NaN where it failed.

    Integrated with ``settings`` (:data:`PLANNING_SETTINGS` by default) within the
    planning budget (module doc; ``hard``: up to its hard deadline).

    Raises
    ------
    ComputationLimitError
        The budget ran out before the integrations ended.
    """
    compiled = compiled_system(system)
    by_len: dict[int, list[int]] = {}
    for idx, segs in enumerate(candidates):
        by_len.setdefault(len(segs), []).append(idx)
    out = np.full((len(candidates), system.n), np.nan)
    x = np.asarray(x0, dtype=float)
    for length, idxs in by_len.items():
        if length == 0:
            out[idxs] = x
            continue
        name = single_engine(settings, system)
        # one trajectory at a time where the engine runs them one by one anyway, so that
        # the budget is checked between them
        groups = [[i] for i in idxs] if name == "scipy" else [idxs]
        for group in groups:
            inputs = Signal.stack([candidates[i] for i in group])
            final, ok = _bounded_integrate(
                compiled, np.repeat(x[None, :], len(group), axis=0), inputs, settings, name,
                "integrating candidate controls of the true system", hard,
                settings.max_steps * length)
            final[~ok] = np.nan
            out[group] = final
    return out


def simulate_path(
    system: ControlSystem,
    x0: Sequence[float] | State,
    segments: Sequence[Segment],
    points_per_segment: int = 40,
    settings: IntegrationSettings = PLANNING_SETTINGS,
    hard: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """``(times, states)`` of the true system under ``segments`` (:func:`simulate_plan`'s samples).

    Raises
    ------
    IntegrationError
        The integration stopped before the end of the controls.
    ComputationLimitError
        The samples would exceed the memory budget, or the time budget ran out.
    """
    traj = simulate_plan(system, x0, segments, points_per_segment, settings, hard)
    return np.array(traj.times), np.array(traj.states)


def simulate_plan(
    system: ControlSystem,
    x0: Sequence[float] | State,
    segments: Sequence[Segment],
    points_per_segment: int = 40,
    settings: IntegrationSettings = PLANNING_SETTINGS,
    hard: bool = False,
) -> Trajectory:
    """The true system's :class:`~nilpotent.simulation.trajectory.Trajectory` under
    ``segments``, sampled ``points_per_segment`` times in every segment.

    Integrated with ``settings`` (:data:`PLANNING_SETTINGS` by default) within the
    planning budget (module doc; ``hard``: up to its hard deadline).

    Raises
    ------
    IntegrationError
        The integration stopped before the end of the controls.
    ComputationLimitError
        The samples would exceed the memory budget, or the time budget ran out.
    """
    if not segments:
        return stationary(compiled_system(system), x0)
    samples = len(segments) * points_per_segment + 1
    budget.check_memory(
        # times, states, and the copies the checks make of them
        4.0 * samples * (system.n + 1) * 8, f"{samples:,} samples of the motion",
        "plan to a nearer goal or raise --max-piece")
    starts = np.concatenate([[0.0], np.cumsum([s.duration for s in segments])])
    times = np.unique(
        np.concatenate(
            [np.linspace(a, b, points_per_segment + 1) for a, b in itertools.pairwise(starts)]
        )
    )
    times = times[times <= starts[-1]]
    what = "re-simulating the motion of the true system"
    name = single_engine(settings, system)
    while True:
        budget.check(what, hard)
        most = settings.max_steps * len(segments)
        cap = _step_cap(name, 1, hard, most)
        t0 = time.perf_counter()
        traj = simulate(
            compiled_system(system), Signal.from_segments(segments), np.asarray(x0, dtype=float),
            times=times, settings=settings.replace(engine=name, max_steps=cap),
        )
        spent = time.perf_counter() - t0
        if traj.status != Status.MAX_STEPS or cap >= most:
            break
        # cut by the time left: learn the cost and retry while time remains
        _STEP_COST[name] = max(_STEP_COST.get(name, 0.0), spent / cap)
        budget.check(what, hard)
    if traj.status != Status.SUCCESS:
        raise IntegrationError(
            f"simulating the plan of {system.name!r} failed: "
            f"{traj.status.message} (the controls drive the system where "
            "it cannot be integrated; try a nearer goal, --anchor goal or fewer iterations)"
        )
    return traj
