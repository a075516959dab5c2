"""Figures of simulation results: trajectories, comparisons, scaling studies, sweeps.

The ``.plot()`` methods of :class:`~nilpotent.simulation.Trajectory`,
:class:`~nilpotent.simulation.Comparison`,
:class:`~nilpotent.simulation.ScalingStudy` and
:class:`~nilpotent.simulation.SweepResult` delegate here.  Figures are
:class:`matplotlib.figure.Figure` objects built without pyplot (headless,
nothing is shown); each function returns ``(figure, axes)``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from nilpotent.errors import OptionError
from nilpotent.numeric.fits import loglog_line

__all__ = [
    "APPROXIMATION_STYLE",
    "ORIGINAL_STYLE",
    "error_floor",
    "plot_comparison",
    "plot_scaling_study",
    "plot_sweep",
    "plot_trajectory",
    "style_legend",
]


def _figure_axes(ax: Any) -> tuple[Any, Any]:
    if ax is not None:
        return ax.figure, ax
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
    return fig, fig.add_subplot(1, 1, 1)


ORIGINAL_STYLE = {"linestyle": "-", "linewidth": 2.8, "alpha": 0.45, "zorder": 2.0}
"""How the original system is drawn in every figure (solid, wide and light, below)."""
APPROXIMATION_STYLE = {"linestyle": "--", "linewidth": 1.2, "zorder": 3.0}
"""How the nilpotent approximation is drawn in every figure (dashed, above the original so
that it stays visible where the two agree): the convention of ``docs/conventions.md``."""
STATE_LABEL = "coordinate value (model units; angles in rad)"
"""The y-label of coordinates against time (models carry no units of their own)."""


def style_legend(ax: Any, **kwargs: Any) -> Any:
    """A legend with the line-style convention stated: the labelled lines, then
    ``original (solid)`` and ``approximation (dashed)`` in black."""
    ax.plot([], [], color="black", label="original (solid)", **ORIGINAL_STYLE)
    ax.plot([], [], color="black", label="approximation (dashed)", **APPROXIMATION_STYLE)
    return ax.legend(**{"loc": "best", "fontsize": "small", **kwargs})


def error_floor(tolerance: float | None, default: float = 1e-12) -> float:
    """The lowest value an error axis shows: the integration tolerance (errors below it
    are integration noise, not the approximation's), ``default`` when it is unknown."""
    if tolerance is None or not np.isfinite(tolerance) or tolerance <= 0:
        return default
    return float(tolerance)


def plot_trajectory(traj: Any, ax: Any = None) -> tuple[Any, Any]:
    """Every coordinate of a :class:`~nilpotent.simulation.Trajectory` against time."""
    fig, ax = _figure_axes(ax)
    n = traj.states.shape[1]
    names = traj.coordinates or tuple(f"x{k + 1}" for k in range(n))
    for k, name in enumerate(names):
        ax.plot(traj.times, traj.states[:, k], label=name)
    ax.set_xlabel("time t (model time units)")
    ax.set_ylabel(STATE_LABEL)
    ax.set_title(traj.system or "trajectory")
    ax.legend(loc="best", fontsize="small")
    return fig, ax


def plot_comparison(comp: Any, fig: Any = None) -> tuple[Any, Any]:
    """Both trajectories of a :class:`~nilpotent.simulation.Comparison` (model
    coordinates) and the error per weight group against time.

    The original is solid, the approximation dashed and drawn above it
    (:data:`ORIGINAL_STYLE`, :data:`APPROXIMATION_STYLE`); the error axis starts at
    the integration tolerance (:func:`error_floor`).

    Returns ``(figure, (ax_states, ax_errors))``.
    """
    from matplotlib.figure import Figure

    from nilpotent.simulation.pair import weight_groups

    fig = fig if fig is not None else Figure(figsize=(10, 4.2), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    for k, name in enumerate(comp.system.coordinate_names):
        (line,) = ax1.plot(comp.times, comp.original[:, k], label=f"{name}", **ORIGINAL_STYLE)
        ax1.plot(comp.times, comp.approximate[:, k], color=line.get_color(),
                 **APPROXIMATION_STYLE)
    ax1.set_xlabel("time t (model time units)")
    ax1.set_ylabel(STATE_LABEL)
    ax1.set_title(f"{comp.system.name}: bracket motion [X{comp.bracket[0]},X{comp.bracket[1]}]")
    style_legend(ax1, fontsize="x-small", ncol=2 if comp.system.n > 3 else 1)
    diff = np.abs(comp.original_y - comp.approximate_y)
    floor = error_floor(comp.tolerance)
    for w, idx in weight_groups(comp.weights):
        err = diff[:, list(idx)].max(axis=1)
        ax2.semilogy(comp.times, np.maximum(err, floor), label=f"weight {w}")
    ax2.axhline(floor, color="gray", linestyle=":", linewidth=0.8,
                label=f"integration tolerance {floor:.0e}")
    ax2.set_ylim(bottom=floor / 2)
    ax2.set_xlabel("time t (model time units)")
    ax2.set_ylabel("|y − ŷ| (privileged coordinates, max in the group)")
    ax2.set_title(f"error per weight group, A = {comp.amplitude:g}")
    ax2.legend(loc="best", fontsize="small")
    return fig, (ax1, ax2)


def plot_scaling_study(study: Any, ax: Any = None) -> tuple[Any, Any]:
    """Log–log errors of a :class:`~nilpotent.simulation.ScalingStudy` per weight group,
    with the fitted lines."""
    fig, ax = _figure_axes(ax)
    a = study.amplitudes
    for w, err in study.errors.items():
        shown = np.where(err > 0, err, np.nan)
        (line,) = ax.loglog(a, shown, "o", label=f"weight {w}")
        slope = study.slopes[w]
        if slope is not None:
            keep = err > study.floor
            coef = loglog_line(a[keep], err[keep])
            ax.loglog(a, np.exp(np.polyval(coef, np.log(a))), "-", color=line.get_color(),
                      label=f"fit slope {slope:.2f} (expected {study.expected_slopes[w]})")
    ax.set_xlabel("amplitude A")
    ax.set_ylabel("max |y − ŷ| in the group")
    ax.set_title(f"{study.system.name}: bracket [X{study.bracket[0]},X{study.bracket[1]}]")
    ax.legend(loc="best", fontsize="small")
    return fig, ax


def plot_sweep(result: Any, ax: Any = None, *, which: str = "along") -> tuple[Any, Any]:
    """Log–log scatter of a :class:`~nilpotent.simulation.SweepResult`'s errors against the
    amplitude, one colour per weight group.

    ``which``: ``"along"`` (errors along the way) or ``"endpoint"``.  The
    fitted line of each (parameter set, bracket, weight) is drawn over the
    successful samples above the noise floor.
    """
    if which not in ("along", "endpoint"):
        raise OptionError(f"which must be 'along' or 'endpoint', got {which!r}")
    fig, ax = _figure_axes(ax)
    errors = result.along_by_weight if which == "along" else result.endpoint_by_weight
    key = "slopes" if which == "along" else "endpoint_slopes"
    fits = {(tuple(f["parameters"].items()), tuple(f["bracket"])): f for f in result.fits()}
    for w in result.groups:
        err = errors[w]
        keep = result.ok & np.isfinite(err) & (err > result.floor)
        (dots,) = ax.loglog(result.amplitude[keep], err[keep], ".", alpha=0.5,
                            label=f"weight {w}")
        for k, pset in enumerate(result.parameter_sets):
            for br in result.parameters.brackets:
                fit = fits.get((tuple(pset.items()), br))
                slope = None if fit is None else fit[key].get(str(w))
                rows = keep & (result.parameter_index == k) & (result.bracket[:, 0] == br[0]) & (
                    result.bracket[:, 1] == br[1])
                if slope is None or np.unique(result.amplitude[rows]).size < 2:
                    continue
                coef = loglog_line(result.amplitude[rows], err[rows])
                a = np.geomspace(result.amplitude[rows].min(), result.amplitude[rows].max(), 20)
                ax.loglog(a, np.exp(np.polyval(coef, np.log(a))), "-",
                          color=dots.get_color(), label=f"slope {slope:.2f} (w + 1 = {w + 1})")
    ax.set_xlabel("amplitude A")
    ax.set_ylabel("|y − ŷ| in the group" + (" (max along the way)" if which == "along"
                                              else " (end point)"))
    ax.set_title(f"{result.parameters.model}: {len(result)} bracket motions")
    ax.legend(loc="best", fontsize="small")
    return fig, ax
