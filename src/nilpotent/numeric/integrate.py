"""Batched integration of ``dx/dt = Σ_i u_i(t) X_i(x)``.

Methods (registry :data:`METHODS`), engines (:data:`ENGINES`):

============  ==========================  =====================================
method        engines                     accuracy reported (``tolerance``)
============  ==========================  =====================================
``adaptive``  ``numba``, ``scipy``,       ``rtol``: every accepted step had its
              ``heyoka``                  local error ≤ ``atol + rtol·|x|``
``fixed``     ``numba``, ``numpy``        step-halving (Richardson) estimate of
                                          the global error, max over the batch
============  ==========================  =====================================

* ``numba``: the DOP853 kernels of :mod:`nilpotent.numeric.kernels`, compiled
  into the system's cached module, ``prange`` over the batch;
* ``numpy``: the same fixed-step DOP853 vectorised over the batch;
* ``heyoka``: heyoka's adaptive Taylor method in SIMD batches
  (:mod:`nilpotent.numeric.heyoka_engine`; tolerance ``min(rtol, atol)``, no
  ``min_step``); the fastest engine measured here (``benchmarks/RESULTS.md``);
* ``scipy``: :func:`scipy.integrate.solve_ivp` (``DOP853``) trajectory by
  trajectory, the reference; it also accepts inputs given as a Python function
  of ``t`` (:func:`solve_function_input`);
* ``auto``: for the adaptive method, ``heyoka`` when the batch has at least
  :data:`AUTO_NUMBA_BATCH` trajectories (and heyoka is installed, as it is by
  default); otherwise ``numba`` when its kernels are already in the on-disk
  cache or the batch is that large, else ``scipy`` (adaptive) / ``numpy``
  (fixed).

Every trajectory gets a :class:`Status`; blow-up (``|x_k| > bound``), a step
below ``min_step`` and ``max_steps`` end that trajectory and are reported,
never raised (:meth:`BatchSolution.raise_for_status` raises when wanted).
"""

from __future__ import annotations

import contextlib
import itertools
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

import numpy as np

from nilpotent.errors import IntegrationError, OptionError
from nilpotent.numeric.compile import CompiledSystem, numba_available
from nilpotent.numeric.signals import Signal
from nilpotent.numeric.tableaux import DOP853

METHODS: dict[str, str] = {
    "adaptive": "DOP853 with embedded error control (scipy's step-size rules)",
    "fixed": "DOP853 with equal steps per segment; error estimated by step halving",
}
ENGINES = ("auto", "numba", "numpy", "scipy", "heyoka")
_SUPPORTED = {"adaptive": ("numba", "scipy", "heyoka"), "fixed": ("numba", "numpy")}

#: ``engine="auto"`` compiles numba kernels from this batch size on (below it
#: only when they are already cached).
AUTO_NUMBA_BATCH = 64


class Status(IntEnum):
    """Outcome of one trajectory."""

    SUCCESS = 0
    MAX_STEPS = 1
    STEP_TOO_SMALL = 2
    BLOW_UP = 3
    NON_FINITE = 4

    @property
    def message(self) -> str:
        return {
            0: "integrated to the end",
            1: "stopped: too many steps (max_steps)",
            2: "stopped: step size below min_step",
            3: "stopped: the state left the bound |x_k| <= bound (blow-up)",
            4: "stopped: the state is not finite",
        }[int(self)]


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
    x0: np.ndarray
    final: np.ndarray
    times: np.ndarray
    samples: np.ndarray
    status: np.ndarray
    steps: np.ndarray
    rejected: np.ndarray
    error_estimate: np.ndarray
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
def integrate(
    system: CompiledSystem,
    x0: Any,
    inputs: Signal,
    *,
    method: str = "adaptive",
    engine: str = "auto",
    times: Sequence[float] | np.ndarray | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    steps: int = 64,
    max_steps: int = 100_000,
    min_step: float | None = None,
    bound: float = 1e8,
    estimate_error: bool = True,
    threads: int | None = None,
) -> BatchSolution:
    """Integrate ``dx/dt = Σ_i u_i(t) X_i(x)`` for a batch of states and inputs.

    Parameters
    ----------
    system:
        The compiled fields (:func:`~nilpotent.numeric.compile.compile_fields`).
    x0:
        ``(B, n)`` initial states (or ``(n,)`` for one).
    inputs:
        A batch of ``B`` input signals, or of 1 shared by all states.
    method:
        ``"adaptive"`` or ``"fixed"`` (:data:`METHODS`).
    engine:
        One of :data:`ENGINES` (see the module docstring).
    times:
        Sample times in ``[0, duration]`` (shared by the batch; sorted).
    rtol, atol:
        Tolerances of the adaptive method.
    steps:
        Steps per segment of the fixed method (even, ≥ 2).
    max_steps:
        Most steps (accepted + rejected) per trajectory.
    min_step:
        Smallest step of the adaptive method (default ``1e-13 ×`` duration);
        numba only (scipy and heyoka have none).
    bound:
        A trajectory with some ``|x_k| > bound`` is stopped (:attr:`Status.BLOW_UP`).
    estimate_error:
        For ``fixed``: also integrate with ``steps/2`` to estimate the error.
    threads:
        Number of numba threads (default: numba's setting), or of threads
        running heyoka's SIMD batches (default 1).
    """
    if method not in METHODS:
        raise OptionError(f"unknown method {method!r} (choose from {', '.join(METHODS)})")
    if engine not in ENGINES:
        raise OptionError(f"unknown engine {engine!r} (choose from {', '.join(ENGINES)})")
    xs = np.ascontiguousarray(np.atleast_2d(np.asarray(x0, dtype=np.float64)))
    if xs.ndim != 2 or xs.shape[1] != system.n:
        raise OptionError(f"initial states must have shape (B, {system.n}), got {np.shape(x0)}")
    if inputs.m != system.m:
        raise OptionError(f"inputs have {inputs.m} components, the system has {system.m} fields")
    batch = xs.shape[0]
    sig = inputs.broadcast(batch)
    total = sig.total_durations
    ts = _check_times(times, total)
    if not (rtol > 0 and atol >= 0 and math.isfinite(rtol) and math.isfinite(atol)):
        raise OptionError(f"need rtol > 0 and atol >= 0, got rtol={rtol}, atol={atol}")
    if method == "fixed" and (int(steps) != steps or steps < 2 or (estimate_error and steps % 2)):
        raise OptionError(f"steps must be an even integer >= 2, got {steps}")
    if max_steps < 1 or not bound > 0:
        raise OptionError("max_steps must be >= 1 and bound > 0")
    if min_step is None:
        min_step = 1e-13 * float(np.max(total))
    chosen = _choose_engine(system, method, engine, batch)
    common = dict(
        rtol=float(rtol), atol=float(atol), max_steps=int(max_steps),
        min_step=float(min_step), bound=float(bound),
    )
    with _numba_threads(threads if chosen == "numba" else None):
        final, samples, info, err, tolerance = _solve(
            system, xs, sig, ts, method, chosen, int(steps), estimate_error, common, threads
        )
    return BatchSolution(
        method=method,
        engine=chosen,
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


@contextlib.contextmanager
def _numba_threads(threads: int | None) -> Iterator[None]:
    """Run with ``threads`` numba threads, restoring the previous setting afterwards."""
    if threads is None:
        yield
        return
    import numba

    previous = numba.get_num_threads()
    numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))
    try:
        yield
    finally:
        numba.set_num_threads(previous)


def _solve(
    system: CompiledSystem,
    xs: np.ndarray,
    sig: Signal,
    ts: np.ndarray,
    method: str,
    chosen: str,
    steps: int,
    estimate_error: bool,
    common: dict[str, Any],
    threads: int | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    batch = xs.shape[0]
    if chosen == "scipy":
        final, samples, info = _run_scipy(system, xs, sig, ts, **common)
    elif chosen == "heyoka":
        from nilpotent.numeric.heyoka_engine import run_heyoka

        final, samples, info = run_heyoka(
            system, xs, sig, ts, rtol=common["rtol"], atol=common["atol"],
            max_steps=common["max_steps"], bound=common["bound"], threads=threads,
        )
    elif chosen == "numba":
        final, samples, info = _run_numba(system, xs, sig, ts, method == "adaptive", steps,
                                          **common)
    else:
        with np.errstate(over="ignore", invalid="ignore"):  # stopped trajectories
            final, samples, info = _run_numpy(system, xs, sig, ts, steps, **common)
    status = info[:, 0].astype(np.int64)
    if chosen == "numba" and method == "adaptive":
        err = info[:, 3].copy()
    else:
        err = np.full(batch, np.nan)
    if method == "fixed":
        if estimate_error:
            half = steps // 2
            if chosen == "numba":
                f2, s2, _ = _run_numba(system, xs, sig, ts, False, half, **common)
            else:
                with np.errstate(over="ignore", invalid="ignore"):
                    f2, s2, _ = _run_numpy(system, xs, sig, ts, half, **common)
            diff = np.abs(final - f2).max(axis=1)
            if ts.size:
                diff = np.maximum(diff, np.nan_to_num(np.abs(samples - s2), nan=np.inf).max(
                    axis=(1, 2)))
            err = diff / (2.0**DOP853.order - 1.0)
            good = err[status == 0]
            tolerance = float(good.max()) if good.size else float("nan")
        else:
            tolerance = float("nan")
    else:
        tolerance = float(common["rtol"])
    return final, samples, info, err, tolerance


def _check_times(times: Any, total: np.ndarray) -> np.ndarray:
    if times is None:
        return np.zeros(0)
    ts = np.ascontiguousarray(np.asarray(times, dtype=np.float64).ravel())
    if ts.size and (not np.all(np.isfinite(ts)) or np.any(np.diff(ts) < 0)):
        raise OptionError("sample times must be finite and sorted")
    if ts.size and (ts[0] < 0 or ts[-1] > float(np.min(total)) * (1 + 1e-12)):
        raise OptionError(
            f"sample times must lie in [0, {float(np.min(total))}] (the input's duration)"
        )
    return ts


def kernels_cached(system: CompiledSystem) -> bool:
    """Whether the numba integrator of ``system`` is in numba's on-disk cache."""
    from nilpotent.numeric.cache import cache_dir
    from nilpotent.numeric.kernels import KERNEL_VERSION

    folder = cache_dir() / "__pycache__"
    stem = f"nb_{system.key}_{KERNEL_VERSION}"
    return any(folder.glob(f"{stem}.integrate_batch-*.nbi"))


def _choose_engine(system: CompiledSystem, method: str, engine: str, batch: int) -> str:
    if engine == "auto":
        if method == "adaptive" and batch >= AUTO_NUMBA_BATCH:
            from nilpotent.numeric.heyoka_engine import heyoka_available

            if heyoka_available():
                return "heyoka"
        if numba_available() and (batch >= AUTO_NUMBA_BATCH or kernels_cached(system)):
            return "numba"
        return "scipy" if method == "adaptive" else "numpy"
    if engine not in _SUPPORTED[method]:
        raise OptionError(
            f"method {method!r} runs on the engines {', '.join(_SUPPORTED[method])}, "
            f"not {engine!r}"
        )
    return engine


# --- numba ------------------------------------------------------------------------
def _run_numba(
    system: CompiledSystem,
    xs: np.ndarray,
    sig: Signal,
    ts: np.ndarray,
    adaptive: bool,
    steps: int,
    *,
    rtol: float,
    atol: float,
    max_steps: int,
    min_step: float,
    bound: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    mod = system.kernels
    batch = xs.shape[0]
    final = np.empty_like(xs)
    samples = np.full((batch, ts.size, system.n), np.nan)
    info = np.zeros((batch, 4))
    mod.integrate_batch(
        xs, sig.durations, sig.omegas, sig.constant, sig.cos, sig.sin, ts,
        adaptive, steps, rtol, atol, max_steps, min_step, bound, final, samples, info,
    )
    return final, samples, info


# --- numpy (fixed step, vectorised over the batch) ----------------------------------
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
    alive = _state_status(x, bound) == 0
    status = np.where(alive, 0, _state_status(x, bound))
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
                    st_now = _state_status(x, bound)
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


def _state_status(x: np.ndarray, bound: float) -> np.ndarray:
    finite = np.all(np.isfinite(x), axis=1)
    big = np.any(np.abs(np.where(np.isfinite(x), x, 0.0)) > bound, axis=1)
    return np.where(~finite, int(Status.NON_FINITE), np.where(big, int(Status.BLOW_UP), 0))


# --- scipy reference ------------------------------------------------------------------
class _TooManySteps(Exception):
    pass


def solve_function_input(
    system: CompiledSystem,
    x0: Any,
    u: Callable[[float], Any],
    breakpoints: Sequence[float],
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
    ts = _check_times(times, np.array([bps[-1]]))
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
    status = Status(int(_state_status(x[None], bound)[0]))
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
            status = Status(int(_state_status(x[None], bound)[0]))
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
