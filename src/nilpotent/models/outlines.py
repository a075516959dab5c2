r"""Outlines and default joint limits of the built-in robots (for planning among obstacles).

**Trident snake** (all three forms; the mathematics page, §8).  Body: the equilateral
triangle of circumradius ``r`` with vertices
``V_i = (x, y) + r (cos(θ+α_i), sin(θ+α_i))``; legs: the segments
``V_i → W_i``, ``W_i = V_i + l (cos ψ_i, sin ψ_i)``, ``ψ_i = θ + α_i + φ_i``;
wheels: the points ``W_i`` (discs of radius 0).  ``α = (0, 2π/3, 4π/3)``
(``trident-snake``, ``trident-snake-joints``) or ``(−2π/3, 0, 2π/3)``
(``trident-snake-paper``, whose coordinates are ``x1..x6``).

*Default joint limits: a leg may not enter the body.*  At vertex ``V_i`` the
two edges of the triangle leave towards the other vertices; the direction
from ``V_1 = (r, 0)`` to ``V_2 = r(−1/2, √3/2)`` is ``(−3/2, √3/2)``, at angle
``5π/6`` from the outward radius ``(1, 0)`` (and ``−5π/6`` towards ``V_3``).  So
the interior angle of the body at a vertex (``π/3``) is the cone of leg
directions ``|φ_i| > 5π/6`` (mod ``2π``), and a leg stays outside the body
(touching an edge at most) iff ``φ_i ∈ [−5π/6, 5π/6]``.  These are the default
``[limits]`` of the three forms; they also keep a joint from turning through
the body (the joint coordinate is not wrapped).  The body is convex, so a leg
leaving a vertex outside the interior cone meets the body only at that vertex:
the limits are exactly "no leg in the body".  *Self-collision:* the outline's
bodies are ``body`` (the triangle) and ``leg1..leg3`` (leg ``i``: its segment and
its wheel); the legs must not touch one another (``self_collision``: every pair
of legs).  A leg always touches the body at its own vertex, so leg–body is the
joint limits' job, not a self-collision pair.

**Car with trailers** (``car-trailers:K``, coordinates ``x, y, θ0..θK``,
hitch lengths ``d_i``).  Axle centres ``P_0 = (x, y)``,
``P_i = P_{i−1} − d_i (cos θ_i, sin θ_i)``.  The car is the rectangle from
0.1 behind to 0.7 ahead of ``P_0`` along ``θ0``, 0.5 wide; trailer ``i`` the
rectangle from 0.2 behind to 0.3 ahead of ``P_i`` along ``θ_i``, 0.4 wide
(model length units, independent of ``d_i``); each hitch is the segment
``P_i → P_{i−1}``.

*Self-collision* (bodies ``car``, ``trailer1..K``, ``hitch1..K``): the car against
every trailer, every two trailers, and each hitch bar against every body except
the two it joins (hitch ``i`` joins vehicle ``i−1`` and trailer ``i``; it touches
them at the axle centres by construction) and against every hitch bar but its
neighbours (consecutive bars share an axle centre).

*Hitch limits* (``relative_limits``): ``|θ_{i−1} − θ_i| ≤`` :data:`HITCH_LIMIT`
``= 1.4`` rad (≈ 80.2°).  At ``|θ_{i−1} − θ_i| = π/2`` the trailer's speed
``v_i = v_{i−1} cos(θ_{i−1} − θ_i)`` vanishes — the jackknife: driving the car
forward no longer moves the trailer, only turns it — and the growth vector
drops there (consecutive bodies perpendicular are outside the regular set), so
the steering's nilpotent approximation degrades near it.  1.4 rad keeps about
10° (``cos 1.4 ≈ 0.17`` of the speed) from it; real tractor–trailer hitches
stop at 60–90°.  Within it the rectangles of the default sizes cannot touch
(they first meet at ``|θ_{i−1} − θ_i| ≈ 2.5`` rad, see the tests), so
self-collision is a second guard (for ``--param d1=...`` shorter hitches and
non-adjacent bodies).  No limits on the absolute angles.

**Car** (``car``): :func:`~nilpotent.models.vehicles.car_outline`; default
limit ``|φ| ≤ atan(L / rmin)`` from the model's own parameter values.
**Snakeboard**, **kinematic snake**, **space robot**: their outlines
(:mod:`nilpotent.models.vehicles`), no default limits.  **Rigid body**: no
outline, ``|pitch| ≤ 17π/36``.
"""

from __future__ import annotations

import sympy as sp

from nilpotent.core.model.outline import Limits, Outline
from nilpotent.core.model.system import ControlSystem
from nilpotent.models.groups import PITCH_LIMIT
from nilpotent.models.vehicles import (
    car_outline,
    snake_outline,
    snakeboard_outline,
    space_robot_outline,
)

__all__ = [
    "CAR_SIZE",
    "HITCH_LIMIT",
    "LEG_LIMIT",
    "TRAILER_SIZE",
    "car_trailers_outline",
    "hitch_limits",
    "trident_outline",
    "with_builtin_constraints",
]

#: The bound of the trident snake's default joint limits ``|φ_i| ≤ 5π/6`` (see module doc).
LEG_LIMIT = 5 * sp.pi / 6
#: The hitch limits of ``car-trailers:K``: ``|θ_{i−1} − θ_i| ≤ 1.4`` rad (module doc).
HITCH_LIMIT = 1.4
#: Car rectangle: (behind the axle, ahead of the axle, width).
CAR_SIZE = (sp.Rational(1, 10), sp.Rational(7, 10), sp.Rational(1, 2))
#: Trailer rectangle: (behind the axle, ahead of the axle, width).
TRAILER_SIZE = (sp.Rational(1, 5), sp.Rational(3, 10), sp.Rational(2, 5))

_TRIDENT_ANGLES = {
    "body": (sp.Integer(0), 2 * sp.pi / 3, 4 * sp.pi / 3),
    "paper": (-2 * sp.pi / 3, sp.Integer(0), 2 * sp.pi / 3),
}


def trident_outline(
    coords: tuple[sp.Symbol, ...], offsets: tuple[sp.Expr, ...], has_lengths: bool = True
) -> Outline:
    """Body triangle, three legs and three wheels of the trident snake (module doc).

    ``has_lengths``: the model has the parameters ``r`` and ``l``; else
    (``trident-snake-paper``) ``r = l = 1``.
    """
    x, y, th, *phis = coords
    r, l = (sp.Symbol("r"), sp.Symbol("l")) if has_lengths else (sp.Integer(1), sp.Integer(1))
    verts = [(x + r * sp.cos(th + a), y + r * sp.sin(th + a)) for a in offsets]
    wheels = [
        (vx + l * sp.cos(th + a + p), vy + l * sp.sin(th + a + p))
        for (vx, vy), a, p in zip(verts, offsets, phis, strict=True)
    ]
    legs = tuple(f"leg{i}" for i in range(1, len(verts) + 1))
    return Outline(
        polygons=(tuple(verts),),
        segments=tuple(zip(verts, wheels, strict=True)),
        discs=tuple((w, sp.Integer(0)) for w in wheels),
        bodies=("body", *legs, *legs),
        self_collision=tuple((a, b) for i, a in enumerate(legs) for b in legs[i + 1:]),
    )


def _rectangle(px, py, th, behind, ahead, width) -> tuple:
    c, s = sp.cos(th), sp.sin(th)
    h = width / 2
    return tuple(
        (px + a * c - b * s, py + a * s + b * c)
        for a, b in ((-behind, -h), (ahead, -h), (ahead, h), (-behind, h))
    )


def car_trailers_outline(coords: tuple[sp.Symbol, ...]) -> Outline:
    """Car and trailer rectangles and hitch bars of ``car-trailers:K`` (module doc)."""
    x, y, *thetas = coords
    axles: list[tuple[sp.Expr, sp.Expr]] = [(x, y)]
    for i in range(1, len(thetas)):
        d = sp.Symbol(f"d{i}")
        px, py = axles[-1]
        axles.append((px - d * sp.cos(thetas[i]), py - d * sp.sin(thetas[i])))
    polys = [_rectangle(x, y, thetas[0], *CAR_SIZE)]
    polys += [_rectangle(px, py, th, *TRAILER_SIZE)
              for (px, py), th in zip(axles[1:], thetas[1:], strict=True)]
    hitches = tuple((axles[i], axles[i - 1]) for i in range(1, len(axles)))
    k = len(hitches)
    vehicles = ["car", *(f"trailer{i}" for i in range(1, k + 1))]
    bars = [f"hitch{i}" for i in range(1, k + 1)]
    pairs = [(a, b) for i, a in enumerate(vehicles) for b in vehicles[i + 1:]]
    for i in range(1, k + 1):  # hitch i joins vehicles[i - 1] and vehicles[i]
        pairs += [(bars[i - 1], v) for j, v in enumerate(vehicles) if j not in (i - 1, i)]
        pairs += [(bars[i - 1], bars[j - 1]) for j in range(i + 2, k + 1)]
    return Outline(polygons=tuple(polys), segments=hitches, bodies=(*vehicles, *bars),
                   self_collision=tuple(pairs))


def hitch_limits(k: int) -> tuple[tuple[str, sp.Expr, float, float], ...]:
    """The relative limits ``|θ_{i−1} − θ_i| ≤`` :data:`HITCH_LIMIT` of ``car-trailers:k``."""
    out = []
    for i in range(1, k + 1):
        a, b = sp.Symbol(f"theta{i - 1}"), sp.Symbol(f"theta{i}")
        out.append((f"theta{i - 1} - theta{i}", a - b, -HITCH_LIMIT, HITCH_LIMIT))
    return tuple(out)


def with_builtin_constraints(system: ControlSystem) -> ControlSystem:
    """The built-in ``system`` with its outline and default limits attached (if it has any).

    Trident forms (by name): :func:`trident_outline` and ``|φ_i| ≤ 5π/6``;
    ``car-trailers:K``: :func:`car_trailers_outline`; ``car``, ``snakeboard``,
    ``kinematic-snake``, ``rigid-body``: see the module doc (the car's limit is
    computed from its parameter values, so apply them first).  Other systems
    are returned unchanged.
    """
    from dataclasses import replace

    name = system.name
    coords = system.coordinates
    if name in ("trident-snake", "trident-snake-joints", "trident-snake-paper"):
        key = "paper" if name == "trident-snake-paper" else "body"
        bound = float(LEG_LIMIT)
        limits = Limits(tuple((str(c), -bound, bound) for c in coords[3:6]))
        return replace(
            system, limits=limits, geometry=trident_outline(
            coords, _TRIDENT_ANGLES[key], "r" in system.parameter_values
        ))
    if name.startswith("car-trailers:"):
        limits = Limits(system.limits.bounds, hitch_limits(len(coords) - 3))
        return replace(system, limits=limits, geometry=car_trailers_outline(coords))
    if name == "car":
        values = system.parameter_values
        bound = float(sp.atan(values["L"] / values["rmin"]))
        return replace(system, limits=Limits((("phi", -bound, bound),)),
                       geometry=car_outline(coords))
    if name == "snakeboard":
        return replace(system, geometry=snakeboard_outline(coords))
    if name == "kinematic-snake":
        return replace(system, geometry=snake_outline(coords))
    if name == "space-robot":
        return replace(system, geometry=space_robot_outline(coords))
    if name == "rigid-body":
        pitch = float(PITCH_LIMIT)
        return replace(system, limits=Limits((("pitch", -pitch, pitch),)))
    return system
