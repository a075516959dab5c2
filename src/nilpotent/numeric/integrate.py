"""Batched integration of ``dx/dt = Σ_i u_i(t) X_i(x)``: :func:`integrate` → :class:`BatchSolution`.

Methods (registry :data:`METHODS`) run on the engines of
:mod:`nilpotent.numeric.engines` (registry ``ENGINES``, the engine contract
written there):

============  ==========================  =====================================
method        engines                     accuracy reported (``tolerance``)
============  ==========================  =====================================
``adaptive``  ``numba``, ``scipy``,       ``rtol``: every accepted step had its
              ``heyoka``                  local error ≤ ``atol + rtol·|x|``
``fixed``     ``numba``, ``numpy``        step-halving (Richardson) estimate of
                                          the global error, max over the batch
============  ==========================  =====================================

``engine="auto"`` (:func:`~nilpotent.numeric.engines.choose_engine`): for the
adaptive method, ``heyoka`` when the batch has at least
:data:`~nilpotent.numeric.engines.AUTO_NUMBA_BATCH` trajectories or the inputs
run through at least :data:`~nilpotent.numeric.engines.HEYOKA_MIN_CYCLES`
periods (and heyoka is installed, as it is by default); otherwise ``numba`` when its kernels are
already in the on-disk cache or the batch is that large, else ``scipy``
(adaptive) / ``numpy`` (fixed).

Every trajectory gets a :class:`Status`; blow-up (``|x_k| > bound``), a step
below ``min_step`` and ``max_steps`` end that trajectory and are reported,
never raised (:meth:`BatchSolution.raise_for_status` raises when wanted).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from nilpotent.errors import IntegrationError, OptionError
from nilpotent.numeric.compile import CompiledSystem
from nilpotent.numeric.engines import ENGINES as ENGINES
from nilpotent.numeric.engines import choose_engine, input_cycles
from nilpotent.numeric.engines.base import Status as Status
from nilpotent.numeric.engines.base import check_times
from nilpotent.numeric.engines.numba_engine import kernels_cached as kernels_cached
from nilpotent.numeric.engines.scipy_engine import solve_function_input as solve_function_input
from nilpotent.numeric.sampled import as_signal
from nilpotent.numeric.settings import DEFAULT_SETTINGS as DEFAULT_SETTINGS
from nilpotent.numeric.settings import METHODS as METHODS
from nilpotent.numeric.settings import IntegrationSettings as IntegrationSettings
from nilpotent.numeric.settings import resolve_settings
from nilpotent.numeric.signals import FunctionSignal, Signal
from nilpotent.numeric.tableaux import DOP853
from nilpotent.numeric.types import PerTrajectory, Samples, States, Times


def _ro(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class BatchSolution:
    """Result of :func:`integrate` over a batch of ``B`` trajectories.

    Attributes
    ----------
    method, engine:
        What integrated it.
    x0:
        ``(B, n)`` initial states.
    final:
        ``(B, n)`` states at the end (the last state reached if stopped early).
    times:
        ``(T,)`` sample times (global time, from 0).
    samples:
        ``(B, T, n)`` states at ``times`` (NaN past an early stop).
    status:
        ``(B,)`` :class:`Status` codes.
    steps, rejected:
        ``(B,)`` accepted and rejected steps.
    error_estimate:
        ``(B,)`` estimated global error (max norm): for ``fixed`` the step-halving
        estimate ``max|x_N − x_{N/2}| / (2^8 − 1)`` over the end point and the
        samples; for ``adaptive`` (numba) the sum of the accepted local error
        estimates (a heuristic, no propagation); NaN where not available.
    tolerance:
        The accuracy this result met: ``rtol`` for ``adaptive`` (per step, see
        the module docstring), the largest ``error_estimate`` of the successful
        trajectories for ``fixed``.
    rtol, atol, steps_per_segment:
        The accuracy parameters used.
    """

    method: str
    engine: str
    x0: States
    final: States
    times: Times
    samples: Samples
    status: PerTrajectory
    steps: PerTrajectory
    rejected: PerTrajectory
    error_estimate: PerTrajectory
    tolerance: float
    rtol: float
    atol: float
    steps_per_segment: int

    @property
    def ok(self) -> np.ndarray:
        """``(B,)`` True where the trajectory reached the end."""
        return self.status == Status.SUCCESS

    @property
    def all_ok(self) -> bool:
        return bool(np.all(self.ok))

    def raise_for_status(self) -> None:
        """Raise :class:`IntegrationError` if some trajectory did not reach the end."""
        bad = np.flatnonzero(~self.ok)
        if bad.size:
            first = int(bad[0])
            raise IntegrationError(
                f"{bad.size} of {self.status.size} trajectories failed; trajectory {first}: "
                f"{Status(int(self.status[first])).message}"
            )


# --- entry point ---------------------------------------------------------------


def _integrate_function(system: CompiledSystem, xs: np.ndarray, inputs: FunctionSignal,
                        method: str, engine: str, times: Any, rtol: float, atol: float,
                        max_steps: int, bound: float) -> BatchSolution:
    """:func:`integrate` of a function input: ``solve_ivp`` per trajectory."""
    if method != "adaptive" or engine not in ("auto", "scipy"):
        raise OptionError("a function input is integrated by solve_ivp (method='adaptive', "
                          "engine='scipy')")
    ts = check_times(times, np.array([inputs.duration]))
    finals, samples, status, evaluations = [], [], [], []
    for x in xs:
        final, states, code, count = solve_function_input(
            system, x, inputs.evaluate, inputs.breakpoints, times=ts, rtol=rtol, atol=atol,
            max_steps=max_steps, bound=bound)
        finals.append(final)
        samples.append(states)
        status.append(int(code))
        evaluations.append(int(count))
    b, n = xs.shape
    return BatchSolution(
        method="adaptive", engine="scipy", x0=_ro(xs),
        final=_ro(np.array(finals).reshape(b, n)), times=_ro(ts),
        samples=_ro(np.array(samples).reshape(b, ts.size, n)),
        status=_ro(np.array(status, dtype=np.int64)),
        steps=_ro(np.array(evaluations, dtype=np.int64)),
        rejected=_ro(np.zeros(b, dtype=np.int64)), error_estimate=_ro(np.full(b, np.nan)),
        tolerance=float(rtol), rtol=float(rtol), atol=float(atol), steps_per_segment=0,
    )
def integrate(
    system: CompiledSystem,
    x0: Any,
    inputs: Signal | FunctionSignal | Callable[[float], Any] | tuple[Any, Any],
    *,
    duration: float | None = None,
    hold: str = "linear",
    settings: IntegrationSettings | None = None,
    times: Sequence[float] | np.ndarray | None = None,
    min_step: float | None = None,
    estimate_error: bool = True,
    threads: int | None = None,
    method: str | None = None,
    engine: str | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    steps: int | None = None,
    max_steps: int | None = None,
    bound: float | None = None,
) -> BatchSolution:
    """Integrate ``dx/dt = Σ_i u_i(t) X_i(x)`` for a batch of states and inputs.

    Parameters
    ----------
    system:
        The compiled fields (:func:`~nilpotent.numeric.compile.compile_fields`).
    x0:
        ``(B, n)`` initial states (or ``(n,)`` for one).
    inputs:
        A batch of ``B`` input signals, or of 1 shared by all states; or inputs
        shared by all states given as a callable ``u(t) -> (m,)`` (with
        ``duration``), a :class:`~nilpotent.numeric.signals.FunctionSignal`, or
        samples ``(T, U)``: ``T`` of shape ``(K,)`` from 0, ``U`` of shape
        ``(K, m)`` (:func:`~nilpotent.numeric.sampled.as_signal`, the one
        conversion).  A function input (a callable, or samples with
        ``hold="linear"``) is integrated by the scipy engine (``solve_ivp``,
        adaptive), one trajectory after the other.
    duration:
        End of a callable input's interval ``[0, duration]``.
    hold:
        How samples ``(T, U)`` are read between their times: ``"linear"``
        interpolation (as python-control) or ``"zero"``-order hold.
    settings : IntegrationSettings or None
        Method, engine (see the module docstring), tolerances, steps and blow-up
        bound (:class:`~nilpotent.numeric.settings.IntegrationSettings`; default
        :data:`~nilpotent.numeric.settings.DEFAULT_SETTINGS`).  A trajectory with
        some ``|x_k| > bound`` is stopped (:attr:`Status.BLOW_UP`).
    times:
        Sample times in ``[0, duration]`` (shared by the batch; sorted).
    min_step:
        Smallest step of the adaptive method (default ``1e-13 ×`` duration);
        numba only (scipy and heyoka have none).
    estimate_error:
        For ``fixed``: also integrate with ``steps/2`` to estimate the error.
    threads:
        Number of numba threads (default: numba's setting), or of threads
        running heyoka's SIMD batches (default: one more than the cores this
        process may use, so that every core stays busy while a thread waits
        for Python's GIL; the results do not depend on it).
    method, engine, rtol, atol, steps, max_steps, bound : optional
        The loose form of ``settings`` (kept for one release): each one given
        overrides that field of ``settings``.

    Raises
    ------
    OptionError
        An unknown ``method`` or ``engine``, initial states whose shape is not
        ``(B, n)``, inputs for another number of fields or batch size, or bad
        tolerances, steps or bounds.
    MissingExtraError
        The engine asked for is not installed.
    """
    chosen_settings = resolve_settings(settings, DEFAULT_SETTINGS, method=method, engine=engine,
                                       rtol=rtol, atol=atol, steps=steps, max_steps=max_steps,
                                       bound=bound)
    method, engine = chosen_settings.method, chosen_settings.engine
    rtol, atol, steps = chosen_settings.rtol, chosen_settings.atol, chosen_settings.steps
    max_steps, bound = chosen_settings.max_steps, chosen_settings.bound
    xs = np.ascontiguousarray(np.atleast_2d(np.asarray(x0, dtype=np.float64)))
    if xs.ndim != 2 or xs.shape[1] != system.n:
        raise OptionError(f"initial states must have shape (B, {system.n}), got {np.shape(x0)}")
    inputs = as_signal(inputs, system.m, duration=duration, hold=hold)
    if isinstance(inputs, FunctionSignal):
        return _integrate_function(system, xs, inputs, method, engine, times, rtol, atol,
                                   max_steps, bound)
    batch = xs.shape[0]
    sig = inputs.broadcast(batch)
    total = sig.total_durations
    ts = check_times(times, total)
    if method == "fixed" and estimate_error and steps % 2:
        raise OptionError(f"steps must be an even integer >= 2, got {steps}")
    if min_step is None:
        min_step = 1e-13 * float(np.max(total)) if batch else 0.0
    chosen = choose_engine(system, method, engine, batch, input_cycles(sig))
    chosen.require()
    adaptive = method == "adaptive"
    if batch == 0:  # nothing to integrate: an empty solution of the right shapes
        empty = np.zeros((0, 4))
        final, samples, info = np.zeros((0, system.n)), np.zeros((0, ts.size, system.n)), empty
        return BatchSolution(
            method=method, engine=chosen.name, x0=_ro(xs), final=_ro(final), times=_ro(ts),
            samples=_ro(samples), status=_ro(np.zeros(0, dtype=np.int64)),
            steps=_ro(np.zeros(0, dtype=np.int64)), rejected=_ro(np.zeros(0, dtype=np.int64)),
            error_estimate=_ro(np.zeros(0)),
            tolerance=float(rtol) if adaptive else float("nan"), rtol=float(rtol),
            atol=float(atol), steps_per_segment=int(steps) if method == "fixed" else 0,
        )

    def run(step_count: int, adaptive_steps: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return chosen.solve(system, xs, sig, ts, adaptive=adaptive_steps, steps=step_count,
                            rtol=float(rtol), atol=float(atol), max_steps=int(max_steps),
                            min_step=float(min_step), bound=float(bound), threads=threads)

    final, samples, info = run(int(steps), adaptive)
    status = info[:, 0].astype(np.int64)
    err = info[:, 3].copy() if chosen.name == "numba" and adaptive else np.full(batch, np.nan)
    if adaptive:
        tolerance = float(rtol)
    elif estimate_error:
        half = int(steps) // 2
        f2, s2, _ = run(half, False)
        diff = np.abs(final - f2).max(axis=1)
        if ts.size:
            diff = np.maximum(diff, np.nan_to_num(np.abs(samples - s2), nan=np.inf).max(
                axis=(1, 2)))
        err = diff / (2.0**DOP853.order - 1.0)
        good = err[status == 0]
        tolerance = float(good.max()) if good.size else float("nan")
    else:
        tolerance = float("nan")
    return BatchSolution(
        method=method,
        engine=chosen.name,
        x0=_ro(xs),
        final=_ro(final),
        times=_ro(ts),
        samples=_ro(samples),
        status=_ro(info[:, 0].astype(np.int64)),
        steps=_ro(info[:, 1].astype(np.int64)),
        rejected=_ro(info[:, 2].astype(np.int64)),
        error_estimate=_ro(err),
        tolerance=tolerance,
        rtol=float(rtol),
        atol=float(atol),
        steps_per_segment=int(steps) if method == "fixed" else 0,
    )
