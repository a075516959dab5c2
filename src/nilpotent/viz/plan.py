"""Figures and animations of a :class:`~nilpotent.planning.iterative.Plan`
(:meth:`Plan.plot <nilpotent.planning.iterative.Plan.plot>` delegates here).

For the trident snake forms the robot is drawn with
:func:`nilpotent.viz.robot.draw_trident` (geometry from
:meth:`nilpotent.models.trident.TridentGeometry.from_system`): start (faded),
goal (dashed) and the reached configuration, with the trails of the body
centre and of the three wheels.  For other models the path is drawn in the
plane of the first two coordinates.  Beside it: the error after each
iteration (log scale) and the inputs against time.

Functions return figure handles and never call ``plt.show()``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

if TYPE_CHECKING:
    from matplotlib.artist import Artist

    from nilpotent.planning.iterative import Plan

_TRIDENT_FORMS = ("trident-snake", "trident-snake-paper", "trident-snake-joints")


def _geometry(plan: Plan):
    if plan.system.name not in _TRIDENT_FORMS:
        return None
    from nilpotent.models.trident import TridentGeometry

    return TridentGeometry.from_system(plan.system)


def _draw_plane(ax, plan: Plan, geometry) -> None:
    states = plan.trajectory.states
    names = plan.system.coordinate_names
    if geometry is None and states.shape[1] == 1:  # one coordinate: it against time
        times = plan.trajectory.times
        ax.plot(times, states[:, 0], color="#0072B2", lw=1.5, label="path")
        ax.plot(times[0], plan.start[0], "o", color="black", label="start")
        ax.plot(times[-1], plan.goal[0], "*", color="#D55E00", markersize=12, label="goal")
        ax.set_xlabel("t")
        ax.set_ylabel(names[0])
        ax.legend(fontsize=7, loc="best")
        return
    if geometry is None:
        ax.plot(states[:, 0], states[:, 1], color="#0072B2", lw=1.5, label="path")
        ax.plot(*plan.start[:2], "o", color="black", label="start")
        ax.plot(*plan.goal[:2], "*", color="#D55E00", markersize=12, label="goal")
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1] if len(names) > 1 else "")
    else:
        from nilpotent.viz.robot import LEG_COLORS, draw_trident

        wheels = geometry.wheels(states)
        ax.plot(states[:, 0], states[:, 1], color="black", lw=1.0, label="centre")
        for i in range(3):
            ax.plot(wheels[:, i, 0], wheels[:, i, 1], color=LEG_COLORS[i], lw=0.8,
                    label=f"wheel {i + 1}")
        draw_trident(ax, plan.start, geometry, alpha=0.35, label="start")
        draw_trident(ax, plan.goal, geometry, alpha=0.6, linestyle="--", body_color="#D55E00",
                     label="goal")
        draw_trident(ax, plan.reached, geometry, label="reached")
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1])
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=7, loc="best")


def plot_plan(plan: Plan) -> Figure:
    """The figure of a plan: :func:`nilpotent.viz.plan_world.plot_plan_world` (the one plan
    figure, also behind ``nilpotent plan --plot`` and ``GlobalPlan.plot()``)."""
    from nilpotent.viz.plan_world import plot_plan_world

    return plot_plan_world(plan)


def animate_plan(plan: Plan, path: str | Path, *, frames: int = 60, fps: float = 12.0,
                 dpi: int = 80) -> Path:
    """Write a GIF (matplotlib's ``PillowWriter``) of the system moving along the plan."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    geometry = _geometry(plan)
    states = plan.trajectory.states
    idx = np.unique(np.linspace(0, len(states) - 1, max(2, frames)).round().astype(int))
    fig = Figure(figsize=(5.5, 5), layout="constrained")
    ax = fig.subplots()
    _draw_plane(ax, plan, geometry)
    ax.set_title(f"{plan.system.name}: plan (error {plan.error:.1e})")
    if geometry is not None:
        from nilpotent.viz.robot import draw_trident, update_trident

        moving = draw_trident(ax, states[0], geometry, body_color="#0072B2", zorder=5)

        def update(k: int) -> tuple[Artist, ...]:
            update_trident(moving, states[idx[k]], geometry)
            return ()
    else:
        (dot,) = ax.plot([states[0, 0]], [states[0, 1]], "o", color="#D55E00", zorder=5)

        def update(k: int) -> tuple[Artist, ...]:
            dot.set_data([states[idx[k], 0]], [states[idx[k], 1]])
            return (dot,)

    anim = FuncAnimation(fig, update, frames=len(idx), interval=1000 / fps, blit=False)
    target = Path(path)
    # matplotlib's stubs say int; PillowWriter takes any positive frame rate
    anim.save(target, writer=PillowWriter(fps=fps), dpi=dpi)  # pyright: ignore[reportArgumentType]
    return target
