"""The ``heyoka`` engine: Taylor-method integration of batches (optional extra).

`heyoka <https://bluescarni.github.io/heyoka.py/>`_ integrates
``dx/dt = Σ_i u_i(t) X_i(x)`` with an adaptive Taylor method whose code it
compiles with LLVM, several trajectories at once in SIMD lanes
(``taylor_adaptive_batch``, batch size :func:`heyoka.recommended_simd_size`).

The right-hand side is built once per system, number of harmonics ``K`` and
tolerance from the compiled fields (:attr:`CompiledSystem.fields`, via
:func:`heyoka.from_sympy`) with the inputs of :class:`Signal` as runtime
parameters:

.. math::

    u_i(τ) = a_i + \\sum_{k=1}^{K} b_{i,k} \\cos(k ω τ) + c_{i,k} \\sin(k ω τ),

parameters ``par[0] = ω``, then ``a_i, b_{i,1}, c_{i,1}, …, b_{i,K}, c_{i,K}``
for ``i = 1..m``.  The integrator's time is the local time ``τ`` of the
segment: at the end of each segment the lane's time is reset to 0 and the
parameters of the next segment are loaded, so one compiled integrator serves
every batch of inputs with ``K`` harmonics, any number of segments, and
per-trajectory durations.

Accuracy: heyoka keeps the local error of each step below
``tol · max(1, ‖x‖∞)``; the engine uses ``tol = min(rtol, atol)`` (``rtol``
when ``atol = 0``), which bounds the local error by both ``atol`` (states below
1) and ``rtol·‖x‖∞`` (larger states).  Taylor steps are never rejected.

Failures: a trajectory is stopped when its state becomes non-finite
(:attr:`Status.NON_FINITE`), when it ends a propagation with some
``|x_k| > bound`` (:attr:`Status.BLOW_UP`; the reported state is the first one
found beyond the bound, not the crossing point), or after ``max_steps`` steps
(:attr:`Status.MAX_STEPS`).  The other lanes of its SIMD batch go on.  There is
no minimum step size: near a finite-time blow-up Taylor steps shrink until the
state overflows, which takes a few hundred steps.

Compilation (~0.4 s for the trident snake) happens on the first use of a
system, ``K`` and tolerance; heyoka keeps the compiled code in its own on-disk
cache (``$XDG_CACHE_HOME/heyoka``, default ``~/.cache/heyoka``), from which a
new process loads it in ~0.02 s.  Integrators are kept per system (in the
system's memo) for the rest of the process.
"""

from __future__ import annotations

import copy
import importlib.util
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from types import ModuleType
from typing import Any, ClassVar

import numpy as np
import sympy as sp

from nilpotent.errors import MissingExtraError
from nilpotent.numeric.compile import CompiledSystem
from nilpotent.numeric.engines import Engine, EngineOutput
from nilpotent.numeric.signals import Signal

#: How to install the optional dependency.
INSTALL_HINT = 'pip install "heyoka>=7.13" (part of the default install of nilpotent)'

# Status codes (the values of nilpotent.numeric.integrate.Status).
_SUCCESS, _MAX_STEPS, _BLOW_UP, _NON_FINITE = 0, 1, 3, 4


class HeyokaEngine(Engine):
    """heyoka's adaptive Taylor method in SIMD batches (:func:`run_heyoka`)."""

    name: ClassVar[str] = "heyoka"
    methods: ClassVar[tuple[str, ...]] = ("adaptive",)
    summary: ClassVar[str] = "heyoka's Taylor method in SIMD batches (fastest measured)"
    install: ClassVar[str] = f"heyoka: {INSTALL_HINT}"

    def available(self) -> bool:
        return heyoka_available()

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
        del adaptive, steps, min_step  # heyoka has no minimum step
        return run_heyoka(system, xs, signal, times, rtol=rtol, atol=atol,
                          max_steps=max_steps, bound=bound, threads=threads)


def heyoka_available() -> bool:
    """Whether heyoka can be imported."""
    return importlib.util.find_spec("heyoka") is not None


def _heyoka() -> ModuleType:
    if not heyoka_available():
        raise MissingExtraError(f"the heyoka engine needs heyoka: {INSTALL_HINT}")
    import heyoka

    return heyoka


def heyoka_tolerance(rtol: float, atol: float) -> float:
    """heyoka's tolerance for ``rtol``, ``atol``: ``min(rtol, atol)`` (``rtol`` if ``atol = 0``)."""
    return float(min(rtol, atol)) if atol > 0 else float(rtol)


@dataclass(frozen=True, eq=False)
class TaylorIntegrator:
    """A compiled heyoka batch integrator of one system (see the module docstring).

    Attributes
    ----------
    template:
        The ``taylor_adaptive_batch`` object (copied for each thread).
    harmonics:
        ``K``, the number of harmonics of the inputs it accepts.
    tol:
        heyoka's tolerance.
    batch_size:
        SIMD lanes per step.
    order:
        Order of the Taylor method heyoka chose for ``tol``.
    """

    template: Any
    harmonics: int
    tol: float
    batch_size: int
    order: int


def _rhs(system: CompiledSystem, harmonics: int) -> tuple[list[tuple[Any, Any]], int]:
    """heyoka's ``[(x_j, dx_j/dt)]`` for ``Σ u_i(t) X_i(x)`` and the number of parameters."""
    hy = _heyoka()
    n, m = system.n, system.m
    names = [f"q{k}" for k in range(n)]
    hv = hy.make_vars(*names)
    hv = list(hv) if n > 1 else [hv]
    qs = sp.symbols(f"q0:{n}", real=True)
    smap = {qs[k]: hv[k] for k in range(n)}
    tau = hy.time
    cosk = [hy.cos(k * hy.par[0] * tau) for k in range(1, harmonics + 1)]
    sink = [hy.sin(k * hy.par[0] * tau) for k in range(1, harmonics + 1)]
    inputs = []
    idx = 1
    for _ in range(m):
        terms = [hy.par[idx]]
        idx += 1
        for k in range(harmonics):
            terms += [hy.par[idx] * cosk[k], hy.par[idx + 1] * sink[k]]
            idx += 2
        inputs.append(hy.sum(terms))
    rhs = []
    for j in range(n):
        terms = []
        for i in range(m):
            f = system.fields[i][j]
            if f == 0:
                continue
            terms.append(inputs[i] if f == 1 else inputs[i] * hy.from_sympy(f, smap))
        rhs.append(hy.sum(terms) if terms else hy.expression(0.0))
    return list(zip(hv, rhs, strict=True)), idx


def taylor_integrator(system: CompiledSystem, harmonics: int, tol: float) -> TaylorIntegrator:
    """The heyoka integrator of ``system`` for inputs with ``harmonics`` harmonics at ``tol``.

    Compiled on the first call (LLVM, in memory), then kept in the system's memo.
    """
    key = ("heyoka", int(harmonics), float(tol))
    memo = system._memo  # the CompiledSystem's per-process cache
    if key not in memo:
        hy = _heyoka()
        sysd, npar = _rhs(system, int(harmonics))
        bs = int(hy.recommended_simd_size())
        ta = hy.taylor_adaptive_batch(
            sysd, np.zeros((system.n, bs)), tol=float(tol), pars=np.zeros((npar, bs))
        )
        memo[key] = TaylorIntegrator(ta, int(harmonics), float(tol), bs, int(ta.order))
    return memo[key]


def _parameters(sig: Signal) -> np.ndarray:
    """``(B, S, npar)`` runtime parameters of every segment (layout of the module docstring)."""
    b, s, m, k = sig.cos.shape
    per_input = np.empty((b, s, m, 1 + 2 * k))
    per_input[..., 0] = sig.constant
    per_input[..., 1::2] = sig.cos
    per_input[..., 2::2] = sig.sin
    return np.concatenate(
        [sig.omegas[..., None], per_input.reshape(b, s, m * (1 + 2 * k))],
        axis=2,
    )


def run_heyoka(
    system: CompiledSystem,
    xs: np.ndarray,
    sig: Signal,
    ts: np.ndarray,
    *,
    rtol: float,
    atol: float,
    max_steps: int,
    bound: float,
    threads: int | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Integrate a batch with heyoka; returns ``(final, samples, info)``.

    ``final`` ``(B, n)``; ``samples`` ``(B, T, n)`` at the global times ``ts``
    (NaN past a stop); ``info`` ``(B, 4)``: status code, steps, rejected steps
    (0), error estimate (NaN).  ``threads`` SIMD batches run at once, each
    thread on its own copy of the integrator (default 1: heyoka releases the
    GIL while it integrates, but the Python work between batches does not, and
    two threads measured no faster than one).
    """
    integ = taylor_integrator(system, sig.harmonics, heyoka_tolerance(rtol, atol))
    batch, n = xs.shape
    bs = integ.batch_size
    pars = _parameters(sig)
    ends = np.cumsum(sig.durations, axis=1)
    segs = sig.segment_count
    # per trajectory: the S segment ends and the T sample times, in time order
    evt_time = np.concatenate([ends, np.broadcast_to(ts, (batch, ts.size))], axis=1)
    evt_kind = np.broadcast_to(np.arange(segs + ts.size), evt_time.shape)
    order = np.argsort(evt_time, axis=1, kind="stable")
    evt_time = np.take_along_axis(evt_time, order, 1)
    evt_kind = np.take_along_axis(evt_kind, order, 1)
    final = np.full((batch, n), np.nan)
    samples = np.full((batch, ts.size, n), np.nan)
    info = np.zeros((batch, 4))
    info[:, 3] = np.nan
    chunks = [(c, min(c + bs, batch)) for c in range(0, batch, bs)]
    # default one thread: the per-batch Python work holds the GIL, and two threads
    # measured no faster than one on the trident snake (~190k trajectories/s)
    workers = max(1, min(int(threads or 1), len(chunks)))
    groups = [chunks[w::workers] for w in range(workers)]

    hy = _heyoka()
    outcomes = (hy.taylor_outcome.time_limit, hy.taylor_outcome.step_limit)

    def work(group: list[tuple[int, int]]) -> None:
        ta = copy.deepcopy(integ.template)
        for lo, hi in group:
            _run_chunk(ta, lo, hi, xs, pars, evt_time, evt_kind, segs, final, samples, info,
                       max_steps, bound, outcomes)

    if workers == 1:
        work(groups[0])
    else:
        with ThreadPoolExecutor(workers) as pool:
            list(pool.map(work, groups))
    return final, samples, info


def _run_chunk(
    ta: Any,
    lo: int,
    hi: int,
    xs: np.ndarray,
    pars: np.ndarray,
    evt_time: np.ndarray,
    evt_kind: np.ndarray,
    segs: int,
    final: np.ndarray,
    samples: np.ndarray,
    info: np.ndarray,
    max_steps: int,
    bound: float,
    outcomes_of_interest: tuple[Any, Any],
) -> None:
    """Integrate trajectories ``lo:hi`` (≤ one SIMD batch) through all their events.

    ``outcomes_of_interest``: heyoka's ``(time_limit, step_limit)`` outcomes.
    """
    time_limit, step_limit = outcomes_of_interest
    bs = ta.batch_size
    width = hi - lo
    rows = np.arange(lo, hi)
    # lanes → trajectories; spare lanes (last chunk) repeat the chunk's trajectories
    pad = slice(lo, hi) if width == bs else lo + np.arange(bs) % width
    state = ta.state
    par = ta.pars
    state[:] = xs[pad].T
    par[:] = pars[pad, 0].T
    ta.set_time(np.zeros(bs))
    alive = np.ones(bs, dtype=bool)
    alive[width:] = False
    par[:, width:] = 0.0  # spare lanes: zero inputs, nothing moves
    status = np.zeros(bs, dtype=np.int64)
    steps = np.zeros(bs, dtype=np.int64)
    all_lanes = np.arange(width)
    final_only = evt_time.shape[1] == 1
    offset = np.zeros(bs)  # global start time of each lane's current segment
    for e in range(evt_time.shape[1]):
        target = evt_time[pad, e]
        if segs > 1:
            target = target - offset  # local time in the current segment
        everyone = width == bs and bool(alive.all())
        if not everyone:
            target = np.where(alive, target, ta.time)
        while True:
            # most steps any live lane has taken so far
            fresh = (e == 0 and everyone) or not alive.any()
            used = 0 if fresh else int(steps[alive].max())
            ta.propagate_until(target, max_steps=max(max_steps - used, 1))
            outcomes, _, _, taken = zip(*ta.propagate_res, strict=True)
            steps += taken if everyone else np.array(taken) * alive
            if (
                outcomes.count(time_limit) == bs
                and used + max(taken) < max_steps
                and np.abs(state).max() <= bound  # False for NaN
            ):
                break  # the common case: every lane reached its target
            x = state.T
            finite = np.all(np.isfinite(x), axis=1)
            big = np.any(np.abs(np.where(np.isfinite(x), x, 0.0)) > bound, axis=1)
            reached = np.array([o == time_limit for o in outcomes])
            over = np.array([o == step_limit for o in outcomes]) | (steps >= max_steps)
            dead = alive & (~finite | big | (over & ~reached))
            if dead.any():
                status[dead] = np.where(~finite[dead], _NON_FINITE,
                                        np.where(big[dead], _BLOW_UP, _MAX_STEPS))
                idx = np.flatnonzero(dead[:width])
                final[lo + idx] = x[idx]
                alive &= ~dead
                # park the stopped lanes: zero state and inputs, target = their time
                state[:, dead] = 0.0
                par[:, dead] = 0.0
                if not np.isfinite(ta.time).all():  # a lane that blew up: restart its clock
                    ta.set_time(np.where(np.isfinite(ta.time), ta.time, 0.0))
                target = np.where(alive, target, ta.time)
                everyone = False
            if np.all(reached | ~alive):
                break
            # a lane stopped the whole SIMD batch: the others go on from where they are
        if final_only and everyone:  # one segment, no samples: the common case
            final[lo:hi] = state[:, :width].T
            continue
        live = all_lanes if alive.all() else np.flatnonzero(alive[:width])
        kind = evt_kind[lo + live, e]
        switch = kind < segs - 1
        if switch.any():  # the next segment's inputs
            lanes = live[switch]
            par[:, lanes] = pars[lo + lanes, kind[switch] + 1].T
            offset[lanes] = evt_time[lo + lanes, e]
            restart = np.zeros(bs, dtype=bool)
            restart[lanes] = True
            ta.set_time(np.where(restart, 0.0, ta.time))
        end = kind == segs - 1
        if end.any():
            final[lo + live[end]] = state[:, live[end]].T
        smp = kind >= segs
        if smp.any():
            samples[lo + live[smp], kind[smp] - segs] = state[:, live[smp]].T
    info[rows, 0] = status[:width]
    info[rows, 1] = steps[:width]
