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
(:attr:`Status.NON_FINITE`), when it reaches one of its events (a segment end,
a sample time) with some ``|x_k| > bound`` (:attr:`Status.BLOW_UP`; the
reported state is the one at that event, not the crossing point), or after
``max_steps`` of its own steps (:attr:`Status.MAX_STEPS`).  The other lanes of
its SIMD batch go on, and none of this depends on them.  There is
no minimum step size: near a finite-time blow-up Taylor steps shrink until the
state overflows, which takes a few hundred steps.

Specialisation: runtime parameters that are 0 in every control of a batch
(e.g. the constant terms and the unused input of a bracket motion) are left
out of the compiled right-hand side, and so is a field whose input is 0
throughout; adding or multiplying an exact 0 changes no value, so the results
are those of the full integrator (up to rounding), at a fraction of the cost.
A coordinate whose velocity is then identically 0 (every field in use has a 0
in that row: e.g. the heading θ of the trident snake when ``u_3 = 0``) is
constant along the trajectory: it is not integrated but read as a runtime
parameter (its start value), which removes its Taylor recurrences and those of
the functions of it (``cos θ``, ``sin θ``).  Its reported values are its start
value, exactly.  The integrated coordinates keep heyoka's error bound
``tol · max(1, ‖x‖∞)`` with the norm over the integrated coordinates only (the
same or tighter: with a held coordinate far above 1, e.g. a car at ``x = 10⁶``
steering on the spot, the others are integrated more accurately, in more steps,
so such a trajectory may reach ``max_steps`` where the full integrator did not).
A start value that is not finite or beyond ``bound`` is not
frozen, so such a trajectory fails as it would in the full integrator.

Threads: SIMD batches are spread over ``threads`` threads (default
:func:`default_workers`: one more than the cores the process may use), each
with its own copy of the integrator; heyoka releases the GIL while it
propagates, and the Python work per batch is a handful of array copies
(:func:`run_heyoka`).  Results do not depend on the thread count.

Compilation (~0.4 s for the trident snake) happens on the first use of a
system, ``K``, tolerance and set of parameters in use.  heyoka keeps compiled
object code in an on-disk cache (an SQLite file) from which a new process loads
it in ~0.02 s, and runs what it finds there: so its cache is never heyoka's
default folder (``~/.cache/heyoka``, which another user may have prepared) but
``<code cache>/heyoka`` under the policy of
:func:`nilpotent.numeric.cache.library_cache` (0700, the user's own, every
entry the user's own and not writable by others), checked before every
compilation; when that folder is not safe heyoka's disk cache is switched off
(a warning says why) and integrators are compiled in every process.
Integrators are kept per system key (the fields, not the name: a renamed model
shares them) for the rest of the process; :data:`COMPILATIONS` counts the
integrators built.

heyoka logs through spdlog on stdout: its level is set to ``critical`` and the
construction of an integrator (where its cache is read and written) runs with
file descriptor 1 pointed at stderr, so nothing of heyoka's reaches stdout (one
JSON object under ``--json``).  Both, and the disk-cache policy, live in
:mod:`nilpotent.numeric.engines.heyoka_setup`.
"""

from __future__ import annotations

import copy
import importlib.util
import itertools
import os
from collections import Counter
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any, ClassVar

import numpy as np
import sympy as sp

from nilpotent.errors import MissingExtraError, OptionError
from nilpotent.numeric.compile import CompiledSystem
from nilpotent.numeric.engines.base import Engine, EngineOutput, compiled_memo
from nilpotent.numeric.engines.heyoka_events import run_chunk
from nilpotent.numeric.engines.heyoka_setup import (
    quiet_logger,
    stdout_to_stderr,
    use_safe_disk_cache,
)
from nilpotent.numeric.signals import Signal

#: How to install the optional dependency.
INSTALL_HINT = 'pip install "heyoka>=7.13" (part of the default install of nilpotent)'


class HeyokaEngine(Engine):
    """heyoka's adaptive Taylor method in SIMD batches (:func:`run_heyoka`)."""

    name: ClassVar[str] = "heyoka"
    methods: ClassVar[tuple[str, ...]] = ("adaptive",)
    summary: ClassVar[str] = "heyoka's Taylor method in SIMD batches (fastest measured)"
    install: ClassVar[str] = f"heyoka: {INSTALL_HINT}"

    def available(self) -> bool:
        return heyoka_available()

    def handles(self, system: Any) -> bool:
        """Whether heyoka can express every field of ``system`` (:func:`heyoka_handles`)."""
        return heyoka_handles(system)

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


#: Integrators built (compiled or loaded from heyoka's disk cache) in this process.
COMPILATIONS: Counter[str] = Counter()


def _heyoka() -> ModuleType:
    if not heyoka_available():
        raise MissingExtraError(f"the heyoka engine needs heyoka: {INSTALL_HINT}")
    import heyoka

    quiet_logger(heyoka)
    return heyoka

def _convert(hy: ModuleType, system: CompiledSystem, f: sp.Expr, smap: dict) -> Any:
    """``f`` as a heyoka expression; :class:`OptionError` for what heyoka cannot express."""
    try:
        return hy.from_sympy(f, smap)
    except (TypeError, ValueError) as exc:
        raise OptionError(
            f"the heyoka engine cannot integrate {system.name}: {exc} (use engine "
            "'scipy' or 'numba')"
        ) from None


def heyoka_handles(system: CompiledSystem) -> bool:
    """Whether heyoka can express every field of ``system`` (``from_sympy``: not ``Abs``).

    Kept in the system's memo.
    """
    memo = compiled_memo(system)
    if "heyoka-handles" not in memo:
        hy = _heyoka()
        names = [f"q{k}" for k in range(system.n)]
        hv = hy.make_vars(*names)
        hv = list(hv) if system.n > 1 else [hv]
        smap = dict(zip(sp.symbols(f"q0:{system.n}", real=True), hv, strict=True))
        try:
            for row in system.fields:
                for f in row:
                    if f not in (0, 1):
                        _convert(hy, system, f, smap)
            memo["heyoka-handles"] = True
        except OptionError:
            memo["heyoka-handles"] = False
    return bool(memo["heyoka-handles"])


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
    parameters:
        How many runtime parameters it has (heyoka counts up to the largest
        index its expressions use).
    slots:
        The signal parameters (indices into :func:`_parameters`' layout) it
        reads as its ``par[0], par[1], …`` (:func:`_slots`); the start values
        of the frozen coordinates follow.
    frozen:
        The coordinates held constant (read as parameters, not integrated;
        :func:`_constant_coordinates`); its state holds the others, in order.
    spares:
        Copies of ``template`` not in use, reused by the threads of later calls.
    """

    template: Any
    harmonics: int
    tol: float
    batch_size: int
    order: int
    parameters: int
    slots: tuple[int, ...] = ()
    frozen: tuple[int, ...] = ()
    spares: list[Any] = field(default_factory=list)


def _signal_parameters(m: int, harmonics: int) -> int:
    """How many runtime parameters the signal has (layout of the module docstring)."""
    return 1 + m * (1 + 2 * harmonics)


def _constant_coordinates(
    system: CompiledSystem, harmonics: int, used: tuple[bool, ...]
) -> tuple[int, ...]:
    """The coordinates whose velocity is identically 0 when only ``used`` parameters are nonzero.

    Coordinate ``j`` qualifies when every field ``X_i`` whose input ``u_i`` has
    a used parameter has ``X_i^j = 0`` (exactly, symbolically).  Empty when
    every coordinate would qualify (nothing would be left to integrate).
    """
    width = 1 + 2 * harmonics
    active = [i for i in range(system.m)
              if any(used[1 + i * width: 1 + (i + 1) * width])]
    still = tuple(j for j in range(system.n)
                  if all(system.fields[i][j] == 0 for i in active))
    return () if len(still) == system.n else still


def _rhs(
    system: CompiledSystem,
    harmonics: int,
    used: tuple[bool, ...] | None = None,
    frozen: tuple[int, ...] = (),
) -> tuple[list[tuple[Any, Any]], int]:
    """heyoka's ``[(x_j, dx_j/dt)]`` for ``Σ u_i(t) X_i(x)`` and the number of parameters.

    ``used[p]`` False: parameter ``p`` is 0 in every control of the batch, and
    its term is left out (adding or multiplying an exact 0 changes no value; a
    field whose input is 0 throughout is left out entirely).  ``None``: all used.
    ``frozen``: coordinates held constant (:func:`_constant_coordinates`): not
    state variables.  The integrator's parameters are the used signal
    parameters in layout order (:func:`_slots`), then coordinate ``frozen[r]``
    as ``par[U + r]`` with ``U`` the number of used signal parameters.
    """
    hy = _heyoka()
    n, m = system.n, system.m
    npar = _signal_parameters(m, harmonics)
    moving = [k for k in range(n) if k not in frozen]
    hv = hy.make_vars(*[f"q{k}" for k in moving])
    hv = list(hv) if len(moving) > 1 else [hv]
    qs = sp.symbols(f"q0:{n}", real=True)
    use = (True,) * npar if used is None else used
    slots = _slots(use)
    par = {p: hy.par[i] for i, p in enumerate(slots)}  # signal parameter p → its slot
    smap = {qs[k]: v for k, v in zip(moving, hv, strict=True)}
    smap.update({qs[k]: hy.par[len(slots) + r] for r, k in enumerate(frozen)})
    tau = hy.time
    cosk = [hy.cos(k * par[0] * tau) for k in range(1, harmonics + 1)]
    sink = [hy.sin(k * par[0] * tau) for k in range(1, harmonics + 1)]
    inputs: list[Any] = []
    idx = 1
    for _ in range(m):
        terms = [par[idx]] if use[idx] else []
        idx += 1
        for k in range(harmonics):
            if use[idx]:
                terms.append(par[idx] * cosk[k])
            if use[idx + 1]:
                terms.append(par[idx + 1] * sink[k])
            idx += 2
        inputs.append(hy.sum(terms) if terms else None)
    rhs = []
    for j in moving:
        terms = []
        for i in range(m):
            f = system.fields[i][j]
            if f == 0 or inputs[i] is None:
                continue
            terms.append(inputs[i] if f == 1 else inputs[i] * _convert(hy, system, f, smap))
        rhs.append(hy.sum(terms) if terms else hy.expression(0.0))
    return list(zip(hv, rhs, strict=True)), len(slots) + len(frozen)


def _slots(used: tuple[bool, ...]) -> tuple[int, ...]:
    """The signal parameters an integrator reads, in the order of its ``par[0], par[1], …``.

    ``used`` over the layout of :func:`_parameters`; ``ω`` (index 0) always.
    """
    return tuple(p for p, u in enumerate(used) if u or p == 0)


def taylor_integrator(
    system: CompiledSystem,
    harmonics: int,
    tol: float,
    used: tuple[bool, ...] | None = None,
    frozen: tuple[int, ...] = (),
) -> TaylorIntegrator:
    """The heyoka integrator of ``system`` for inputs with ``harmonics`` harmonics at ``tol``.

    ``used``: which runtime parameters may be nonzero (:func:`_rhs`; ``None``:
    all); ``frozen``: coordinates held constant (read as parameters).
    Compiled on the first call (LLVM, in memory; heyoka's on-disk cache in the
    checked folder of
    :func:`~nilpotent.numeric.engines.heyoka_setup.use_safe_disk_cache` across
    processes), then kept
    in the system's memo (shared by every system with the same key).
    """
    key = ("heyoka", int(harmonics), float(tol), used, tuple(frozen))
    memo = compiled_memo(system)  # the engines' per-process cache of the system
    if key not in memo:
        hy = _heyoka()
        sysd, _ = _rhs(system, int(harmonics), used, tuple(frozen))
        bs = int(hy.recommended_simd_size())
        from nilpotent.progress import COMPILING, progress

        with stdout_to_stderr(), progress(COMPILING):
            use_safe_disk_cache(hy)
            # heyoka sizes the parameters by the largest index the expressions use
            ta = hy.taylor_adaptive_batch(sysd, np.zeros((len(sysd), bs)), tol=float(tol))
        COMPILATIONS[system.key] += 1
        slots = _slots((True,) * _signal_parameters(system.m, int(harmonics))
                       if used is None else used)
        memo[key] = TaylorIntegrator(ta, int(harmonics), float(tol), bs, int(ta.order),
                                     int(ta.pars.shape[0]), slots, tuple(frozen))
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


def default_threads() -> int:
    """The cores this process may run on (``os.sched_getaffinity``; else ``os.cpu_count()``)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def default_workers() -> int:
    """The heyoka engine's default thread count: one more than :func:`default_threads`.

    Each SIMD batch costs ~20 µs in heyoka (GIL released) and a few µs of
    Python (GIL held).  With one thread per core, a thread back from heyoka
    that waits for the GIL leaves its core idle; an extra thread fills those
    gaps.  Measured on 2 cores (``benchmarks/simulate.py``, 10,000 trident
    snake bracket motions): 2 threads 1.61–1.80× the one-thread heyoka baseline,
    3 threads 1.73–1.93× in the same runs.  One core: one thread.
    """
    cores = default_threads()
    return cores + 1 if cores > 1 else 1


def _borrow(integ: TaylorIntegrator) -> Any:
    """A private copy of ``integ``'s integrator (reused across calls; see :func:`_give_back`)."""
    try:
        return integ.spares.pop()
    except IndexError:
        return copy.deepcopy(integ.template)  # ~2 ms: compiled code is shared, not rebuilt


def _give_back(integ: TaylorIntegrator, ta: Any) -> None:
    integ.spares.append(ta)


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
    (0), error estimate (NaN).

    Threads: ``threads`` (default :func:`default_workers`, one more than the
    cores this process may use) threads each own a copy of the integrator and take SIMD
    batches from a shared counter; heyoka releases the GIL while it
    propagates.  Every batch starts from a fully reset integrator (state,
    parameters, time), so the results do not depend on the number of threads
    or on which thread ran a batch.

    Each trajectory runs on the integrator specialised to the parameters its
    own control uses (:func:`_rhs`): trajectories are grouped by that set, so
    a trajectory's result does not depend on the others in the batch.

    The common case (one segment, sample times only at 0 and at the end, full
    SIMD batches) runs a lean loop: load the batch, propagate, store the end
    state, the steps and the lanes' end times; afterwards one vectorised check finds batches in
    which a lane failed (stopped early, too many steps, non-finite, beyond
    ``bound``) and integrates those again on the general path
    (:func:`~nilpotent.numeric.engines.heyoka_events.run_chunk`), which stops and
    reports the failing lanes.
    """
    pars = _parameters(sig)
    ends = np.cumsum(sig.durations, axis=1)
    tol = heyoka_tolerance(rtol, atol)
    batch = xs.shape[0]
    row_used = np.any(pars[..., 1:] != 0, axis=1)  # (B, npar - 1)
    if batch == 0 or bool(np.all(row_used == row_used[0])):
        kinds, which = row_used[:1], np.zeros(batch, dtype=np.int64)
    else:  # np.unique on rows sorts them: ~2 µs a row, only when the rows differ
        kinds, which = np.unique(row_used, axis=0, return_inverse=True)
        which = np.ravel(which)
    # (integrator, rows or None for all): rows grouped by the parameters they use and by
    # whether their constant coordinates can be frozen (finite, within the bound)
    groups: list[tuple[TaylorIntegrator, np.ndarray | None]] = []
    for g, kind in enumerate(kinds):
        used = (True, *(bool(u) for u in kind))
        rows = np.flatnonzero(which == g) if kinds.shape[0] > 1 else None
        still = _constant_coordinates(system, sig.harmonics, used)
        frozen_ok = np.ones(batch if rows is None else rows.size, dtype=bool)
        if still:
            start = xs[:, still] if rows is None else xs[np.ix_(rows, np.asarray(still))]
            frozen_ok = np.all(np.abs(start) <= bound, axis=1)  # False for NaN
        for frozen, mask in ((still, frozen_ok), ((), ~frozen_ok)):
            if not mask.any():
                continue
            if mask.all():
                sub = rows
            elif rows is None:
                sub = np.flatnonzero(mask)
            else:
                sub = rows[mask]
            groups.append((taylor_integrator(system, sig.harmonics, tol, used, frozen), sub))
    if len(groups) == 1:
        return _run_specialised(groups[0][0], xs, pars, ends, ts, max_steps, bound, threads)
    final = np.empty(xs.shape)
    samples = np.empty((batch, ts.size, xs.shape[1]))
    info = np.empty((batch, 4))
    for integ, sub in groups:
        final[sub], samples[sub], info[sub] = _run_specialised(
            integ, xs[sub], pars[sub], ends[sub], ts, max_steps, bound, threads)
    return final, samples, info


def _run_specialised(
    integ: TaylorIntegrator,
    xs: np.ndarray,
    pars: np.ndarray,
    ends: np.ndarray,
    ts: np.ndarray,
    max_steps: int,
    bound: float,
    threads: int | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_run_group` on the integrated coordinates; the frozen ones are their start values.

    ``pars`` in the full layout of :func:`_parameters`; the integrator gets its
    slots (:func:`_slots`), then the frozen coordinates' start values
    (:func:`_rhs`).  A sample past a stop (NaN in
    the integrated coordinates) is NaN in the frozen ones too.
    """
    pars = pars[..., list(integ.slots)]
    if not integ.frozen:
        return _run_group(integ, xs, pars, ends, ts, max_steps, bound, threads)
    batch, n = xs.shape
    still = list(integ.frozen)
    moving = [k for k in range(n) if k not in integ.frozen]
    held = xs[:, still]
    extra = np.broadcast_to(held[:, None, :], (*pars.shape[:2], len(still)))
    final_m, samples_m, info = _run_group(
        integ, xs[:, moving], np.concatenate([pars, extra], axis=2), ends, ts, max_steps,
        bound, threads)
    final = np.empty((batch, n))
    final[:, moving] = final_m
    final[:, still] = held
    samples = np.empty((batch, ts.size, n))
    samples[..., moving] = samples_m
    stopped = np.isnan(samples_m).all(axis=2, keepdims=True)
    samples[..., still] = np.where(stopped, np.nan, held[:, None, :])
    return final, samples, info


def _run_group(
    integ: TaylorIntegrator,
    xs: np.ndarray,
    pars: np.ndarray,
    ends: np.ndarray,
    ts: np.ndarray,
    max_steps: int,
    bound: float,
    threads: int | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`run_heyoka` for trajectories that all run on ``integ``.

    ``pars`` ``(B, S, P)`` the integrator's parameters (:func:`_run_specialised`),
    ``ends`` ``(B, S)`` the segments' global end times.
    """
    pars = np.ascontiguousarray(pars[..., : integ.parameters])
    batch, n = xs.shape
    bs = integ.batch_size
    segs = ends.shape[1]
    final = np.full((batch, n), np.nan)
    samples = np.full((batch, ts.size, n), np.nan)
    info = np.zeros((batch, 4))
    info[:, 3] = np.nan
    full = batch // bs
    # the lean loop: one segment, a full SIMD batch, and sample times only at the start (0)
    # or at every trajectory's end (no stop on the way)
    at_start = ts == 0.0
    at_end = np.all(ends[:, -1:] == ts[None, :], axis=0) & ~at_start
    lean = segs == 1 and full > 0 and bool(np.all(at_start | at_end))
    # the SIMD batches from the first one that is not full (all of them off the lean path)
    chunks = [(c, min(c + bs, batch)) for c in range(full * bs if lean else 0, batch, bs)]
    hy = _heyoka()
    outcomes = (hy.taylor_outcome.time_limit, hy.taylor_outcome.step_limit)
    jobs: list[tuple[int, int]] = chunks
    # the lean loop's arrays, one contiguous (n, bs) block per full SIMD batch (empty when
    # it does not run); one common end time is passed as a number
    lean_rows = full * bs if lean else 0
    blocks = lean_rows // bs
    x_b = np.ascontiguousarray(xs[:lean_rows].reshape(blocks, bs, n).transpose(0, 2, 1))
    p_b = np.ascontiguousarray(
        pars[:lean_rows, 0].reshape(blocks, bs, pars.shape[2]).transpose(0, 2, 1))
    target = np.ascontiguousarray(ends[:lean_rows, 0]).reshape(blocks, bs)
    common = bool(lean_rows) and bool(np.all(target == target[0, 0]))
    end_time = float(target[0, 0]) if common else 0.0
    final_b = np.empty((blocks, n, bs))
    reached = np.empty((blocks, bs))
    steps = np.empty((blocks, bs), dtype=np.int64)

    def lean_work(ta: Any, counter: Iterator[int]) -> None:
        # a few µs of Python per SIMD batch against ~20 µs in heyoka: a scalar time (one
        # number for every lane) and positional arguments are measurably cheaper
        state, par = ta.state, ta.pars
        set_time, propagate = ta.set_time, ta.propagate_until
        for k in counter:
            if k >= full:
                return
            state[:] = x_b[k]
            par[:] = p_b[k]
            set_time(0.0)
            propagate(end_time if common else target[k], max_steps)
            steps[k] = [r[3] for r in ta.propagate_res]
            reached[k] = ta.time
            final_b[k] = state

    events: list[np.ndarray] = []  # filled by run_general, before its threads start

    def run_general() -> None:
        """The general path on ``jobs``; per trajectory, its S segment ends and T sample
        times in time order (sorted once, only when this path runs)."""
        if not events:
            evt_time = np.concatenate([ends, np.broadcast_to(ts, (batch, ts.size))], axis=1)
            evt_kind = np.broadcast_to(np.arange(segs + ts.size), evt_time.shape)
            order = np.argsort(evt_time, axis=1, kind="stable")
            events.extend([np.take_along_axis(evt_time, order, 1),
                           np.take_along_axis(evt_kind, order, 1)])
        run_all(general_work, len(jobs))

    def general_work(ta: Any, counter: Iterator[int]) -> None:
        evt_time, evt_kind = events
        for k in counter:
            if k >= len(jobs):
                return
            lo, hi = jobs[k]
            run_chunk(ta, lo, hi, xs, pars, evt_time, evt_kind, segs, final, samples, info,
                       max_steps, bound, outcomes)

    def run_all(work: Any, count: int) -> None:
        workers = max(1, min(int(threads or default_workers()), count))
        counter = itertools.count()  # next() on it is atomic: threads share it safely
        copies = [_borrow(integ) for _ in range(workers)]
        try:
            if workers == 1:
                work(copies[0], counter)
            else:
                with ThreadPoolExecutor(workers) as pool:
                    for fut in [pool.submit(work, ta, counter) for ta in copies]:
                        fut.result()
        finally:
            for ta in copies:
                _give_back(integ, ta)

    if not lean:
        run_general()
        return final, samples, info
    run_all(lean_work, full)
    final[: full * bs] = final_b.transpose(0, 2, 1).reshape(full * bs, n)
    info[: full * bs, 1] = steps.ravel()
    x_end = final[: full * bs]
    with np.errstate(invalid="ignore"):
        bad = ((reached.ravel() != target.ravel()) | (steps.ravel() >= max_steps)
               | ~(np.abs(x_end) <= bound).all(axis=1))  # NaN fails <= bound
    redo = sorted(set((np.flatnonzero(bad) // bs).tolist()))
    if ts.size:
        samples[: full * bs, at_start] = xs[: full * bs, None]
        samples[: full * bs, at_end] = x_end[:, None]
        for k in redo:  # the general path fills these, NaN past a stop
            samples[k * bs: (k + 1) * bs] = np.nan
    jobs = [(k * bs, (k + 1) * bs) for k in redo] + chunks
    if jobs:  # failed batches and the last, partial one: the general path
        run_general()
    return final, samples, info
