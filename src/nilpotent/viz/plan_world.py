"""Figures and animations of a plan among obstacles (a ``GlobalPlan``).

* :func:`plot_plan_world` — left: the world (bounds, obstacles), the
  configuration-space waypoints' positions, the robot's outline at evenly
  spaced times along the re-simulated motion (start and end emphasised) and
  the tracks of its discs/points (the trident snake's wheels) and of the
  position ``(x, y)``; right: the limited coordinates against time with their
  limits (dashed), or, without limits, the first coordinates.
* :func:`animate_plan_world` — the robot moving in the world, written as GIF
  (``PillowWriter``), MP4 (``FFMpegWriter``, needs ffmpeg) or a self-contained
  HTML player (:func:`nilpotent.viz.animation.html_player`).

The outline comes from the model's ``geometry``
(:class:`nilpotent.planning.robot.Robot`); a model without one is drawn as
its path in the plane of the first two coordinates.  Functions return figures
and never call ``plt.show()``.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Circle
from matplotlib.patches import Polygon as PolygonPatch

from nilpotent.errors import OptionError
from nilpotent.planning.robot import Robot

__all__ = ["animate_plan_world", "draw_outline", "draw_world", "plot_plan_world"]

_OBSTACLE = "#7f7f7f"
_ROBOT = "#0072B2"
_TRACKS = ("#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442")


def draw_world(ax: Any, world: Any) -> None:
    """Bounds (a black frame) and obstacles (grey) of a :class:`~nilpotent.planning.world.World`."""
    if world is None:
        return
    if world.bounds is not None:
        (xlo, xhi), (ylo, yhi) = world.bounds
        ax.plot([xlo, xhi, xhi, xlo, xlo], [ylo, ylo, yhi, yhi, ylo], color="black", lw=1.2)
    for poly in world.polygons:
        ax.add_patch(PolygonPatch(np.asarray(poly), closed=True, color=_OBSTACLE, alpha=0.8))
    for centre, radius in world.discs:
        ax.add_patch(Circle(centre, radius, color=_OBSTACLE, alpha=0.8))


def draw_outline(ax: Any, robot: Robot, q: np.ndarray, *, alpha: float = 1.0,
                 color: str = _ROBOT) -> list[Any]:
    """Draw the robot's outline at one configuration; return the artists."""
    pts = robot.points(np.asarray(q, dtype=float)[None, :])
    artists: list[Any] = []
    for poly in pts["polygons"]:
        patch = PolygonPatch(poly[0], closed=True, facecolor=color, edgecolor=color,
                             alpha=0.35 * alpha)
        ax.add_patch(patch)
        artists.append(patch)
    for seg in pts["segments"][0]:
        (line,) = ax.plot(seg[:, 0], seg[:, 1], color=color, lw=1.5, alpha=alpha)
        artists.append(line)
    for centre, radius in zip(pts["discs"][0], pts["radii"][0], strict=True):
        if radius > 0:
            patch = Circle(centre, radius, color=color, alpha=0.5 * alpha)
            ax.add_patch(patch)
            artists.append(patch)
        else:
            (dot,) = ax.plot(*centre, "o", color=color, markersize=3, alpha=alpha)
            artists.append(dot)
    return artists


def _draw_plane(ax: Any, result: Any, snapshots: int) -> None:
    p = result.plan
    states = p.trajectory.states
    names = p.system.coordinate_names
    robot = Robot(p.system, result.limits)
    draw_world(ax, result.world)
    if robot.has_outline:
        idx = np.linspace(0, len(states) - 1, max(2, snapshots)).astype(int)
        for k in idx[1:-1]:
            draw_outline(ax, robot, states[k], alpha=0.25)
        draw_outline(ax, robot, states[0], alpha=0.7, color="black")
        draw_outline(ax, robot, states[-1], alpha=1.0, color=_ROBOT)
        discs = robot.points(states)["discs"]
        for i in range(discs.shape[1]):
            ax.plot(discs[:, i, 0], discs[:, i, 1], color=_TRACKS[i % len(_TRACKS)], lw=0.8,
                    label=f"track of point {i + 1}")
    if states.shape[1] == 1:  # one coordinate: there is no plane, draw it against time
        times = p.trajectory.times
        ax.plot(times, states[:, 0], color="black", lw=1.0, label=names[0])
        ax.plot(times[-1], p.goal[0], "*", color="#D55E00", markersize=12, label="goal")
        ax.set_xlabel("time")
        ax.set_ylabel(names[0])
    else:
        ax.plot(states[:, 0], states[:, 1], color="black", lw=1.0,
                label=f"({names[0]}, {names[1]})")
        way = np.asarray(result.waypoints)
        ax.plot(way[:, 0], way[:, 1], "x", color="#D55E00", markersize=5, label="waypoints")
        ax.plot(*p.goal[:2], "*", color="#D55E00", markersize=12, label="goal")
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1])
        ax.set_aspect("equal", adjustable="datalim")
    title = f"{p.system.name}" + (f" in {result.world.name}" if result.world is not None else "")
    v = result.verification
    if v.clearance is not None:
        title += f"; clearance {v.clearance:.3g}"
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=6, loc="best")


def _draw_limits(ax: Any, result: Any) -> None:
    p = result.plan
    names = p.system.coordinate_names
    t, states = p.trajectory.times, p.trajectory.states
    limited = result.limits.as_dict()
    shown = list(limited) or list(names[2:5] or names[:2])
    for i, name in enumerate(shown):
        color = _TRACKS[i % len(_TRACKS)]
        ax.plot(t, states[:, names.index(name)], color=color, lw=1.2, label=name)
        if name in limited:
            for b in limited[name]:
                ax.axhline(b, color=color, ls="--", lw=0.8)
    ax.set_xlabel("time")
    ax.set_ylabel("coordinate")
    ax.set_title("limited coordinates and their limits (dashed)" if limited
                 else "coordinates (no limits)", fontsize=9)
    ax.legend(fontsize=7, loc="best")


def plot_plan_world(result: Any, snapshots: int = 12) -> Figure:
    """Figure of a global plan: world with outlines and tracks; coordinates against limits."""
    fig = Figure(figsize=(12, 5), layout="constrained")
    ax_plane, ax_lim = fig.subplots(1, 2, width_ratios=(3, 2))
    _draw_plane(ax_plane, result, snapshots)
    _draw_limits(ax_lim, result)
    return fig


def animate_plan_world(
    result: Any, path: str | Path, kind: str | None = None, *, frames: int = 80,
    fps: float = 15.0, dpi: int = 80,
) -> int:
    """Write an animation of the robot moving along the plan; return the number of frames.

    ``kind``: ``".gif"``, ``".mp4"`` or ``".html"`` (default: the suffix of ``path``).

    Raises
    ------
    OptionError
        Unknown kind, or ``.mp4`` without ffmpeg.
    """
    from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter

    from nilpotent.viz.animation import html_player

    kind = (kind or Path(path).suffix).lower()
    if kind not in (".gif", ".mp4", ".html"):
        raise OptionError(f"unknown animation type {kind!r} (use .gif, .mp4 or .html)")
    if kind == ".mp4" and not FFMpegWriter.isAvailable():
        raise OptionError("writing .mp4 needs ffmpeg (use .gif or .html)")
    p = result.plan
    states = p.trajectory.states
    idx = np.linspace(0, len(states) - 1, max(2, frames)).astype(int)
    robot = Robot(p.system, result.limits)
    fig = Figure(figsize=(6, 5), layout="constrained")
    ax = fig.subplots()
    draw_world(ax, result.world)
    ax.plot(states[:, 0], states[:, 1], color="black", lw=0.6, alpha=0.5)
    pts = robot.points(states) if robot.has_outline else None
    lo = states[:, :2].min(axis=0) - 1.5
    hi = states[:, :2].max(axis=0) + 1.5
    if pts is not None and pts["discs"].size:
        lo = np.minimum(lo, pts["discs"].reshape(-1, 2).min(axis=0) - 0.3)
        hi = np.maximum(hi, pts["discs"].reshape(-1, 2).max(axis=0) + 0.3)
    if result.world is not None and result.world.bounds is not None:
        (xlo, xhi), (ylo, yhi) = result.world.bounds
        lo, hi = np.array([xlo, ylo]) - 0.2, np.array([xhi, yhi]) + 0.2
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    drawn: list[Any] = []
    (marker,) = ax.plot([], [], "o", color="black", markersize=3)

    def update(k: int) -> list[Any]:
        for a in drawn:
            a.remove()
        drawn.clear()
        q = states[idx[k]]
        if robot.has_outline:
            drawn.extend(draw_outline(ax, robot, q))
        marker.set_data([q[0]], [q[1]])
        ax.set_title(f"{p.system.name}: t = {p.trajectory.times[idx[k]]:.3g}", fontsize=9)
        return [*drawn, marker]

    if kind in (".gif", ".mp4"):
        anim = FuncAnimation(fig, update, frames=len(idx), blit=False)
        # matplotlib's stubs say int; the writers take any positive frame rate
        writer = (
            PillowWriter(fps=fps)  # pyright: ignore[reportArgumentType]
            if kind == ".gif"
            else FFMpegWriter(fps=fps)  # pyright: ignore[reportArgumentType]
        )
        anim.save(str(path), writer=writer, dpi=dpi)
    else:
        images = []
        for k in range(len(idx)):
            update(k)
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=dpi)
            images.append(buf.getvalue())
        Path(path).write_text(html_player(images, title=f"plan of {p.system.name}", fps=fps),
                              encoding="utf-8")
    return len(idx)
