"""Figures and animations of a plan among obstacles (a ``GlobalPlan``).

* :func:`plot_plan_world` — the one figure of a plan, behind ``nilpotent plan
  --plot``, :meth:`GlobalPlan.plot <nilpotent.planning.global_planner.GlobalPlan.plot>`
  and :meth:`Plan.plot <nilpotent.planning.iterative.Plan.plot>`.  Left: the
  world (bounds, obstacles), the configuration-space waypoints' positions, the
  robot's outline at evenly spaced times along the re-simulated motion (start
  and end emphasised) and the tracks of its discs/points (the trident snake's
  wheels) and of the position ``(x, y)``; middle: the limited coordinates
  against time with their limits (dotted), or, without limits, the first
  coordinates; right: the inputs against time (segment boundaries in grey).
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

__all__ = [
    "animate_plan_world", "draw_marker", "draw_outline", "draw_world", "frame_motion",
    "plot_plan_world",
]

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


_HEADINGS = ("theta", "θ", "yaw", "heading", "psi", "theta0")


def _heading(system: Any) -> int | None:
    """Index of the heading angle of a model without an outline (``theta`` of the
    unicycle), which is drawn as an arrowhead; ``None`` where there is none."""
    names = system.coordinate_names
    if len(names) >= 3 and names[2].lower() in _HEADINGS:
        return 2
    return None


def draw_marker(ax: Any, q: np.ndarray, heading: int | None, size: float, *,
                color: str = _ROBOT, alpha: float = 1.0) -> Any:
    """A robot without an outline at ``q``: an arrowhead of length ``size`` (model length
    units) pointing along the heading angle, or a dot where the model has none."""
    if heading is None:
        (dot,) = ax.plot([q[0]], [q[1]], "o", color=color, markersize=6, alpha=alpha,
                         zorder=5)
        return dot
    a = float(q[heading])
    tip = np.array([np.cos(a), np.sin(a)])
    side = np.array([-tip[1], tip[0]])
    centre = np.asarray(q[:2], dtype=float)
    points = np.array([centre + size * 0.6 * tip, centre - size * 0.4 * tip + size * 0.3 * side,
                       centre - size * 0.4 * tip - size * 0.3 * side])
    patch = PolygonPatch(points, closed=True, facecolor=color, edgecolor="black", lw=0.6,
                         alpha=alpha, zorder=5)
    ax.add_patch(patch)
    return patch


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
    elif states.shape[1] >= 2:  # no outline: the robot as an arrowhead along its heading
        lo, hi = frame_motion(states, None)
        size = 0.06 * float((hi - lo).max())
        heading = _heading(p.system)
        idx = np.linspace(0, len(states) - 1, max(2, snapshots)).astype(int)
        for k in idx[1:-1]:
            draw_marker(ax, states[k], heading, size, alpha=0.35)
        draw_marker(ax, states[0], heading, size, color="black", alpha=0.7)
        draw_marker(ax, states[-1], heading, size)
    if states.shape[1] == 1:  # one coordinate: there is no plane, draw it against time
        times = p.trajectory.times
        ax.plot(times, states[:, 0], color="black", lw=1.0, label=names[0])
        ax.plot(times[-1], p.goal[0], "*", color="#D55E00", markersize=12, label="goal")
        ax.set_xlabel("time t (model time units)")
        ax.set_ylabel(f"{names[0]} (model units)")
    else:
        ax.plot(states[:, 0], states[:, 1], color="black", lw=1.0,
                label=f"({names[0]}, {names[1]})")
        way = np.asarray(result.waypoints)
        ax.plot(way[:, 0], way[:, 1], "x", color="#D55E00", markersize=5, label="waypoints")
        ax.plot(*p.goal[:2], "*", color="#D55E00", markersize=12, label="goal")
        ax.set_xlabel(f"{names[0]} (model length units)")
        ax.set_ylabel(f"{names[1]} (model length units)")
        ax.set_aspect("equal", adjustable="datalim")
    title = f"{p.system.name}" + (f" in {result.world.name}" if result.world is not None else "")
    v = result.verification
    if v is not None and v.clearance is not None:
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
                ax.axhline(b, color=color, ls=":", lw=0.8)
    ax.set_xlabel("time t (model time units)")
    ax.set_ylabel("coordinate value (model units; angles in rad)")
    ax.set_title("limited coordinates and their limits (dotted)" if limited
                 else "coordinates (no limits)", fontsize=9)
    ax.legend(fontsize=7, loc="best")


class _LocalPlan:
    """A :class:`~nilpotent.planning.iterative.Plan` seen as a plan in an empty world."""

    def __init__(self, plan: Any) -> None:
        from nilpotent.core.model.outline import Limits

        self.plan = plan
        self.world = None
        self.limits = Limits()
        self.waypoints = (tuple(plan.start), tuple(plan.goal))
        self.verification = None


def _as_global(result: Any) -> Any:
    return result if hasattr(result, "plan") else _LocalPlan(result)


def _draw_inputs(ax: Any, plan: Any) -> None:
    from nilpotent.numeric.signals import Signal

    if plan.segments:
        t = np.linspace(0.0, plan.duration, 600)
        signal = Signal.from_segments(plan.segments)  # the one control evaluator
        u = np.array([signal.evaluate(s) for s in t])
        for i in range(u.shape[1]):
            ax.plot(t, u[:, i], lw=1.0, label=f"u{i + 1}")
        edges = np.cumsum([s.duration for s in plan.segments])[:-1]
        if len(edges) <= 200:
            for e in edges:
                ax.axvline(e, color="gray", lw=0.3, alpha=0.6)
        ax.legend(fontsize=7, loc="best")
    ax.set_xlabel("time t (model time units)")
    ax.set_ylabel("input u_i (model units per time unit)")
    ax.set_title(f"inputs ({len(plan.segments)} segments)", fontsize=9)


def plot_plan_world(result: Any, snapshots: int = 12) -> Figure:
    """The figure of a plan: the motion in its world, coordinates against limits, inputs.

    The one plan figure of the package: ``nilpotent plan --plot``,
    :meth:`GlobalPlan.plot <nilpotent.planning.global_planner.GlobalPlan.plot>` and
    :meth:`Plan.plot <nilpotent.planning.iterative.Plan.plot>` all draw it.

    Parameters
    ----------
    result : GlobalPlan or Plan
        A plan among obstacles (:func:`nilpotent.plan`) or a local plan
        (:func:`nilpotent.steer`, drawn in an empty world without limits).
    snapshots : int
        Outlines of the robot drawn along the motion (start and end included).

    Returns
    -------
    matplotlib.figure.Figure
        Three panels (``fig.axes``): the plane, the coordinates, the inputs.
    """
    result = _as_global(result)
    fig = Figure(figsize=(15, 4.8), layout="constrained")
    ax_plane, ax_lim, ax_u = fig.subplots(1, 3, width_ratios=(3, 2, 2))
    _draw_plane(ax_plane, result, snapshots)
    _draw_limits(ax_lim, result)
    _draw_inputs(ax_u, result.plan)
    return fig


def frame_motion(states: np.ndarray, robot: Robot | None) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners of a view framing the motion: the positions and every
    point of the robot's outline along it, padded by a tenth of the extent."""
    pts = [states[:, :2]]
    if robot is not None and robot.has_outline:
        drawn = robot.points(states)
        for poly in drawn["polygons"]:
            pts.append(np.asarray(poly).reshape(-1, 2))
        if drawn["segments"].size:
            pts.append(np.asarray(drawn["segments"]).reshape(-1, 2))
        if drawn["discs"].size:
            radii = np.asarray(drawn["radii"]).reshape(-1, 1)
            centres = np.asarray(drawn["discs"]).reshape(-1, 2)
            pts += [centres - radii, centres + radii]
    allp = np.concatenate(pts)
    allp = allp[np.all(np.isfinite(allp), axis=1)]
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    extent = float(max((hi - lo).max(), 1e-9))
    pad = 0.1 * extent
    centre = (lo + hi) / 2
    half = np.maximum((hi - lo) / 2, 0.25 * extent) + pad  # neither side thinner than
    return centre - half, centre + half  # half the other: a straight path stays visible


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
    result = _as_global(result)
    p = result.plan
    states = p.trajectory.states
    idx = np.linspace(0, len(states) - 1, max(2, frames)).astype(int)
    robot = Robot(p.system, result.limits)
    fig = Figure(figsize=(6, 5), layout="constrained")
    ax = fig.subplots()
    draw_world(ax, result.world)
    ax.plot(states[:, 0], states[:, 1], color="black", lw=0.6, alpha=0.5)
    lo, hi = frame_motion(states, robot)
    if result.world is not None and result.world.bounds is not None:
        (xlo, xhi), (ylo, yhi) = result.world.bounds
        lo, hi = np.array([xlo, ylo]) - 0.2, np.array([xhi, yhi]) + 0.2
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel(f"{p.system.coordinate_names[0]} (model length units)")
    ax.set_ylabel(f"{p.system.coordinate_names[1]} (model length units)")
    drawn: list[Any] = []
    (marker,) = ax.plot([], [], "o", color="black", markersize=3)
    (trail,) = ax.plot([], [], color=_ROBOT, lw=1.6)  # the way travelled so far
    heading = _heading(p.system)
    size = 0.06 * float((hi - lo).max())

    def update(k: int) -> list[Any]:
        for a in drawn:
            a.remove()
        drawn.clear()
        q = states[idx[k]]
        if robot.has_outline:
            drawn.extend(draw_outline(ax, robot, q))
        else:
            drawn.append(draw_marker(ax, q, heading, size))
        trail.set_data(states[: idx[k] + 1, 0], states[: idx[k] + 1, 1])
        marker.set_data([q[0]], [q[1]])
        ax.set_title(f"{p.system.name}: t = {p.trajectory.times[idx[k]]:.3g}", fontsize=9)
        return [*drawn, marker, trail]

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
