"""Simulation of the true system under plan controls (through :mod:`nilpotent.numeric`).

Segments (:class:`~nilpotent.planning.controls.Segment`) are converted to the
numeric layer's :class:`~nilpotent.numeric.signals.Signal` (``Signal.stack``; the same
format: constant plus ``cos``/``sin`` harmonics, time restarting in every
segment) and integrated with adaptive DOP853 at tight tolerances.  Several
candidate controls from the same state are integrated as one batch.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import IntegrationError
from nilpotent.numeric.engines import choose_engine
from nilpotent.numeric.integrate import Status, integrate
from nilpotent.numeric.signals import Signal
from nilpotent.numeric.types import State
from nilpotent.planning.controls import Segment
from nilpotent.planning.local_model import compiled_system
from nilpotent.simulation.trajectory import Trajectory, simulate, stationary

#: Tolerances of the true-system integration (DOP853).
RTOL = 1e-12
ATOL = 1e-13


def single_engine(engine: str, system: ControlSystem) -> str:
    """The engine (:mod:`nilpotent.numeric.engines`) that ``engine`` means for one trajectory
    of ``system``: with ``"auto"``, numba when its kernels for the system are already
    compiled, else scipy (one plan costs less than a compilation)."""
    return choose_engine(compiled_system(system), "adaptive", engine, 1).name


def simulate_candidates(
    system: ControlSystem,
    x0: Sequence[float] | State,
    candidates: Sequence[Sequence[Segment]],
    engine: str = "auto",
) -> np.ndarray:
    """End states ``(len(candidates), n)`` of the true system from ``x0``; NaN where it failed."""
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
        inputs = Signal.stack([candidates[i] for i in idxs])
        sol = integrate(
            compiled, np.repeat(x[None, :], len(idxs), axis=0), inputs,
            engine=single_engine(engine, system), rtol=RTOL, atol=ATOL,
        )
        final = np.array(sol.final)
        final[~sol.ok] = np.nan
        out[idxs] = final
    return out


def simulate_path(
    system: ControlSystem,
    x0: Sequence[float] | State,
    segments: Sequence[Segment],
    points_per_segment: int = 40,
    engine: str = "auto",
) -> tuple[np.ndarray, np.ndarray]:
    """``(times, states)`` of the true system under ``segments`` (:func:`simulate_plan`'s samples).

    Raises
    ------
    IntegrationError
        The integration stopped before the end of the controls.
    """
    traj = simulate_plan(system, x0, segments, points_per_segment, engine)
    return np.array(traj.times), np.array(traj.states)


def simulate_plan(
    system: ControlSystem,
    x0: Sequence[float] | State,
    segments: Sequence[Segment],
    points_per_segment: int = 40,
    engine: str = "auto",
) -> Trajectory:
    """The true system's :class:`~nilpotent.simulation.trajectory.Trajectory` under
    ``segments``, sampled ``points_per_segment`` times in every segment.

    Raises
    ------
    IntegrationError
        The integration stopped before the end of the controls.
    """
    if not segments:
        return stationary(compiled_system(system), x0)
    starts = np.concatenate([[0.0], np.cumsum([s.duration for s in segments])])
    times = np.unique(
        np.concatenate(
            [np.linspace(a, b, points_per_segment + 1) for a, b in itertools.pairwise(starts)]
        )
    )
    times = times[times <= starts[-1]]
    traj = simulate(
        compiled_system(system), Signal.from_segments(segments), np.asarray(x0, dtype=float),
        times=times, engine=single_engine(engine, system), rtol=RTOL, atol=ATOL,
    )
    if traj.status != Status.SUCCESS:
        raise IntegrationError(
            f"simulating the plan of {system.name!r} failed: "
            f"{traj.status.message} (the controls drive the system where "
            "it cannot be integrated; try a nearer goal, --anchor goal or fewer iterations)"
        )
    return traj
