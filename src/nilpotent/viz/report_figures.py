"""Figures made for the paper reproduction that combine several results on one canvas.

:func:`plot_amplitude_panels`: the amplitude study of one model, one log–log
panel per bracket (error of the nilpotent approximation over one period,
privileged coordinates grouped by weight; theory: slope ≥ w + 1, the mathematics
page, §6), drawn with :func:`~nilpotent.viz.scaling.plot_error_scaling`.  Returns
handles, never calls ``plt.show()``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from nilpotent.viz.scaling import plot_error_scaling

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from nilpotent.simulation import ScalingStudy

__all__ = ["plot_amplitude_panels"]


def plot_amplitude_panels(
    studies: Sequence[tuple[tuple[int, int], ScalingStudy]],
    label: str,
    *,
    figsize: tuple[float, float] = (12.0, 4.0),
) -> tuple[Figure, Sequence[Axes]]:
    """One log–log panel of error against amplitude per bracket, sharing the error axis.

    Parameters
    ----------
    studies : sequence of ((i, j), ScalingStudy)
        The bracket ``[X_i, X_j]`` of each panel (1-based input indices) and
        its amplitude study (``nilpotent.scaling``).  Weight
        groups whose slope is ``None`` (errors below the round-off floor: the
        approximation is exact there) are not drawn; a note in the panel names
        them.
    label : str
        The model, for the title (``"eq. vf"``).
    figsize : (float, float)
        Figure size in inches.

    Returns
    -------
    (Figure, sequence of Axes)
        The figure and its panels, in the order of ``studies``.

    Raises
    ------
    ValueError
        ``studies`` is empty.
    """
    from matplotlib.figure import Figure

    if not studies:
        raise ValueError("plot_amplitude_panels needs at least one study")
    fig = Figure(figsize=figsize, layout="constrained")
    axes = fig.subplots(1, len(studies), sharey=True, squeeze=False)[0]
    for ax, (pair, st) in zip(axes, studies, strict=True):
        series = {f"weight {w}": e for w, e in st.errors.items() if st.slopes[w] is not None}
        bounds = {f"weight {w}": float(st.expected_slopes[w]) for w in st.errors}
        plot_error_scaling(
            st.amplitudes, series, lower_bounds=bounds, ax=ax, title=f"[g{pair[0]},g{pair[1]}]"
        )
        exact = [f"weight {w}" for w in st.errors if st.slopes[w] is None]
        if exact:
            ax.text(
                0.02,
                0.02,
                ", ".join(exact) + f": below the noise floor {st.floor:.1g} (exact)",
                transform=ax.transAxes,
                fontsize=7,
            )
    fig.suptitle(
        f"{label}: largest error of the nilpotent approximation over one period "
        "(privileged coordinates by weight; theory: slope ≥ w + 1)"
    )
    return fig, tuple(axes)
