"""The singular set of the paper's simplified trident snake (eq. ``vf``).

Where the determinant of the frame ``(g1, g2, g3, [g1,g2], [g2,g3], [g1,g3])``
vanishes (:func:`nilpotent.models.trident.paper_singular_determinant`, a
function of ``x4, x5, x6`` only) the growth vector drops below ``(3, 6)``.
:func:`plot_paper_singular_set` draws that zero set in the ``(x4, x5)`` plane
for a few values of ``x6``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from nilpotent.models.trident import paper_singular_determinant

__all__ = ["DEFAULT_SLICES", "plot_paper_singular_set"]

#: Values of ``x6`` (rad) shown by default, with their labels.
DEFAULT_SLICES: tuple[tuple[float, str], ...] = (
    (0.0, "0"),
    (np.pi / 3, "π/3"),
    (2 * np.pi / 3, "2π/3"),
    (np.pi, "π"),
)


def plot_paper_singular_set(
    slices: Sequence[tuple[float, str]] = DEFAULT_SLICES,
    *,
    resolution: int = 241,
    figsize: tuple[float, float] = (10.0, 3.2),
) -> tuple[Figure, tuple[Axes, ...]]:
    """Zero set of the frame determinant of eq. vf in ``(x4, x5) ∈ [−π, π]²``, one panel per ``x6``.

    The sign of the determinant is shaded (two colours), the zero set is drawn
    in black and the origin (the paper's base point) is marked.

    Returns
    -------
    (Figure, tuple of Axes)
    """
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure

    grid = np.linspace(-np.pi, np.pi, resolution)
    x4, x5 = np.meshgrid(grid, grid, indexing="xy")
    fig = Figure(figsize=figsize, layout="constrained")
    axes = fig.subplots(1, len(slices), sharey=True, squeeze=False)[0]
    cmap = ListedColormap(["#F0E442", "#56B4E9"])
    for ax, (x6, label) in zip(axes, slices, strict=True):
        q = np.zeros((*x4.shape, 6))
        q[..., 3], q[..., 4], q[..., 5] = x4, x5, x6
        det = paper_singular_determinant(q)
        ax.contourf(x4, x5, np.sign(det), levels=[-1.5, 0, 1.5], cmap=cmap, alpha=0.6)
        ax.contour(x4, x5, det, levels=[0.0], colors="black", linewidths=1.2)
        ax.plot([0], [0], marker="o", color="#D55E00", markersize=5)
        ax.set_title(f"x6 = {label}", fontsize=9)
        ax.set_xlabel("x4 = φ1 (rad)")
        ax.set_aspect("equal")
        ticks = [-np.pi, -np.pi / 2, 0, np.pi / 2, np.pi]
        ax.set_xticks(ticks, ["−π", "−π/2", "0", "π/2", "π"])
        ax.set_yticks(ticks, ["−π", "−π/2", "0", "π/2", "π"])
    axes[0].set_ylabel("x5 = φ2 (rad)")
    fig.suptitle(
        "eq. vf: singular set (black) where the frame determinant vanishes; "
        "shading = its sign; dot = origin",
        fontsize=9,
    )
    return fig, tuple(axes)
