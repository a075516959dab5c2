"""Figures of bracket motions of the trident snake (the paper's Figs 2–7).

* :func:`plot_bracket_motion` — one motion: trajectories of the body centre, the
  three vertices and the three wheels in the plane, the robot drawn at the start
  (faded) and at the end, and the six coordinates against time;
* :func:`plot_motion_comparison` — the same motion for the original fields and for
  the nilpotent approximation overlaid (original solid, approximation dashed and
  drawn above it: the convention of every figure, ``docs/conventions.md``),
  with the coordinate histories side by side.

Trajectories are arrays ``q`` of shape ``(T, 6)`` in the coordinates the
``geometry`` reads (``x, y, θ, φ1, φ2, φ3``); lengths are in the model's units
(units of the body circumradius ``r`` when ``r = 1``), angles in radians.
Functions return ``(figure, axes)`` and never call ``plt.show()``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from nilpotent.errors import OptionError
from nilpotent.models.trident import TridentGeometry
from nilpotent.viz.robot import LEG_COLORS, draw_trident

__all__ = ["COORDINATE_LABELS", "plot_bracket_motion", "plot_motion_comparison"]

#: Axis labels of the six configuration coordinates, with units.
COORDINATE_LABELS = ("x / r", "y / r", "θ (rad)", "φ1 (rad)", "φ2 (rad)", "φ3 (rad)")
_COORD_COLORS = ("#000000", "#777777", "#CC79A7", *LEG_COLORS)


def _check(q: np.ndarray, name: str) -> np.ndarray:
    arr = np.asarray(q, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 6 or arr.shape[0] < 2:
        raise OptionError(f"{name} must have shape (T, 6) with T >= 2, got {arr.shape}")
    return arr


def _trails(
    ax: Axes,
    geometry: TridentGeometry,
    q: np.ndarray,
    *,
    style: str,
    width: float,
    label_suffix: str = "",
    labels: bool = True,
    alpha: float = 1.0,
    zorder: float = 5.0,
) -> None:
    centre = geometry.body_centre(q)
    vertices = geometry.vertices(q)
    wheels = geometry.wheels(q)
    ax.plot(
        centre[:, 0],
        centre[:, 1],
        color="black",
        linestyle=style,
        linewidth=width,
        alpha=alpha,
        label=f"body centre{label_suffix}" if labels else None,
        zorder=zorder,
    )
    for i in range(3):
        ax.plot(
            vertices[:, i, 0],
            vertices[:, i, 1],
            color=LEG_COLORS[i],
            linestyle=style,
            linewidth=0.8 * width,
            alpha=0.6 * alpha,
            label=f"vertex {i + 1}{label_suffix}" if labels else None,
            zorder=zorder,
        )
        ax.plot(
            wheels[:, i, 0],
            wheels[:, i, 1],
            color=LEG_COLORS[i],
            linestyle=style,
            linewidth=width,
            alpha=alpha,
            label=f"wheel {i + 1}{label_suffix}" if labels else None,
            zorder=zorder,
        )


def _frame_plane(ax: Axes, geometry: TridentGeometry, qs: Sequence[np.ndarray]) -> None:
    pts = []
    for q in qs:
        pts += [geometry.wheels(q).reshape(-1, 2), geometry.vertices(q).reshape(-1, 2)]
        pts.append(geometry.body_centre(q))
    allp = np.concatenate(pts)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    pad = 0.25 * max(geometry.r, float((hi - lo).max()) * 0.1)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x / r")
    ax.set_ylabel("y / r")
    ax.grid(True, linewidth=0.3, alpha=0.5)


def plot_bracket_motion(
    q: np.ndarray,
    geometry: TridentGeometry | None = None,
    *,
    times: np.ndarray | None = None,
    title: str | None = None,
    figsize: tuple[float, float] = (10.0, 4.6),
) -> tuple[Figure, tuple[Axes, Axes]]:
    """Trajectories of one bracket motion, robot at start and end (the paper's Figs 2–4).

    Parameters
    ----------
    q:
        ``(T, 6)`` configurations along the motion (the first is the start).
    geometry:
        How to read ``q`` (default ``TridentGeometry()``, ``r = l = 1``).
    times:
        ``(T,)`` times for the right panel (default: the sample index).
    title:
        Figure title.

    Returns
    -------
    (Figure, (Axes, Axes))
        The plane picture and the coordinates against time.
    """
    from matplotlib.figure import Figure

    qq = _check(q, "q")
    geom = geometry if geometry is not None else TridentGeometry()
    fig = Figure(figsize=figsize, layout="constrained")
    ax, axt = fig.subplots(1, 2, width_ratios=(1.25, 1))
    draw_trident(ax, qq[0], geom, alpha=0.35, linestyle=":", label="start")
    draw_trident(ax, qq[-1], geom, alpha=1.0, label="end")
    _trails(ax, geom, qq, style="-", width=1.4)
    _frame_plane(ax, geom, [qq])
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False)
    t = np.arange(qq.shape[0], dtype=float) if times is None else np.asarray(times, float)
    for j in range(6):
        axt.plot(t, qq[:, j] - qq[0, j], color=_COORD_COLORS[j], label=COORDINATE_LABELS[j])
    axt.set_xlabel("t (s)" if times is not None else "sample")
    axt.set_ylabel("q(t) − q(0)  (lengths / r, angles rad)")
    axt.legend(fontsize=7, ncol=2)
    axt.grid(True, linewidth=0.3, alpha=0.5)
    if title:
        fig.suptitle(title)
    return fig, (ax, axt)


def plot_motion_comparison(
    q_original: np.ndarray,
    q_approx: np.ndarray,
    geometry: TridentGeometry | None = None,
    *,
    times: np.ndarray | None = None,
    title: str | None = None,
    figsize: tuple[float, float] = (10.0, 4.6),
) -> tuple[Figure, tuple[Axes, Axes]]:
    """One bracket motion for the original fields and the approximation, overlaid (Figs 5–7).

    The original system's trajectories are solid (wide, light), the approximation's
    dashed and drawn above them, as in every figure of the package
    (:data:`nilpotent.viz.simulation.ORIGINAL_STYLE`); the robot is drawn at the start
    and at both ends.  The right panel shows ``q(t) − q(0)`` for both.

    Parameters
    ----------
    q_original, q_approx:
        ``(T, 6)`` configurations (same times, same start) in the coordinates
        ``geometry`` reads.
    geometry, times, title, figsize:
        As in :func:`plot_bracket_motion`.
    """
    from matplotlib.figure import Figure

    qo = _check(q_original, "q_original")
    qa = _check(q_approx, "q_approx")
    if qo.shape != qa.shape:
        raise OptionError(f"trajectories differ in shape: {qo.shape} and {qa.shape}")
    geom = geometry if geometry is not None else TridentGeometry()
    fig = Figure(figsize=figsize, layout="constrained")
    ax, axt = fig.subplots(1, 2, width_ratios=(1.25, 1))
    draw_trident(ax, qo[0], geom, alpha=0.3, linestyle=":", label="start")
    draw_trident(ax, qo[-1], geom, alpha=0.45, label="end, original")
    draw_trident(ax, qa[-1], geom, alpha=1.0, linestyle="--", body_color="#BBBBBB",
                 label="end, approximation", zorder=6.0)
    _trails(ax, geom, qo, style="-", width=2.4, alpha=0.45, zorder=5.0)
    _trails(ax, geom, qa, style="--", width=1.0, labels=False, zorder=6.0)
    _frame_plane(ax, geom, [qo, qa])
    ax.plot([], [], color="black", linestyle="-", linewidth=2.4, alpha=0.45,
            label="original (solid)")
    ax.plot([], [], color="black", linestyle="--", linewidth=1.0, label="approximation (dashed)")
    ax.legend(fontsize=6.5, loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False)
    t = np.arange(qo.shape[0], dtype=float) if times is None else np.asarray(times, float)
    for j in range(6):
        axt.plot(t, qo[:, j] - qo[0, j], color=_COORD_COLORS[j], linestyle="-", linewidth=2.4,
                 alpha=0.45, zorder=2.0, label=COORDINATE_LABELS[j])
        axt.plot(t, qa[:, j] - qa[0, j], color=_COORD_COLORS[j], linestyle="--",
                 linewidth=1.0, zorder=3.0)
    axt.set_xlabel("t (s)" if times is not None else "sample")
    axt.set_ylabel("q(t) − q(0)  (lengths / r, angles rad)")
    axt.legend(fontsize=7, ncol=2, title="solid: original, dashed: approximation",
               title_fontsize=7)
    axt.grid(True, linewidth=0.3, alpha=0.5)
    if title:
        fig.suptitle(title)
    return fig, (ax, axt)
