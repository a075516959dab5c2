r"""What a sweep was asked (:class:`SweepParameters`) and what it found (:class:`SweepResult`).

The result owns its schema: :meth:`SweepResult.to_json` builds the
``nilpotent/sweep@1`` object, :meth:`SweepResult.to_csv` one row per sample;
its figure is drawn by :mod:`nilpotent.viz`.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from nilpotent.numeric.fits import loglog_slope
from nilpotent.numeric.integrate import Status
from nilpotent.strict_json import json_object

__all__ = ["SweepParameters", "SweepResult", "json_float", "read_only"]


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
        return json_object({
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
        })


# --- the result -----------------------------------------------------------------------


def read_only(a: np.ndarray) -> np.ndarray:
    """``a`` contiguous and read-only."""
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


def json_float(value: float) -> float | None:
    """``value`` as a float, ``None`` where it is not finite (JSON has no NaN)."""
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
        ``(N,)`` :class:`~nilpotent.numeric.integrate.Status` codes (blow-ups
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
        return loglog_slope(self.amplitude[rows], errors[rows], self.floor)

    def summary(self) -> dict[str, Any]:
        """Counts, statuses, and error quantiles (median, 90 %, max) over the successful samples."""

        def stats(values: np.ndarray) -> dict[str, float | None]:
            v = values[self.ok & np.isfinite(values)]
            if v.size == 0:
                return {"median": None, "p90": None, "max": None}
            return {
                "median": json_float(np.median(v)),
                "p90": json_float(np.quantile(v, 0.9)),
                "max": json_float(v.max()),
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
            "pairs_per_second": json_float(len(self) / self.wall_time)
            if self.wall_time > 0 else None,
        }

    # --- figure ----------------------------------------------------------------------
    def plot(self, ax: Any = None, *, which: str = "along") -> tuple[Any, Any]:
        """Log–log scatter of the errors against the amplitude, one colour per weight group,
        with the fitted lines; returns ``(figure, axes)``
        (:func:`nilpotent.viz.simulation.plot_sweep`).

        ``which``: ``"along"`` (errors along the way) or ``"endpoint"``.
        """
        from nilpotent.viz.simulation import plot_sweep

        return plot_sweep(self, ax, which=which)

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
            "tolerance": json_float(self.tolerance),
            "floor": json_float(self.floor),
            "statuses": self.status_counts(),
            "summary": self.summary(),
            "fits": self.fits(),
        }
        if include_samples:
            out["samples"] = {
                "columns": self.columns(),
                "rows": [
                    [json_float(v) if isinstance(v, float) else v for v in row]
                    for row in self.rows()
                ],
            }
        return json_object(out)
