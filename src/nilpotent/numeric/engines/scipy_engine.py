"""The ``scipy`` engine: :func:`scipy.integrate.solve_ivp` (DOP853), one trajectory at a time.

The reference engine: no compilation, restarts at every segment boundary (and
at the breakpoints of inputs given as Python functions,
:func:`solve_function_input`), blow-ups caught by a terminal event.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from typing import Any, ClassVar

import numpy as np

from nilpotent.errors import OptionError
from nilpotent.numeric.compile import CompiledSystem
from nilpotent.numeric.engines.base import Engine, EngineOutput, Status, check_times, state_status
from nilpotent.numeric.signals import Signal
from nilpotent.numeric.tableaux import DOP853

__all__ = ["ScipyEngine", "solve_function_input"]


class ScipyEngine(Engine):
    """``solve_ivp`` DOP853 per trajectory (adaptive; the reference)."""

    name: ClassVar[str] = "scipy"
    methods: ClassVar[tuple[str, ...]] = ("adaptive",)
    summary: ClassVar[str] = "scipy.integrate.solve_ivp (DOP853) per trajectory, the reference"

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
        del adaptive, steps, threads
        return _run_scipy(system, xs, signal, times, rtol=rtol, atol=atol,
                          max_steps=max_steps, min_step=min_step, bound=bound)


class _TooManySteps(Exception):
    pass


def solve_function_input(
    system: CompiledSystem,
    x0: Any,
    u: Callable[[float], Any],
    breakpoints: Sequence[float] | np.ndarray,
    *,
    times: Sequence[float] | np.ndarray | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    max_steps: int = 100_000,
    bound: float = 1e8,
) -> tuple[np.ndarray, np.ndarray, Status, int]:
    """Integrate one trajectory with :func:`scipy.integrate.solve_ivp` (DOP853).

    ``u(t)`` returns the ``m`` inputs at global time ``t`` (any Python function);
    ``breakpoints`` ``0 = t_0 < t_1 < … < t_S`` are where ``u`` may jump (the
    integration restarts there) and ``t_S`` is the end.  Returns
    ``(final (n,), samples (T, n), status, evaluations)``.
    """
    from scipy.integrate import solve_ivp

    x = np.asarray(x0, dtype=float).copy()
    bps = [float(b) for b in breakpoints]
    if len(bps) < 2 or any(b1 <= b0 for b0, b1 in itertools.pairwise(bps)) or bps[0] != 0:
        raise OptionError("breakpoints must start at 0 and increase")
    ts = check_times(times, np.array([bps[-1]]))
    samples = np.full((ts.size, system.n), np.nan)
    counter = [0]
    rhs1 = system.numpy_module.rhs

    def fun(t: float, y: np.ndarray) -> np.ndarray:
        counter[0] += 1
        if counter[0] > 12 * max_steps:
            raise _TooManySteps
        uu = np.asarray(u(t), dtype=float).reshape(1, system.m)
        return rhs1(y.reshape(1, -1), uu)[0]

    def escape(t: float, y: np.ndarray) -> float:
        return bound - float(np.max(np.abs(y)))

    escape.terminal = True  # type: ignore[attr-defined]
    status = Status(int(state_status(x[None], bound)[0]))
    for k, (a, b) in enumerate(itertools.pairwise(bps)):
        if status != Status.SUCCESS:
            break
        last = k == len(bps) - 2
        inside = ts[(ts >= a) & ((ts < b) | (last & (ts <= b)))]
        teval = np.unique(np.concatenate([inside, [b]]))
        try:
            with np.errstate(all="ignore"):
                if not np.all(np.isfinite(fun(a, x))):
                    status = Status.NON_FINITE
                    break
                sol = solve_ivp(fun, (a, b), x, method="DOP853", rtol=rtol, atol=atol,
                                t_eval=teval, events=escape)
        except _TooManySteps:
            status = Status.MAX_STEPS
            break
        y = np.asarray(sol.y, dtype=float)
        got = y.T if y.ndim == 2 else np.zeros((0, system.n))  # empty when stopped early
        if inside.size:
            pos = np.searchsorted(teval, inside)
            keep = pos < got.shape[0]
            samples[np.searchsorted(ts, inside)[keep]] = got[pos[keep]]
        if sol.status == 1:
            status = Status.BLOW_UP
            x = np.asarray(sol.y_events[0][0], dtype=float)
        elif sol.status != 0:
            status = Status.STEP_TOO_SMALL
            x = got[-1].copy() if got.shape[0] else x
        else:
            x = got[-1].copy()
            status = Status(int(state_status(x[None], bound)[0]))
    return x, samples, status, counter[0]


def _run_scipy(
    system: CompiledSystem,
    xs: np.ndarray,
    sig: Signal,
    ts: np.ndarray,
    *,
    rtol: float,
    atol: float,
    max_steps: int,
    min_step: float,
    bound: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    del min_step
    batch = xs.shape[0]
    final = np.empty_like(xs)
    samples = np.full((batch, ts.size, system.n), np.nan)
    info = np.zeros((batch, 4))
    for b in range(batch):
        one = sig[b]
        bps = np.concatenate([[0.0], np.cumsum(one.durations[0])])

        def u(t: float, one: Signal = one) -> np.ndarray:
            return one.evaluate_batch(t)[0]

        f, smp, st, nfev = solve_function_input(
            system, xs[b], u, bps, times=ts, rtol=rtol, atol=atol,
            max_steps=max_steps, bound=bound,
        )
        final[b] = f
        samples[b] = smp
        info[b, 0] = int(st)
        info[b, 1] = nfev / DOP853.stages
        info[b, 3] = np.nan
    return final, samples, info
