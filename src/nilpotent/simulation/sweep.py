r"""Parameter sweeps of bracket motions: the original system against its nilpotent approximation.

One sample is one *pair* of trajectories under the periodic bracket input of
:mod:`nilpotent.numeric.signals` ($u_I = -A\omega\sin\omega t$, $u_J = A\omega\cos\omega t$,
others 0, ``periods`` whole periods):

* the original system from a start point $q_0$ near $p$ (model coordinates);
* the nilpotent approximation at $p$ from $\hat y_0 = y(q_0)$ (privileged
  coordinates of $q_0$, so both start at the same place).

The errors are measured in the privileged coordinates $y$ of $p$, per weight
group $w$: $\max_{w_j = w}|y_j - \hat y_j|$ at the end point (``endpoint``) and
its maximum over ``time_samples`` equally spaced times (``along``), plus the
Euclidean distance of the two end points in model coordinates.  From $q_0 = p$
the error of group $w$ scales like $A^{w+1}$ (the mathematics page, §6); from $q_0 \ne p$ at
distance $\rho \gg A$ it is only $O(A)$ (the approximation is good near $p$).

**The frequency drops out.** Over whole periods, $s = \omega t$ turns
$\dot x = A\omega(-\sin\omega t\,X_I + \cos\omega t\,X_J)$ into
$dx/ds = A(-\sin s\,X_I + \cos s\,X_J)$: the path, its end point and every
error along it are the same for every $\omega > 0$.  A one-period sweep over
$(A, \omega, q_0)$ is therefore a sweep over $(A, q_0)$, and :func:`sweep`
integrates with $\omega = 1$.

What is swept (:func:`sweep`): amplitudes, start points (random, uniform in the
Euclidean ball of radius ``radius`` round $p$ in model coordinates), bracket
pairs and model parameters (each parameter set is its own system with its own
approximation, computed once).  ``design="grid"`` takes every combination;
``design="random"`` draws ``samples`` rows, the amplitude log-uniform between
the smallest and largest amplitude given.

Engines: locally the batched integrators of :mod:`nilpotent.numeric`
(threads over the batch, chunks of ``chunk_size`` pairs; a process pool adds
nothing there: the threads already use every core), each chunk one call of the
pair engine :meth:`~nilpotent.simulation.pair.CompiledPair.run`; the chunks run
through :mod:`nilpotent.simulation.executors`.  With ``dask=`` (a
scheduler address, ``"local"`` for a :class:`distributed.LocalCluster` on this
machine, or a :class:`distributed.Client`) the chunks go to Dask workers; Dask
is the optional extra ``pip install "nilpotent[dask]"``.  Scripts that use
``dask="local"`` need an ``if __name__ == "__main__":`` guard (workers are
spawned processes that import the script).

Conventions: bracket $[X, Y] = DY\cdot X - DX\cdot Y$; inputs and fields are
numbered from 1.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import OptionError, PointError
from nilpotent.numeric.settings import DEFAULT_SETTINGS, IntegrationSettings, resolve_settings
from nilpotent.numeric.signals import bracket_inputs, check_bracket
from nilpotent.progress import ProgressCallback
from nilpotent.simulation.executors import MIN_DASK_CHUNK, check_dask, execute, versions
from nilpotent.simulation.pair import CompiledPair
from nilpotent.simulation.scaling import DEFAULT_AMPLITUDES
from nilpotent.simulation.sweep_result import SweepParameters, SweepResult, read_only

__all__ = [
    "DEFAULT_AMPLITUDES",
    "DESIGNS",
    "MIN_DASK_CHUNK",
    "SWEEP_SETTINGS",
    "SweepParameters",
    "SweepResult",
    "amplitude_range",
    "sweep",
]


#: The integration of a sweep: the one default
#: (:data:`nilpotent.numeric.settings.DEFAULT_SETTINGS`) with the blow-up bound
#: ``1e6`` (a documented override, kept so that sweeps give the results they
#: gave: a motion of a large sweep that leaves ``|x_k| <= 1e6`` is reported
#: as a blow-up sooner).
SWEEP_SETTINGS = DEFAULT_SETTINGS.replace(bound=1e6)


#: Sampling designs of :func:`sweep`.
DESIGNS: dict[str, str] = {
    "grid": "every combination of parameter set, bracket, start point and amplitude",
    "random": "`samples` rows, each with a random parameter set, bracket, start point "
              "and a log-uniform amplitude",
}


def amplitude_range(low: float, high: float, count: int) -> tuple[float, ...]:
    """``count`` amplitudes from ``low`` to ``high``, equally spaced in $\\log A$.

    Logarithmic spacing gives the log–log fits of :meth:`SweepResult.fits`
    evenly spread points.  ``count == 1`` needs ``low == high``.

    Parameters
    ----------
    low, high : float
        The smallest and largest amplitude (``0 < low ≤ high``).
    count : int
        How many amplitudes (≥ 1).

    Raises
    ------
    OptionError
        Amplitudes that are not ``0 < low ≤ high`` (finite), or a bad ``count``.
    """
    if not (math.isfinite(low) and math.isfinite(high) and 0 < low <= high):
        raise OptionError(f"amplitudes: need 0 < A1 <= A2, got {low} and {high}")
    if int(count) != count or count < 1:
        raise OptionError(f"amplitudes: the count must be a positive integer, got {count}")
    if count == 1:
        if low != high:
            raise OptionError("amplitudes: one amplitude needs A1 == A2")
        return (float(low),)
    return tuple(float(a) for a in np.geomspace(low, high, int(count)))


# --- the work: chunks of pairs --------------------------------------------------------


@dataclass(frozen=True)
class _Chunk:
    """One task: a batch of rows of one parameter set (picklable, for Dask)."""

    pair: CompiledPair
    rows: np.ndarray  # (B,) indices into the whole sweep
    starts: np.ndarray  # (B, n)
    brackets: np.ndarray  # (B, 2)
    amplitudes: np.ndarray  # (B,)
    periods: int
    time_samples: int
    settings: dict[str, Any]


def _run_chunk(chunk: _Chunk) -> dict[str, Any]:
    """Integrate one chunk of pairs; module-level so that Dask can ship it."""
    pair = chunk.pair
    inputs = bracket_inputs(pair.original.m, chunk.brackets[:, 0], chunk.brackets[:, 1],
                            chunk.amplitudes, omega=1.0, periods=chunk.periods)
    times = np.linspace(0.0, 2 * math.pi * chunk.periods, chunk.time_samples)
    run = pair.run(chunk.starts, inputs, times, **chunk.settings)
    ok = run.ok
    with np.errstate(all="ignore"):
        along_y = run.y()
        final_hat = run.final_x_hat()
        end_diff = np.abs(run.final_y() - run.final_y_hat)
        along_diff = np.abs(along_y - run.y_hat)
        distance = np.linalg.norm(run.final_x - final_hat, axis=1)
        endpoint = run.by_weight(end_diff, ())
        along = run.by_weight(along_diff, (1,))
    nan = np.full(ok.shape, np.nan)
    scale = float(np.nanmax(np.abs(along_y[ok]))) if np.any(ok) else 0.0
    return {
        "rows": chunk.rows,
        "status_original": run.status_original,
        "status_approximation": run.status_approximation,
        "final_original": run.final_x,
        "final_approximation": final_hat,
        "endpoint_error": np.where(ok, distance, nan),
        "endpoint": {w: np.where(ok, e, nan) for w, e in endpoint.items()},
        "along": {w: np.where(ok, e, nan) for w, e in along.items()},
        "engines": set(run.engines),
        "tolerance": run.tolerance,
        "scale": scale,
    }


# --- planning the samples -------------------------------------------------------------


def _as_value(value: Any, where: str) -> sp.Expr:
    """A parameter value: sympy numbers and Python numbers as they are, text through the grammar."""
    if isinstance(value, str):
        from nilpotent.core.model.expressions import parse_expression

        expr = parse_expression(value, {}, where=where)
    elif isinstance(value, sp.Expr):
        expr = value
    elif isinstance(value, bool) or not isinstance(value, int | float):
        raise OptionError(f"{where}: {value!r} is not a number")
    elif isinstance(value, int):
        expr = sp.Integer(value)
    else:
        if not math.isfinite(value):
            raise OptionError(f"{where}: {value!r} is not a finite number")
        expr = sp.Float(value)
    if expr.free_symbols or not expr.is_real:
        raise OptionError(f"{where}: {value!r} is not a real number")
    return expr


def _parameter_sets(system: ControlSystem, vary: Mapping[str, Sequence[Any]] | None
                    ) -> tuple[tuple[str, tuple[sp.Expr, ...]], ...]:
    if not vary:
        return ()
    out = []
    for name, values in vary.items():
        if name not in system.parameter_values:
            known = ", ".join(system.parameter_values) or "none"
            raise OptionError(f"vary: model {system.name!r} has no parameter {name!r} "
                              f"(parameters: {known})")
        if isinstance(values, str) or not isinstance(values, Sequence) or not values:
            raise OptionError(f"vary: give a non-empty list of values for {name!r}")
        out.append((name, tuple(_as_value(v, f"vary {name}") for v in values)))
    return tuple(out)


def _check_brackets(m: int, brackets: Any) -> tuple[tuple[int, int], ...]:
    items = list(brackets)
    if len(items) == 2 and all(isinstance(v, int | np.integer) for v in items):
        items = [tuple(items)]
    out = []
    for b in items:
        pair = tuple(b)
        if len(pair) != 2 or not all(isinstance(v, int | np.integer) for v in pair):
            raise OptionError(f"a bracket is a pair of field numbers (I, J), got {b!r}")
        out.append(check_bracket(m, pair))
    if not out:
        raise OptionError("give at least one bracket pair")
    return tuple(dict.fromkeys(out))


def _ball(rng: np.random.Generator, count: int, n: int, radius: float) -> np.ndarray:
    """``count`` points uniform in the Euclidean ball of ``radius`` round 0 in R^n."""
    if count == 0:
        return np.zeros((0, n))
    direction = rng.standard_normal((count, n))
    norms = np.linalg.norm(direction, axis=1, keepdims=True)
    norms[norms == 0] = 1.0
    return radius * rng.random((count, 1)) ** (1.0 / n) * direction / norms


# --- the entry point ------------------------------------------------------------------


def sweep(
    sys: ControlSystem,
    brackets: Sequence[int] | Sequence[Sequence[int]],
    amplitudes: Sequence[float] = DEFAULT_AMPLITUDES,
    *,
    point: Any = None,
    samples: int = 0,
    radius: float = 0.0,
    seed: int = 0,
    design: str = "grid",
    vary: Mapping[str, Sequence[Any]] | None = None,
    periods: int = 1,
    time_samples: int = 33,
    settings: IntegrationSettings | None = None,
    method: str | None = None,
    engine: str | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    bound: float | None = None,
    max_steps: int | None = None,
    chunk_size: int = 4096,
    dask: Any = None,
    progress: ProgressCallback | None = None,
    dask_connect_timeout: float | None = None,
    dask_progress_timeout: float | None = None,
) -> SweepResult:
    r"""Simulate many bracket motions of ``sys`` and of its nilpotent approximation at $p$.

    Parameters
    ----------
    sys:
        The original system (its parameter values are the defaults of ``vary``).
    brackets:
        One pair ``(I, J)`` or a list of pairs (1-based, different fields).
    amplitudes:
        Loop amplitudes $A > 0$ (:func:`amplitude_range` for a log-spaced range).
        In ``design="random"`` only their minimum and maximum matter.
    point:
        $p$, where the approximation is computed (default: the origin).
    samples:
        ``design="grid"``: number of random start points $q_0$ (0: the single
        start $q_0 = p$); ``design="random"``: number of rows.
    radius:
        Start points are uniform in the Euclidean ball of this radius round $p$
        (model coordinates); 0 puts every start at $p$.
    seed:
        Seed of the random draws (the same seed gives the same samples).
    design:
        ``"grid"`` or ``"random"`` (:data:`DESIGNS`).
    vary:
        Model parameters to sweep, ``{name: [value, ...]}`` (numbers, sympy
        numbers, or expression text such as ``"sqrt(2)"``); every combination
        is a parameter set with its own approximation.
    periods:
        Whole periods of the bracket input ($\omega = 1$; see the module docstring).
    time_samples:
        Equally spaced times (≥ 2, ends included) at which the errors along the way are taken.
    settings : IntegrationSettings or None
        How to integrate (:func:`nilpotent.numeric.integrate`; default
        :data:`SWEEP_SETTINGS`); a trajectory leaving $|x_k| \le$ ``bound`` is
        stopped and reported as a blow-up.
    method, engine, rtol, atol, bound, max_steps : optional
        The loose form of ``settings`` (kept for one release): each one given
        overrides that field.
    chunk_size:
        Pairs per chunk (at least :data:`MIN_DASK_CHUNK` on Dask).
    dask:
        ``None``: this process.  ``"local"``: a :class:`distributed.LocalCluster`
        on this machine (one single-threaded worker per core; started and
        closed here).  A scheduler address (``"tcp://host:8786"``), a
        :class:`distributed.Client` or a cluster object
        (:class:`distributed.deploy.Cluster`, e.g. dask-jobqueue's): that
        cluster (docs/sweeps.md: the cluster recipe).  Needs the ``dask`` extra
        (:class:`~nilpotent.errors.MissingExtraError` otherwise).
    progress : ProgressCallback or None
        Called after each chunk with ``ProgressEvent("bracket motions", done, total)``
        (:class:`~nilpotent.progress.ProgressEvent`: bracket motions, each a trajectory
        of the system and one of its approximation, done and in all); the bar
        :class:`~nilpotent.progress.Progress` is one such callback.
    dask_connect_timeout, dask_progress_timeout:
        Seconds to reach a scheduler given by address (default
        :data:`~nilpotent.simulation.executors.DEFAULT_CONNECT_TIMEOUT`), and
        without a finished chunk before the sweep stops with a
        :class:`~nilpotent.errors.DaskError` (default
        :data:`~nilpotent.simulation.executors.DEFAULT_PROGRESS_TIMEOUT`); Dask only.

    Returns
    -------
    SweepResult
        Rows ordered parameter set → bracket → start → amplitude (grid), or as drawn (random).

    Raises
    ------
    OptionError
        If an option is out of its range (amplitudes, samples, radius, design,
        periods, integration settings, chunk size, the parameters to vary).
    PointError
        If the point is not a point of ``sys``.
    MissingExtraError
        If ``dask`` is given without the ``dask`` extra installed.
    """
    # --- validate the request --------------------------------------------------------
    if design not in DESIGNS:
        raise OptionError(f"unknown design {design!r} (choose from {', '.join(DESIGNS)})")
    chosen = resolve_settings(settings, SWEEP_SETTINGS, method=method, engine=engine,
                              rtol=rtol, atol=atol, bound=bound, max_steps=max_steps)
    method, engine = chosen.method, chosen.engine
    rtol, atol, bound, max_steps = chosen.rtol, chosen.atol, chosen.bound, chosen.max_steps
    amps = np.asarray([float(a) for a in amplitudes], dtype=float)
    if amps.size == 0 or not np.all(np.isfinite(amps)) or np.any(amps <= 0):
        raise OptionError("amplitudes must be a non-empty list of numbers > 0")
    if int(samples) != samples or samples < 0:
        raise OptionError(f"samples must be an integer >= 0, got {samples}")
    if not (math.isfinite(radius) and radius >= 0):
        raise OptionError(f"radius must be a number >= 0, got {radius}")
    if design == "grid" and samples > 0 and radius == 0:
        raise OptionError("random start points need a radius > 0 (or samples = 0 for the start p)")
    if design == "random" and samples < 1:
        raise OptionError("design 'random' needs samples >= 1 (the number of rows)")
    if int(periods) != periods or periods < 1:
        raise OptionError(f"periods must be a positive integer, got {periods}")
    if int(time_samples) != time_samples or time_samples < 2:
        raise OptionError(f"time_samples must be an integer >= 2, got {time_samples}")
    if int(chunk_size) != chunk_size or chunk_size < 1:
        raise OptionError(f"chunk_size must be a positive integer, got {chunk_size}")
    if not isinstance(seed, int | np.integer) or seed < 0:
        raise OptionError(f"seed must be an integer >= 0, got {seed!r}")
    pairs = _check_brackets(sys.m, brackets)
    varied = _parameter_sets(sys, vary)
    check_dask(dask, chunk_size, connect_timeout=dask_connect_timeout,
               progress_timeout=dask_progress_timeout)

    # --- one job per parameter set ---------------------------------------------------
    from nilpotent.core.coordinates.approximation import approximate
    from nilpotent.core.model.expressions import format_expression

    names = [n for n, _ in varied]
    combos = list(itertools.product(*[vals for _, vals in varied])) if varied else [()]
    jobs: list[CompiledPair] = []
    psets: list[dict[str, str]] = []
    weights: list[tuple[int, ...]] = []
    base = sys.specialized()
    pt = base.point(point) if point is not None else base.origin()
    try:
        p_float = np.array([float(v) for v in pt])
    except TypeError:
        raise PointError(f"the point {pt} is not made of real numbers") from None
    for combo in combos:
        sys_k = sys.with_parameters(dict(zip(names, combo, strict=True))) if combo else sys
        sysp = sys_k.specialized()
        job = CompiledPair.build(sysp, approximate(sysp, pt))
        jobs.append(job)
        psets.append({n: format_expression(v) for n, v in zip(names, combo, strict=True)})
        weights.append(job.weights)
    n = sys.n
    all_groups = tuple(sorted({wk for w in weights for wk in w}))

    # --- the rows --------------------------------------------------------------------
    rng = np.random.default_rng(int(seed))
    if design == "grid":
        offsets = _ball(rng, int(samples), n, float(radius)) if samples else np.zeros((1, n))
        grid = list(itertools.product(range(len(jobs)), range(len(pairs)),
                                      range(offsets.shape[0]), range(amps.size)))
        p_idx = np.array([g[0] for g in grid], dtype=np.int64)
        b_idx = np.array([g[1] for g in grid], dtype=np.int64)
        starts = p_float[None, :] + offsets[[g[2] for g in grid]]
        row_amps = amps[[g[3] for g in grid]]
    else:
        count = int(samples)
        p_idx = rng.integers(0, len(jobs), count)
        b_idx = rng.integers(0, len(pairs), count)
        starts = p_float[None, :] + _ball(rng, count, n, float(radius))
        lo, hi = float(amps.min()), float(amps.max())
        row_amps = np.exp(rng.uniform(math.log(lo), math.log(hi), count)) if hi > lo else (
            np.full(count, lo))
    row_brackets = np.array(pairs, dtype=np.int64)[b_idx].reshape(-1, 2)
    total = int(row_amps.size)

    # --- chunks ----------------------------------------------------------------------
    threads = 1 if (dask is not None and isinstance(dask, str) and dask == "local") else None
    chunks: list[_Chunk] = []
    # what each chunk passes to the integrator (picklable: chunks travel to Dask workers)
    integration = dict(settings=chosen, threads=threads)
    for k, job in enumerate(jobs):
        rows_k = np.flatnonzero(p_idx == k)
        for lo_i in range(0, rows_k.size, int(chunk_size)):
            sel = rows_k[lo_i: lo_i + int(chunk_size)]
            chunks.append(_Chunk(
                pair=job, rows=sel, starts=np.ascontiguousarray(starts[sel]),
                brackets=np.ascontiguousarray(row_brackets[sel]),
                amplitudes=np.ascontiguousarray(row_amps[sel]), periods=int(periods),
                time_samples=int(time_samples), settings=integration,
            ))
    done = execute(_run_chunk, chunks, [c.rows.size for c in chunks], dask=dask,
                   progress=progress, connect_timeout=dask_connect_timeout,
                   progress_timeout=dask_progress_timeout, stage="bracket motions")
    outputs, backend, scheduler, wall = (done.outputs, done.backend, done.scheduler,
                                         done.wall_time)

    # --- assemble --------------------------------------------------------------------
    status_o = np.zeros(total, dtype=np.int64)
    status_a = np.zeros(total, dtype=np.int64)
    final_o = np.full((total, n), np.nan)
    final_a = np.full((total, n), np.nan)
    distance = np.full(total, np.nan)
    endpoint = {w: np.full(total, np.nan) for w in all_groups}
    along = {w: np.full(total, np.nan) for w in all_groups}
    engines: set[str] = set()
    tolerance = 0.0
    scale = 0.0
    for out in outputs:
        rows = out["rows"]
        status_o[rows] = out["status_original"]
        status_a[rows] = out["status_approximation"]
        final_o[rows] = out["final_original"]
        final_a[rows] = out["final_approximation"]
        distance[rows] = out["endpoint_error"]
        for w, e in out["endpoint"].items():
            endpoint[w][rows] = e
        for w, e in out["along"].items():
            along[w][rows] = e
        engines |= out["engines"]
        if math.isfinite(out["tolerance"]):
            tolerance = max(tolerance, out["tolerance"])
        scale = max(scale, out["scale"])
    params = SweepParameters(
        model=sys.name,
        point=tuple(format_expression(v) for v in pt),
        brackets=pairs,
        amplitudes=tuple(float(a) for a in amps),
        design=design,
        samples=int(samples),
        radius=float(radius),
        seed=int(seed),
        vary=tuple((nm, tuple(format_expression(v) for v in vals)) for nm, vals in varied),
        periods=int(periods),
        time_samples=int(time_samples),
        method=method,
        rtol=float(rtol),
        atol=float(atol),
        bound=float(bound),
        max_steps=int(max_steps),
        engine=engine,
        chunk_size=int(chunk_size),
        dask=None if dask is None else (dask if isinstance(dask, str) else scheduler),
    )
    return SweepResult(
        parameters=params,
        coordinates=sys.coordinate_names,
        parameter_sets=tuple(psets),
        weights=tuple(weights),
        groups=all_groups,
        parameter_index=read_only(p_idx.astype(np.int64)),
        bracket=read_only(row_brackets),
        amplitude=read_only(row_amps.astype(float)),
        start=read_only(starts),
        offset=read_only(np.linalg.norm(starts - p_float[None, :], axis=1)),
        status_original=read_only(status_o),
        status_approximation=read_only(status_a),
        final_original=read_only(final_o),
        final_approximation=read_only(final_a),
        endpoint_error=read_only(distance),
        endpoint_by_weight={w: read_only(e) for w, e in endpoint.items()},
        along_by_weight={w: read_only(e) for w, e in along.items()},
        engine="+".join(sorted(engines)),
        backend=backend,
        scheduler=scheduler,
        versions=versions(backend),
        tolerance=tolerance if tolerance > 0 else float(rtol),
        floor=1e3 * (float(atol) + float(rtol) * scale),
        wall_time=wall,
    )
