r"""Parameter sweeps of bracket motions: the original system against its nilpotent approximation.

One sample is one *pair* of trajectories under the periodic bracket input of
:mod:`nilpotent.simulate` ($u_I = -A\omega\sin\omega t$, $u_J = A\omega\cos\omega t$,
others 0, ``periods`` whole periods):

* the original system from a start point $q_0$ near $p$ (model coordinates);
* the nilpotent approximation at $p$ from $\hat y_0 = y(q_0)$ (privileged
  coordinates of $q_0$, so both start at the same place).

The errors are measured in the privileged coordinates $y$ of $p$, per weight
group $w$: $\max_{w_j = w}|y_j - \hat y_j|$ at the end point (``endpoint``) and
its maximum over ``time_samples`` equally spaced times (``along``), plus the
Euclidean distance of the two end points in model coordinates.  From $q_0 = p$
the error of group $w$ scales like $A^{w+1}$ (MATH.md §6); from $q_0 \ne p$ at
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

Engines: locally the batched numba integrator of :mod:`nilpotent.numeric`
(threads over the batch, chunks of ``chunk_size`` pairs; a process pool adds
nothing there: the threads already use every core).  With ``dask=`` (a
scheduler address, ``"local"`` for a :class:`distributed.LocalCluster` on this
machine, or a :class:`distributed.Client`) the chunks go to Dask workers; Dask
is the optional extra ``pip install "nilpotent[dask]"``.  Scripts that use
``dask="local"`` need an ``if __name__ == "__main__":`` guard (workers are
spawned processes that import the script).

Conventions: bracket $[X, Y] = DY\cdot X - DX\cdot Y$; inputs and fields are
numbered from 1.
"""

from __future__ import annotations

import csv
import itertools
import math
import os
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.core.system import ControlSystem
from nilpotent.errors import MissingExtraError, OptionError, PointError
from nilpotent.numeric.compile import CompiledSystem, compile_fields, compile_system
from nilpotent.numeric.integrators import METHODS, Status, integrate
from nilpotent.numeric.signals import bracket_inputs

__all__ = [
    "DEFAULT_AMPLITUDES",
    "DESIGNS",
    "MIN_DASK_CHUNK",
    "SweepParameters",
    "SweepResult",
    "amplitude_range",
    "sweep",
]

#: Default amplitudes (factors of 2, as :data:`nilpotent.simulate.DEFAULT_AMPLITUDES`).
DEFAULT_AMPLITUDES: tuple[float, ...] = (0.01, 0.02, 0.04, 0.08, 0.16)

#: Sampling designs of :func:`sweep`.
DESIGNS: dict[str, str] = {
    "grid": "every combination of parameter set, bracket, start point and amplitude",
    "random": "`samples` rows, each with a random parameter set, bracket, start point "
              "and a log-uniform amplitude",
}

#: Smallest chunk sent to a Dask worker (scheduling one task costs 30–70 trajectories).
MIN_DASK_CHUNK = 1000

_INSTALL_DASK = 'pip install "nilpotent[dask]"'


def amplitude_range(low: float, high: float, count: int) -> tuple[float, ...]:
    """``count`` amplitudes from ``low`` to ``high``, equally spaced in $\\log A$.

    Logarithmic spacing gives the log–log fits of :meth:`SweepResult.fits`
    evenly spread points.  ``count == 1`` needs ``low == high``.
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


# --- the request ------------------------------------------------------------------------


@dataclass(frozen=True)
class SweepParameters:
    """Everything a sweep was asked to do (carried by its :class:`SweepResult`).

    Attributes
    ----------
    model:
        Name of the system.
    point:
        $p$, each coordinate as an exact expression string.
    brackets:
        Bracket pairs $(I, J)$ (1-based).
    amplitudes:
        Amplitudes of the grid, or (``design="random"``) whose smallest and
        largest bound the log-uniform draw.
    design:
        ``"grid"`` or ``"random"`` (:data:`DESIGNS`).
    samples:
        Random start points (grid) or rows (random); 0 in a grid means the single start $p$.
    radius:
        Radius of the ball round $p$ (model coordinates) of the random starts.
    seed:
        Seed of :func:`numpy.random.default_rng`.
    vary:
        Model parameters swept: ``(name, (value, ...))`` with exact expression strings.
    periods:
        Whole periods of the bracket input ($\\omega = 1$: it drops out).
    time_samples:
        Sample times per trajectory for the errors along the way.
    method, rtol, atol, bound, max_steps:
        Integration settings (:func:`nilpotent.numeric.integrate`).
    engine:
        Integration engine asked for.
    chunk_size:
        Pairs of trajectories per chunk.
    dask:
        ``None`` (local), ``"local"``, or the scheduler address.
    """

    model: str
    point: tuple[str, ...]
    brackets: tuple[tuple[int, int], ...]
    amplitudes: tuple[float, ...]
    design: str
    samples: int
    radius: float
    seed: int
    vary: tuple[tuple[str, tuple[str, ...]], ...]
    periods: int
    time_samples: int
    method: str
    rtol: float
    atol: float
    bound: float
    max_steps: int
    engine: str
    chunk_size: int
    dask: str | None

    def to_json(self) -> dict[str, Any]:
        return {
            "model": self.model,
            "point": list(self.point),
            "brackets": [list(b) for b in self.brackets],
            "amplitudes": list(self.amplitudes),
            "design": self.design,
            "samples": self.samples,
            "radius": self.radius,
            "seed": self.seed,
            "vary": {name: list(values) for name, values in self.vary},
            "omega": 1.0,
            "periods": self.periods,
            "time_samples": self.time_samples,
            "method": self.method,
            "rtol": self.rtol,
            "atol": self.atol,
            "bound": self.bound,
            "max_steps": self.max_steps,
            "engine": self.engine,
            "chunk_size": self.chunk_size,
            "dask": self.dask,
        }


# --- the result -----------------------------------------------------------------------


def _ro(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


def _json_float(value: float) -> float | None:
    value = float(value)
    return value if math.isfinite(value) else None


@dataclass(frozen=True, eq=False)
class SweepResult:
    r"""Per-sample errors of a sweep, with what produced them.

    Rows are samples (pairs of trajectories); arrays are read-only.

    Attributes
    ----------
    parameters:
        The request (:class:`SweepParameters`).
    coordinates:
        Names of the model coordinates.
    parameter_sets:
        One ``{name: exact string}`` per swept parameter set (``({},)`` when
        nothing is varied).
    weights:
        The weights $w_1 \le \dots \le w_n$ at $p$, one tuple per parameter set.
    groups:
        Every weight that occurs (sorted): the keys of the error dicts.
    parameter_index:
        ``(N,)`` index into ``parameter_sets``.
    bracket:
        ``(N, 2)`` the pair $(I, J)$.
    amplitude:
        ``(N,)`` $A$.
    start:
        ``(N, n)`` $q_0$ (model coordinates).
    offset:
        ``(N,)`` $|q_0 - p|$.
    status_original, status_approximation:
        ``(N,)`` :class:`~nilpotent.numeric.integrators.Status` codes (blow-ups
        and other early stops are reported here, never raised).
    final_original, final_approximation:
        ``(N, n)`` end points in model coordinates (the approximation's mapped
        back with the privileged coordinates' inverse); the last state reached
        where a trajectory stopped early.
    endpoint_error:
        ``(N,)`` Euclidean distance of the two end points (NaN unless both succeeded).
    endpoint_by_weight:
        weight $w$ → ``(N,)``: $\max_{w_j = w}|y_j(T) - \hat y_j(T)|$.
    along_by_weight:
        weight $w$ → ``(N,)``: the same, maximum over the sample times.
    engine:
        The integration engine(s) that ran (``"numba"``, ``"scipy"``, ...).
    backend:
        ``"local"`` or ``"dask"``.
    scheduler:
        The Dask scheduler address (``None`` locally).
    versions:
        Versions of Python, nilpotent and the numeric packages used.
    tolerance:
        Accuracy of the integrations (largest reported).
    floor:
        Errors at or below it are integration noise (not fitted).
    wall_time:
        Seconds the integrations took (chunks included, approximations excluded).
    """

    parameters: SweepParameters
    coordinates: tuple[str, ...]
    parameter_sets: tuple[dict[str, str], ...]
    weights: tuple[tuple[int, ...], ...]
    groups: tuple[int, ...]
    parameter_index: np.ndarray
    bracket: np.ndarray
    amplitude: np.ndarray
    start: np.ndarray
    offset: np.ndarray
    status_original: np.ndarray
    status_approximation: np.ndarray
    final_original: np.ndarray
    final_approximation: np.ndarray
    endpoint_error: np.ndarray
    endpoint_by_weight: dict[int, np.ndarray]
    along_by_weight: dict[int, np.ndarray]
    engine: str
    backend: str
    scheduler: str | None
    versions: dict[str, str]
    tolerance: float
    floor: float
    wall_time: float

    # --- summaries -------------------------------------------------------------------
    def __len__(self) -> int:
        return int(self.amplitude.size)

    @property
    def ok(self) -> np.ndarray:
        """``(N,)`` True where both trajectories reached the end."""
        return (self.status_original == Status.SUCCESS) & (
            self.status_approximation == Status.SUCCESS
        )

    def status_counts(self) -> dict[str, dict[str, int]]:
        """Counts of each :class:`Status` name, for the original and the approximation."""
        out: dict[str, dict[str, int]] = {}
        for label, st in (("original", self.status_original),
                          ("approximation", self.status_approximation)):
            out[label] = {s.name.lower(): int(np.count_nonzero(st == s)) for s in Status}
        return out

    def fits(self) -> list[dict[str, Any]]:
        r"""Log–log slopes of the errors against the amplitude, per weight group.

        One entry per (parameter set, bracket): least-squares slope of
        $\log(\text{error})$ on $\log A$ over the successful samples whose
        error is above :attr:`floor` (``None`` where fewer than two different
        amplitudes remain: the group is exact there).  ``slopes`` fit the
        errors along the way, ``endpoint_slopes`` those at the end point;
        ``expected_slopes`` is $w + 1$ (valid from $q_0 = p$, or $|q_0 - p| \ll A$).
        """
        out = []
        pairs = sorted({(int(k), (int(b[0]), int(b[1])))
                        for k, b in zip(self.parameter_index, self.bracket, strict=True)})
        for k, br in pairs:
            rows = (self.parameter_index == k) & (self.bracket[:, 0] == br[0]) & (
                self.bracket[:, 1] == br[1]) & self.ok
            present = sorted(set(self.weights[k]))
            out.append({
                "parameters": dict(self.parameter_sets[k]),
                "bracket": list(br),
                "samples": int(np.count_nonzero(rows)),
                "slopes": {str(w): self._slope(self.along_by_weight[w], rows) for w in present},
                "endpoint_slopes": {
                    str(w): self._slope(self.endpoint_by_weight[w], rows) for w in present
                },
                "expected_slopes": {str(w): w + 1 for w in present},
            })
        return out

    def _slope(self, errors: np.ndarray, rows: np.ndarray) -> float | None:
        keep = rows & np.isfinite(errors) & (errors > self.floor)
        amps = self.amplitude[keep]
        if np.unique(amps).size < 2:
            return None
        return float(np.polyfit(np.log(amps), np.log(errors[keep]), 1)[0])

    def summary(self) -> dict[str, Any]:
        """Counts, statuses, and error quantiles (median, 90 %, max) over the successful samples."""

        def stats(values: np.ndarray) -> dict[str, float | None]:
            v = values[self.ok & np.isfinite(values)]
            if v.size == 0:
                return {"median": None, "p90": None, "max": None}
            return {
                "median": _json_float(np.median(v)),
                "p90": _json_float(np.quantile(v, 0.9)),
                "max": _json_float(v.max()),
            }

        blow = (self.status_original == Status.BLOW_UP) | (
            self.status_approximation == Status.BLOW_UP)
        return {
            "count": len(self),
            "succeeded": int(np.count_nonzero(self.ok)),
            "blow_ups": int(np.count_nonzero(blow)),
            "failed": int(np.count_nonzero(~self.ok)),
            "endpoint_error": stats(self.endpoint_error),
            "endpoint_by_weight": {str(w): stats(e) for w, e in self.endpoint_by_weight.items()},
            "along_by_weight": {str(w): stats(e) for w, e in self.along_by_weight.items()},
            "wall_time": self.wall_time,
            "pairs_per_second": _json_float(len(self) / self.wall_time)
            if self.wall_time > 0 else None,
        }

    # --- figure ----------------------------------------------------------------------
    def plot(self, ax: Any = None, *, which: str = "along") -> tuple[Any, Any]:
        """Log–log scatter of the errors against the amplitude, one colour per weight group.

        ``which``: ``"along"`` (errors along the way) or ``"endpoint"``.  The
        fitted line of each (parameter set, bracket, weight) is drawn over the
        successful samples above the noise floor.  Built without pyplot;
        returns ``(figure, axes)``.
        """
        if which not in ("along", "endpoint"):
            raise OptionError(f"which must be 'along' or 'endpoint', got {which!r}")
        if ax is None:
            from matplotlib.figure import Figure

            fig = Figure(figsize=(6.4, 4.4), layout="constrained")
            ax = fig.add_subplot(1, 1, 1)
        else:
            fig = ax.figure
        errors = self.along_by_weight if which == "along" else self.endpoint_by_weight
        key = "slopes" if which == "along" else "endpoint_slopes"
        fits = {(tuple(f["parameters"].items()), tuple(f["bracket"])): f for f in self.fits()}
        for w in self.groups:
            err = errors[w]
            keep = self.ok & np.isfinite(err) & (err > self.floor)
            (dots,) = ax.loglog(self.amplitude[keep], err[keep], ".", alpha=0.5,
                                label=f"weight {w}")
            for k, pset in enumerate(self.parameter_sets):
                for br in self.parameters.brackets:
                    fit = fits.get((tuple(pset.items()), br))
                    slope = None if fit is None else fit[key].get(str(w))
                    rows = keep & (self.parameter_index == k) & (self.bracket[:, 0] == br[0]) & (
                        self.bracket[:, 1] == br[1])
                    if slope is None or np.unique(self.amplitude[rows]).size < 2:
                        continue
                    coef = np.polyfit(np.log(self.amplitude[rows]), np.log(err[rows]), 1)
                    a = np.geomspace(self.amplitude[rows].min(), self.amplitude[rows].max(), 20)
                    ax.loglog(a, np.exp(np.polyval(coef, np.log(a))), "-",
                              color=dots.get_color(), label=f"slope {slope:.2f} (w + 1 = {w + 1})")
        ax.set_xlabel("amplitude A")
        ax.set_ylabel("|y − ŷ| in the group" + (" (max along the way)" if which == "along"
                                                  else " (end point)"))
        ax.set_title(f"{self.parameters.model}: {len(self)} bracket motions")
        ax.legend(loc="best", fontsize="small")
        return fig, ax

    # --- export ----------------------------------------------------------------------
    def columns(self) -> list[str]:
        """Column names of :meth:`rows` / :meth:`to_csv`."""
        names = ["sample"]
        names += [f"param_{n}" for n, _ in self.parameters.vary]
        names += ["bracket_i", "bracket_j", "amplitude"]
        names += [f"start_{c}" for c in self.coordinates]
        names += ["offset", "status_original", "status_approximation", "endpoint_error"]
        names += [f"endpoint_w{w}" for w in self.groups]
        names += [f"along_w{w}" for w in self.groups]
        names += [f"final_{c}" for c in self.coordinates]
        names += [f"final_hat_{c}" for c in self.coordinates]
        return names

    def rows(self) -> Iterator[list[Any]]:
        """One list per sample, aligned with :meth:`columns` (statuses by name, NaN as ``nan``)."""
        vary_names = [n for n, _ in self.parameters.vary]
        for r in range(len(self)):
            pset = self.parameter_sets[int(self.parameter_index[r])]
            row: list[Any] = [r]
            row += [pset[n] for n in vary_names]
            row += [int(self.bracket[r, 0]), int(self.bracket[r, 1]), float(self.amplitude[r])]
            row += [float(v) for v in self.start[r]]
            row += [
                float(self.offset[r]),
                Status(int(self.status_original[r])).name.lower(),
                Status(int(self.status_approximation[r])).name.lower(),
                float(self.endpoint_error[r]),
            ]
            row += [float(self.endpoint_by_weight[w][r]) for w in self.groups]
            row += [float(self.along_by_weight[w][r]) for w in self.groups]
            row += [float(v) for v in self.final_original[r]]
            row += [float(v) for v in self.final_approximation[r]]
            yield row

    def to_csv(self, path: str | os.PathLike[str]) -> Path:
        """Write one row per sample (header :meth:`columns`; floats in full precision)."""
        target = Path(path)
        with open(target, "w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle)
            writer.writerow(self.columns())
            for row in self.rows():
                writer.writerow([repr(v) if isinstance(v, float) else v for v in row])
        return target

    def to_json(self, *, include_samples: bool = False) -> dict[str, Any]:
        """The ``nilpotent/sweep@1`` object: request, provenance, summary and fits.

        ``include_samples`` adds ``"samples": {"columns": [...], "rows": [...]}``
        (non-finite numbers as ``null``).
        """
        out: dict[str, Any] = {
            "schema": "nilpotent/sweep@1",
            "model": self.parameters.model,
            "coordinates": list(self.coordinates),
            "point": dict(zip(self.coordinates, self.parameters.point, strict=True)),
            "parameters": self.parameters.to_json(),
            "parameter_sets": [dict(p) for p in self.parameter_sets],
            "weights": [list(w) for w in self.weights],
            "engine": self.engine,
            "backend": self.backend,
            "scheduler": self.scheduler,
            "versions": dict(self.versions),
            "tolerance": _json_float(self.tolerance),
            "floor": _json_float(self.floor),
            "statuses": self.status_counts(),
            "summary": self.summary(),
            "fits": self.fits(),
        }
        if include_samples:
            out["samples"] = {
                "columns": self.columns(),
                "rows": [
                    [_json_float(v) if isinstance(v, float) else v for v in row]
                    for row in self.rows()
                ],
            }
        return out


# --- the work: chunks of pairs --------------------------------------------------------


@dataclass(frozen=True)
class _Fields:
    """A compiled system as plain data (picklable; rebuilt on a Dask worker)."""

    name: str
    coordinate_names: tuple[str, ...]
    fields: tuple[tuple[sp.Expr, ...], ...]
    key: str
    backend: str

    @classmethod
    def of(cls, compiled: CompiledSystem) -> _Fields:
        return cls(compiled.name, compiled.coordinate_names, compiled.fields, compiled.key,
                   compiled.backend)


_REBUILT: dict[str, CompiledSystem] = {}


def _rebuild(spec: _Fields) -> CompiledSystem:
    """The :class:`CompiledSystem` of ``spec`` (one per process; generated code is cached)."""
    key = f"{spec.key}:{spec.backend}"
    compiled = _REBUILT.get(key)
    if compiled is None:
        compiled = CompiledSystem(spec.name, spec.coordinate_names, spec.fields, spec.key,
                                  spec.backend)
        _REBUILT[key] = compiled
    return compiled


@dataclass(frozen=True)
class _Job:
    """What one parameter set needs: the four compiled maps and its weight groups."""

    original: _Fields
    approximation: _Fields
    forward: _Fields  # model coordinates -> y (one "field" of n components)
    inverse: _Fields  # y -> model coordinates
    groups: tuple[tuple[int, tuple[int, ...]], ...]  # (weight, coordinate indices)


@dataclass(frozen=True)
class _Chunk:
    job: _Job
    rows: np.ndarray  # (B,) indices into the whole sweep
    starts: np.ndarray  # (B, n)
    brackets: np.ndarray  # (B, 2)
    amplitudes: np.ndarray  # (B,)
    periods: int
    time_samples: int
    method: str
    engine: str
    rtol: float
    atol: float
    bound: float
    max_steps: int
    threads: int | None


def _apply_map(spec: _Fields, points: np.ndarray) -> np.ndarray:
    compiled = _rebuild(spec)
    flat = np.ascontiguousarray(points.reshape(-1, points.shape[-1]))
    values = compiled.field_values(flat)[:, :, 0]
    return values.reshape(*points.shape[:-1], values.shape[-1])


def _run_chunk(chunk: _Chunk) -> dict[str, Any]:
    """Integrate one chunk of pairs; module-level so that Dask can ship it."""
    job = chunk.job
    original = _rebuild(job.original)
    approximation = _rebuild(job.approximation)
    inputs = bracket_inputs(original.m, chunk.brackets[:, 0], chunk.brackets[:, 1],
                            chunk.amplitudes, omega=1.0, periods=chunk.periods)
    times = np.linspace(0.0, 2 * math.pi * chunk.periods, chunk.time_samples)
    y0 = _apply_map(job.forward, chunk.starts)
    common = dict(method=chunk.method, engine=chunk.engine, times=times, rtol=chunk.rtol,
                  atol=chunk.atol, bound=chunk.bound, max_steps=chunk.max_steps,
                  threads=chunk.threads)
    sol_x = integrate(original, chunk.starts, inputs, **common)
    sol_y = integrate(approximation, y0, inputs, **common)
    ok = (sol_x.status == Status.SUCCESS) & (sol_y.status == Status.SUCCESS)
    with np.errstate(all="ignore"):
        final_y = _apply_map(job.forward, np.asarray(sol_x.final))
        along_y = _apply_map(job.forward, np.asarray(sol_x.samples))
        final_hat = _apply_map(job.inverse, np.asarray(sol_y.final))
        end_diff = np.abs(final_y - np.asarray(sol_y.final))
        along_diff = np.abs(along_y - np.asarray(sol_y.samples))
        distance = np.linalg.norm(np.asarray(sol_x.final) - final_hat, axis=1)
    nan = np.full(ok.shape, np.nan)
    endpoint: dict[int, np.ndarray] = {}
    along: dict[int, np.ndarray] = {}
    for w, idx in job.groups:
        cols = list(idx)
        endpoint[w] = np.where(ok, end_diff[:, cols].max(axis=1), nan)
        along[w] = np.where(ok, along_diff[:, :, cols].max(axis=(1, 2)), nan)
    scale = float(np.nanmax(np.abs(along_y[ok]))) if np.any(ok) else 0.0
    return {
        "rows": chunk.rows,
        "status_original": np.asarray(sol_x.status),
        "status_approximation": np.asarray(sol_y.status),
        "final_original": np.asarray(sol_x.final),
        "final_approximation": final_hat,
        "endpoint_error": np.where(ok, distance, nan),
        "endpoint": endpoint,
        "along": along,
        "engines": {sol_x.engine, sol_y.engine},
        "tolerance": max(sol_x.tolerance, sol_y.tolerance),
        "scale": scale,
    }


# --- planning the samples -------------------------------------------------------------


def _as_value(value: Any, where: str) -> sp.Expr:
    """A parameter value: sympy numbers and Python numbers as they are, text through the grammar."""
    if isinstance(value, str):
        from nilpotent.core.expressions import parse_expression

        expr = parse_expression(value, {}, where=where)
    elif isinstance(value, sp.Basic):
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
        i, j = int(pair[0]), int(pair[1])
        if not (1 <= i <= m and 1 <= j <= m) or i == j:
            raise OptionError(f"bracket ({i},{j}): need two different fields between 1 and {m}")
        out.append((i, j))
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


def _versions(backend: str) -> dict[str, str]:
    from importlib import metadata

    import nilpotent

    out = {"python": sys.version.split()[0], "nilpotent": nilpotent.__version__}
    names = ["numpy", "sympy", "symengine", "numba"]
    if backend == "dask":
        names += ["dask", "distributed"]
    for name in names:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return out


def _import_distributed() -> Any:
    try:
        import distributed
    except ImportError:
        raise MissingExtraError(
            "sweeps on Dask need the dask extra, which is not installed: "
            f"{_INSTALL_DASK}"
        ) from None
    return distributed


# --- the entry point ------------------------------------------------------------------


def sweep(
    system: ControlSystem,
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
    method: str = "adaptive",
    engine: str = "auto",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    bound: float = 1e6,
    max_steps: int = 100_000,
    chunk_size: int = 4096,
    dask: Any = None,
    progress: Callable[[int, int], None] | None = None,
) -> SweepResult:
    r"""Simulate many bracket motions of ``system`` and of its nilpotent approximation at $p$.

    Parameters
    ----------
    system:
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
    method, engine, rtol, atol, bound, max_steps:
        Integration (:func:`nilpotent.numeric.integrate`); a trajectory leaving
        $|x_k| \le$ ``bound`` is stopped and reported as a blow-up.
    chunk_size:
        Pairs per chunk (at least :data:`MIN_DASK_CHUNK` on Dask).
    dask:
        ``None``: this process.  ``"local"``: a :class:`distributed.LocalCluster`
        on this machine (one single-threaded worker per core; started and
        closed here).  A scheduler address (``"tcp://host:8786"``) or a
        :class:`distributed.Client`: that cluster.  Needs the ``dask`` extra
        (:class:`~nilpotent.errors.MissingExtraError` otherwise).
    progress:
        Called as ``progress(done_pairs, total_pairs)`` after each chunk.

    Returns
    -------
    SweepResult
        Rows ordered parameter set → bracket → start → amplitude (grid), or as drawn (random).
    """
    # --- validate the request --------------------------------------------------------
    if design not in DESIGNS:
        raise OptionError(f"unknown design {design!r} (choose from {', '.join(DESIGNS)})")
    if method not in METHODS:
        raise OptionError(f"unknown method {method!r} (choose from {', '.join(METHODS)})")
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
    pairs = _check_brackets(system.m, brackets)
    varied = _parameter_sets(system, vary)
    client, cluster, scheduler = None, None, None
    if dask is not None:
        distributed = _import_distributed()
        if int(chunk_size) < MIN_DASK_CHUNK:
            raise OptionError(
                f"chunk_size {chunk_size} is too small for Dask: one task costs as much as "
                f"30–70 trajectories; use at least {MIN_DASK_CHUNK}"
            )
        if not isinstance(dask, str | distributed.Client):
            raise OptionError("dask must be 'local', a scheduler address or a distributed.Client")

    # --- one job per parameter set ---------------------------------------------------
    from nilpotent.core.approximation import approximate
    from nilpotent.core.expressions import format_expression

    names = [n for n, _ in varied]
    combos = list(itertools.product(*[vals for _, vals in varied])) if varied else [()]
    jobs: list[_Job] = []
    psets: list[dict[str, str]] = []
    weights: list[tuple[int, ...]] = []
    base = system.specialized()
    pt = base.point(point) if point is not None else base.origin()
    try:
        p_float = np.array([float(v) for v in pt])
    except TypeError:
        raise PointError(f"the point {pt} is not made of real numbers") from None
    for combo in combos:
        sys_k = system.with_parameters(dict(zip(names, combo, strict=True))) if combo else system
        sysp = sys_k.specialized()
        approx = approximate(sysp, pt)
        w = tuple(int(v) for v in approx.filtration.weights)
        groups: dict[int, list[int]] = {}
        for j, wj in enumerate(w):
            groups.setdefault(wj, []).append(j)
        coords = approx.coordinates
        jobs.append(_Job(
            original=_Fields.of(compile_system(sysp)),
            approximation=_Fields.of(compile_fields(coords.names, approx.fields,
                                                    name=f"{sysp.name}-nilpotent")),
            forward=_Fields.of(compile_fields(sysp.coordinates, [tuple(coords.forward)],
                                              name=f"{sysp.name}-forward", backend="numpy")),
            inverse=_Fields.of(compile_fields(coords.names, [tuple(coords.inverse)],
                                              name=f"{sysp.name}-inverse", backend="numpy")),
            groups=tuple((wk, tuple(idx)) for wk, idx in sorted(groups.items())),
        ))
        psets.append({n: format_expression(v) for n, v in zip(names, combo, strict=True)})
        weights.append(w)
    n = system.n
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
    for k, job in enumerate(jobs):
        rows_k = np.flatnonzero(p_idx == k)
        for lo_i in range(0, rows_k.size, int(chunk_size)):
            sel = rows_k[lo_i: lo_i + int(chunk_size)]
            chunks.append(_Chunk(
                job=job, rows=sel, starts=np.ascontiguousarray(starts[sel]),
                brackets=np.ascontiguousarray(row_brackets[sel]),
                amplitudes=np.ascontiguousarray(row_amps[sel]), periods=int(periods),
                time_samples=int(time_samples), method=method, engine=engine,
                rtol=float(rtol), atol=float(atol), bound=float(bound),
                max_steps=int(max_steps), threads=threads,
            ))

    t0 = time.perf_counter()  # restarted below once a Dask cluster is up
    if dask is None:
        outputs = []
        done = 0
        for chunk in chunks:
            outputs.append(_run_chunk(chunk))
            done += chunk.rows.size
            if progress is not None:
                progress(done, total)
        backend = "local"
    else:
        backend = "dask"
        if isinstance(dask, str):
            if dask == "local":
                cluster = distributed.LocalCluster(
                    n_workers=os.cpu_count() or 1, threads_per_worker=1, processes=True,
                    dashboard_address=None,
                )
                client = distributed.Client(cluster)
            else:
                try:
                    client = distributed.Client(dask)
                except (OSError, TimeoutError, ValueError) as exc:
                    raise OptionError(
                        f"cannot reach the Dask scheduler at {dask!r}: {exc}"
                    ) from None
            own_client = True
        else:
            client = dask
            own_client = False
        try:
            scheduler = str(client.scheduler.address)
            t0 = time.perf_counter()
            futures = client.map(_run_chunk, chunks, pure=False)
            index = {f.key: k for k, f in enumerate(futures)}
            results: list[Any] = [None] * len(chunks)
            done = 0
            for fut in distributed.as_completed(futures):
                k = index[fut.key]
                results[k] = fut.result()
                done += chunks[k].rows.size
                if progress is not None:
                    progress(done, total)
            outputs = results
        finally:
            if own_client:
                client.close()
            if cluster is not None:
                cluster.close()
    wall = time.perf_counter() - t0

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
        model=system.name,
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
        coordinates=system.coordinate_names,
        parameter_sets=tuple(psets),
        weights=tuple(weights),
        groups=all_groups,
        parameter_index=_ro(p_idx.astype(np.int64)),
        bracket=_ro(row_brackets),
        amplitude=_ro(row_amps.astype(float)),
        start=_ro(starts),
        offset=_ro(np.linalg.norm(starts - p_float[None, :], axis=1)),
        status_original=_ro(status_o),
        status_approximation=_ro(status_a),
        final_original=_ro(final_o),
        final_approximation=_ro(final_a),
        endpoint_error=_ro(distance),
        endpoint_by_weight={w: _ro(e) for w, e in endpoint.items()},
        along_by_weight={w: _ro(e) for w, e in along.items()},
        engine="+".join(sorted(engines)),
        backend=backend,
        scheduler=scheduler,
        versions=_versions(backend),
        tolerance=tolerance if tolerance > 0 else float(rtol),
        floor=1e3 * (float(atol) + float(rtol) * scale),
        wall_time=wall,
    )
