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

__all__ = ["plot_comparison", "plot_scaling_study", "plot_sweep", "plot_trajectory"]


def _figure_axes(ax: Any) -> tuple[Any, Any]:
    if ax is not None:
        return ax.figure, ax
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
    return fig, fig.add_subplot(1, 1, 1)


def plot_trajectory(traj: Any, ax: Any = None) -> tuple[Any, Any]:
    """Every coordinate of a :class:`~nilpotent.simulation.Trajectory` against time."""
    fig, ax = _figure_axes(ax)
    n = traj.states.shape[1]
    names = traj.coordinates or tuple(f"x{k + 1}" for k in range(n))
    for k, name in enumerate(names):
        ax.plot(traj.times, traj.states[:, k], label=name)
    ax.set_xlabel("t")
    ax.set_ylabel("state")
    ax.set_title(traj.system or "trajectory")
    ax.legend(loc="best", fontsize="small")
    return fig, ax


def plot_comparison(comp: Any, fig: Any = None) -> tuple[Any, Any]:
    """Both trajectories of a :class:`~nilpotent.simulation.Comparison` (model
    coordinates) and the error per weight group against time.

    Returns ``(figure, (ax_states, ax_errors))``.
    """
    from matplotlib.figure import Figure

    from nilpotent.simulation.pair import weight_groups

    fig = fig if fig is not None else Figure(figsize=(10, 4.2), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    for k, name in enumerate(comp.system.coordinate_names):
        (line,) = ax1.plot(comp.times, comp.original[:, k], label=f"{name}")
        ax1.plot(comp.times, comp.approximate[:, k], "--", color=line.get_color())
    ax1.set_xlabel("t")
    ax1.set_title(f"{comp.system.name}: original (solid), approximation (dashed)")
    ax1.legend(loc="best", fontsize="small")
    diff = np.abs(comp.original_y - comp.approximate_y)
    for w, idx in weight_groups(comp.weights):
        err = diff[:, list(idx)].max(axis=1)
        ax2.semilogy(comp.times, np.maximum(err, 1e-17), label=f"weight {w}")
    ax2.set_xlabel("t")
    ax2.set_title(f"|y − ŷ| per weight group, A = {comp.amplitude:g}")
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
