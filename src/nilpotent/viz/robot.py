"""Drawing the trident snake robot: body triangle, legs and wheels at one configuration.

Positions come from :class:`nilpotent.models.trident.TridentGeometry` (world
frame, lengths in the model's units; with ``r = 1`` every length is in units
of the body's circumradius ``r``).  Each wheel pair is drawn as a short thick
bar along its leg — the direction it rolls in — so that sideways slip is
visible as motion across the bar.

Functions return the matplotlib artists they create and never call
``plt.show()``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.lines import Line2D
from matplotlib.patches import Polygon

from nilpotent.models.trident import TridentGeometry
from nilpotent.numeric.types import State

__all__ = ["LEG_COLORS", "TridentArtists", "draw_trident", "update_trident"]

#: One colour per leg / wheel (colour-blind-safe Okabe–Ito), body centre in black.
LEG_COLORS: tuple[str, str, str] = ("#0072B2", "#D55E00", "#009E73")
_WHEEL_LENGTH = 0.35  # in units of r


@dataclass(frozen=True)
class TridentArtists:
    """The artists of one drawn robot (update them with :func:`update_trident`)."""

    body: Polygon
    legs: tuple[Line2D, Line2D, Line2D]
    wheels: tuple[Line2D, Line2D, Line2D]
    centre: Line2D

    def all(self) -> tuple[Artist, ...]:
        return (self.body, *self.legs, *self.wheels, self.centre)


def _parts(geometry: TridentGeometry, q: Sequence[float] | State) -> tuple[np.ndarray, ...]:
    qq = np.asarray(q, dtype=float)
    vertices = geometry.vertices(qq)
    wheels = geometry.wheels(qq)
    direction = geometry.leg_directions(qq)
    half = 0.5 * _WHEEL_LENGTH * geometry.r * direction
    return qq[0:2], vertices, wheels, wheels - half, wheels + half


def draw_trident(
    ax: Axes,
    q: Sequence[float],
    geometry: TridentGeometry | None = None,
    *,
    alpha: float = 1.0,
    body_color: str = "#999999",
    linestyle: str = "-",
    zorder: float = 3.0,
    label: str | None = None,
) -> TridentArtists:
    """Draw the robot at configuration ``q = (x, y, θ, φ1, φ2, φ3)`` on ``ax``.

    Parameters
    ----------
    ax:
        The axes to draw on (equal aspect is the caller's choice).
    q:
        One configuration (6 numbers) in the coordinates ``geometry`` reads.
    geometry:
        Body circumradius, leg length and leg offsets; default ``TridentGeometry()``
        (``r = l = 1``, legs at ``0, 2π/3, 4π/3``).
    alpha, body_color, linestyle, zorder:
        Styling (a faded robot marks the start of a motion).
    label:
        Legend label for the body.

    Returns
    -------
    TridentArtists
        The body polygon, three leg lines, three wheel bars and the centre marker.
    """
    geom = geometry if geometry is not None else TridentGeometry()
    centre, vertices, _wheels, w0, w1 = _parts(geom, q)
    body = Polygon(
        vertices,
        closed=True,
        facecolor=body_color,
        edgecolor="black",
        alpha=0.35 * alpha + 0.15,
        linestyle=linestyle,
        zorder=zorder,
        label=label,
    )
    ax.add_patch(body)
    legs = []
    wheels = []
    for i in range(3):
        (leg,) = ax.plot(
            [vertices[i, 0], _wheels[i, 0]],
            [vertices[i, 1], _wheels[i, 1]],
            color="black",
            linewidth=1.6,
            alpha=alpha,
            linestyle=linestyle,
            zorder=zorder + 0.1,
        )
        (wheel,) = ax.plot(
            [w0[i, 0], w1[i, 0]],
            [w0[i, 1], w1[i, 1]],
            color=LEG_COLORS[i],
            linewidth=5.0,
            solid_capstyle="round",
            alpha=alpha,
            zorder=zorder + 0.2,
        )
        legs.append(leg)
        wheels.append(wheel)
    (mark,) = ax.plot(
        [centre[0]],
        [centre[1]],
        marker="+",
        color="black",
        markersize=8,
        alpha=alpha,
        zorder=zorder + 0.3,
        linestyle="none",
    )
    return TridentArtists(
        body, (legs[0], legs[1], legs[2]), (wheels[0], wheels[1], wheels[2]), mark
    )


def update_trident(
    artists: TridentArtists, q: Sequence[float] | State, geometry: TridentGeometry | None = None
) -> TridentArtists:
    """Move already-drawn robot artists to configuration ``q`` (for animations)."""
    geom = geometry if geometry is not None else TridentGeometry()
    centre, vertices, wheels, w0, w1 = _parts(geom, q)
    artists.body.set_xy(vertices)
    for i in range(3):
        artists.legs[i].set_data([vertices[i, 0], wheels[i, 0]], [vertices[i, 1], wheels[i, 1]])
        artists.wheels[i].set_data([w0[i, 0], w1[i, 0]], [w0[i, 1], w1[i, 1]])
    artists.centre.set_data([centre[0]], [centre[1]])
    return artists
