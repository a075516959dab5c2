"""The ``numpy`` engine: fixed-step DOP853 vectorised over the batch (no compilation).

Every trajectory takes ``steps`` equal steps per segment (cut at the sample
times); the batch must share its segment durations.  The cheapest start-up,
used by ``engine="auto"`` for the fixed method when numba's kernels are not
compiled yet.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from nilpotent.errors import OptionError
from nilpotent.numeric.compile import CompiledSystem
from nilpotent.numeric.engines.base import Engine, EngineOutput, Status, state_status
from nilpotent.numeric.signals import Signal
from nilpotent.numeric.tableaux import DOP853

__all__ = ["NumpyEngine"]


class NumpyEngine(Engine):
    """Fixed-step DOP853 over the whole batch at once (numpy arrays)."""

    name: ClassVar[str] = "numpy"
    methods: ClassVar[tuple[str, ...]] = ("fixed",)
    summary: ClassVar[str] = "fixed-step DOP853 vectorised over the batch"

    def solve(
        self,
        system: Any,
        xs: np.ndarray,
        signal: Any,
        times: np.ndarray,
        *,
        adaptive: bool,
        steps: int,
        rtol: float,
        atol: float,
        max_steps: int,
        min_step: float,
        bound: float,
        threads: int | None,
    ) -> EngineOutput:
        del adaptive, threads
        with np.errstate(over="ignore", invalid="ignore"):  # stopped trajectories
            return _run_numpy(system, xs, signal, times, steps, rtol=rtol, atol=atol,
                              max_steps=max_steps, min_step=min_step, bound=bound)


def _run_numpy(
    system: CompiledSystem,
    xs: np.ndarray,
    sig: Signal,
    ts: np.ndarray,
    steps: int,
    *,
    rtol: float,
    atol: float,
    max_steps: int,
    min_step: float,
    bound: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    del rtol, atol, min_step  # fixed steps: no error control
    if not np.allclose(sig.durations, sig.durations[:1], rtol=0, atol=0):
        raise OptionError(
            "the numpy engine needs the same segment durations for the whole batch "
            "(use engine='numba' or 'scipy')"
        )
    tab = DOP853
    a_rows = [np.array(r) for r in tab.a]
    b_w = np.array(tab.b)
    batch, n = xs.shape
    rhs = system.numpy_module.rhs
    x = xs.copy()
    alive = state_status(x, bound) == 0
    status = np.where(alive, 0, state_status(x, bound))
    samples = np.full((batch, ts.size, n), np.nan)
    isamp = 0
    while isamp < ts.size and ts[isamp] <= 0.0:
        samples[:, isamp] = x
        isamp += 1
    accepted = np.zeros(batch)
    t0 = 0.0
    durations = sig.durations[0]
    k_stages = np.empty((tab.stages, batch, n))
    for s, d in enumerate(durations):
        seg = np.full(batch, s)
        stops = [float(t - t0) for t in ts[isamp:] if t - t0 < d * (1 - 1e-14)]
        tl = 0.0
        for stop in [*stops, float(d)]:
            if stop - tl > 4e-16 * max(1.0, abs(t0 + tl)):
                npiece = max(1, math.ceil(steps * (stop - tl) / d - 1e-9))
                h = (stop - tl) / npiece
                for _ in range(npiece):
                    if np.any(accepted >= max_steps):
                        over = alive & (accepted >= max_steps)
                        status[over] = Status.MAX_STEPS
                        alive &= ~over
                    for st in range(tab.stages):
                        if st == 0:
                            xst = x
                        else:
                            xst = x + h * np.tensordot(a_rows[st], k_stages[:st], axes=1)
                        u = sig.evaluate_local(seg, np.full(batch, tl + tab.c[st] * h))
                        k_stages[st] = rhs(np.ascontiguousarray(xst), u)
                    xn = x + h * np.tensordot(b_w, k_stages, axes=1)
                    x = np.where(alive[:, None], xn, x)
                    accepted += alive
                    tl += h
                    st_now = state_status(x, bound)
                    newly = alive & (st_now != 0)
                    status[newly] = st_now[newly]
                    alive &= ~newly
                    if not alive.any():
                        break
            tl = stop
            while isamp < ts.size and ts[isamp] - t0 <= tl * (1 + 1e-14) and tl < d:
                samples[alive, isamp] = x[alive]
                isamp += 1
        t0 += float(d)
        while isamp < ts.size and ts[isamp] <= t0 * (1 + 1e-14):
            samples[alive, isamp] = x[alive]
            isamp += 1
    info = np.zeros((batch, 4))
    info[:, 0] = status
    info[:, 1] = accepted
    return x, samples, info
