r"""Wheeled robots from the literature: the kinematic car, the snakeboard, the three-link snake.

Each builder derives its fields from no-side-slip constraints (re-derived in
the docstrings; ``tests/test_models.py`` checks every constraint and growth
vector independently).  Convention ``[X, Y] = DY·X − DX·Y``.

* :func:`car` — the kinematic car with its steering angle as a state
  (rear-wheel drive; Laumond, *Robot Motion Planning and Control*, 1998,
  ch. 1; Murray & Sastry, IEEE TAC 38(5), 1993, the car example);
* :func:`snakeboard` — the snakeboard's constraint distribution (Lewis,
  Ostrowski, Murray & Burdick, ICRA 1994, the model and its constraints;
  Bullo & Lewis, *Geometric Control of Mechanical Systems*, 2005, the
  snakeboard example);
* :func:`kinematic_snake` — the three-link wheeled snake with joint-velocity
  inputs (Hirose 1993; Ostrowski & Burdick, IJRR 17(7), 1998; Shammas,
  Choset & Rizzi, IJRR 26(10), 2007);
* :func:`space_robot` — a free-floating planar robot, base and two links,
  nonholonomic through the conservation of angular momentum (Nakamura &
  Mukherjee, IEEE TRA 7(4), 1991; Vafa & Dubowsky 1987).

Their outlines (for planning among obstacles) are :func:`car_outline`,
:func:`snakeboard_outline`, :func:`snake_outline` and :func:`space_robot_outline`.
"""

from __future__ import annotations

import sympy as sp

from nilpotent.core.model.outline import Outline
from nilpotent.core.model.system import ControlSystem

__all__ = [
    "car",
    "car_outline",
    "kinematic_snake",
    "snake_outline",
    "snake_singularity",
    "snakeboard",
    "snakeboard_outline",
    "space_robot",
    "space_robot_outline",
]

_ZERO, _ONE = sp.Integer(0), sp.Integer(1)


def car() -> ControlSystem:
    r"""The kinematic car (rear-wheel drive), steering angle a state: ``(x, y, theta, phi)``.

    ``(x, y)`` is the midpoint of the rear axle, ``θ`` the heading, ``φ`` the
    steering angle of the front wheels, ``L`` the wheelbase::

            rear axle          front axle (steered by φ)
              ||------- L -------//
           (x, y)   → θ

    Both wheels roll without slipping sideways: the rear axle centre moves
    along ``(cos θ, sin θ)``, the front one, at ``(x, y) + L (cos θ, sin θ)``,
    along ``(cos(θ+φ), sin(θ+φ))``.  With the rear speed ``v`` the first gives
    ``(ẋ, ẏ) = v (cos θ, sin θ)``; the second,
    ``−sin(θ+φ)(ẋ − L sin θ θ̇) + cos(θ+φ)(ẏ + L cos θ θ̇) = 0``, reads
    ``−v sin φ + L cos φ θ̇ = 0``, i.e. ``θ̇ = v tan φ / L``.  Inputs: the rear
    speed (drive) and the steering rate::

        X1 = cos θ ∂x + sin θ ∂y + (tan φ / L) ∂θ,     X2 = ∂φ.

    $[X_1, X_2] = -\sec^2\varphi / L\,\partial_\theta$,
    $[X_1, [X_1, X_2]] = \sec^2\varphi / L\,(-\sin\theta\,\partial_x + \cos\theta\,\partial_y)$:
    ``det(X1, X2, [X1,X2], [X1,[X1,X2]]) = 1 / (L² cos⁴φ)``, so the growth
    vector is ``(2, 3, 4)`` on the whole domain ``|φ| < π/2``, weights
    ``(1, 1, 2, 3)``, step 3 (the car is flat and converts to the chained form
    ``(2, 3, 4)``; Murray–Sastry 1993).

    Parameters (exact defaults): ``L = 3/5`` (wheelbase) and ``rmin = 1``
    (the least turning radius of the rear axle centre, ``L / tan φ_max``).
    ``rmin`` is not in the fields: it sets the default limit
    ``|φ| ≤ atan(L / rmin)`` (``atan 0.6`` by default, radius ≥ 1, the
    Reeds–Shepp car of radius 1).

    Examples
    --------
    >>> car().fields[0]
    (cos(theta), sin(theta), tan(phi)/L, 0)
    """
    x, y, th, phi = sp.symbols("x y theta phi")
    wheelbase = sp.Symbol("L")
    return ControlSystem(
        "car",
        (x, y, th, phi),
        ((sp.cos(th), sp.sin(th), sp.tan(phi) / wheelbase, _ZERO), (_ZERO, _ZERO, _ZERO, _ONE)),
        (("L", sp.Rational(3, 5)), ("rmin", _ONE)),
        "kinematic car, rear-wheel drive, steering angle phi a state, |phi| <= atan(L/rmin) "
        "(Laumond 1998 ch. 1; Murray-Sastry 1993); growth (2,3,4) for |phi| < pi/2",
    )


def snakeboard() -> ControlSystem:
    r"""The snakeboard's constraint distribution: ``(x, y, theta, psi, phi)``.

    A board of half-length ``l`` (centre ``(x, y)``, heading ``θ``) on two
    wheel trucks at ``(x, y) ± l (cos θ, sin θ)``, turned by ``+φ`` (front) and
    ``−φ`` (back); ``ψ`` is the rotor (the rider's torso) on the centre
    (Lewis, Ostrowski, Murray & Burdick, ICRA 1994; Bullo & Lewis 2005).
    The wheels do not slip sideways: with ``n(a) = (−sin a, cos a)``,

        front: ``−sin(θ+φ) ẋ + cos(θ+φ) ẏ + l cos φ θ̇ = 0``,
        back:  ``−sin(θ−φ) ẋ + cos(θ−φ) ẏ − l cos φ θ̇ = 0``.

    For ``cos φ ≠ 0`` their solutions in ``(ẋ, ẏ, θ̇)`` are the multiples of
    ``(l cos φ cos θ, l cos φ sin θ, sin φ)`` (the board turns about the
    intersection of the two axles), which stays the solution line at
    ``φ = ±π/2`` (pure rotation).  ``ψ`` and ``φ`` are free shape variables.
    The kinematic model takes as inputs the board's rate along the constraint,
    the rotor rate and the steering rate::

        X1 = l cos φ (cos θ ∂x + sin θ ∂y) + sin φ ∂θ,   X2 = ∂ψ,   X3 = ∂φ.

    (The rotor's drive of ``X1`` through angular momentum is the dynamics,
    not this kinematic model; ``X2`` commutes with everything.)
    $[X_1, X_3] = l\sin\varphi(\cos\theta\,\partial_x + \sin\theta\,\partial_y)
    - \cos\varphi\,\partial_\theta$ and
    ``det(X1, X2, X3, [X1,X3], [X1,[X1,X3]]) = l²``: growth ``(3, 4, 5)`` at
    every point, weights ``(1, 1, 1, 2, 3)``, step 3 (``[X3,[X1,X3]] = X1``).
    Parameter ``l = 1`` (half the wheel base).  Default limits: none.

    Examples
    --------
    >>> snakeboard().fields[0]
    (l*cos(phi)*cos(theta), l*sin(theta)*cos(phi), sin(phi), 0, 0)
    """
    x, y, th, psi, phi = sp.symbols("x y theta psi phi")
    half = sp.Symbol("l")
    roll = (half * sp.cos(phi) * sp.cos(th), half * sp.cos(phi) * sp.sin(th), sp.sin(phi),
            _ZERO, _ZERO)
    return ControlSystem(
        "snakeboard",
        (x, y, th, psi, phi),
        (roll, (_ZERO, _ZERO, _ZERO, _ONE, _ZERO), (_ZERO, _ZERO, _ZERO, _ZERO, _ONE)),
        (("l", _ONE),),
        "snakeboard constraint distribution: roll along the wheels, rotor, steer "
        "(Lewis-Ostrowski-Murray-Burdick 1994; Bullo-Lewis 2005); growth (3,4,5) everywhere",
    )


def snake_singularity(system: ControlSystem) -> sp.Expr:
    """``D = sin α1 + sin α2 + sin(α1 + α2) = 4 sin((α1+α2)/2) cos(α1/2) cos(α2/2)``.

    The denominator of :func:`kinematic_snake`'s fields: they are undefined
    where ``D = 0``, the shapes whose three wheel axles meet in one point or
    are parallel (the straight snake and every circular arc ``α1 = −α2``, and
    a folded joint ``α_i = π``).
    """
    a1, a2 = system.coordinates[3:5]
    return sp.sin(a1) + sp.sin(a2) + sp.sin(a1 + a2)


def kinematic_snake() -> ControlSystem:
    r"""The three-link wheeled snake, joint-rate inputs: ``(x, y, theta, alpha1, alpha2)``.

    Three links of length ``2R``, a pair of wheels at the middle of each
    (Hirose's active cord mechanism, 1993; Ostrowski & Burdick 1998; Shammas,
    Choset & Rizzi 2007).  ``(x, y)`` is the middle link's centre, ``θ`` its
    heading; the front link has heading ``θ + α1`` and is jointed at
    ``(x, y) + R e(θ)``, the rear link heading ``θ + α2`` at
    ``(x, y) − R e(θ)`` (``e(a) = (cos a, sin a)``), so the wheel centres are
    ``c0 = (x, y)``, ``c1 = (x, y) + R e(θ) + R e(θ+α1)``,
    ``c2 = (x, y) − R e(θ) − R e(θ+α2)``.  Each moves along its link
    (``n(a)·ċ_i = 0`` with ``n(a) = (−sin a, cos a)``): three linear equations
    in ``(ẋ, ẏ, θ̇)`` given the joint rates ``(α̇1, α̇2)``; solved by Cramer's
    rule, with ``D = sin α1 + sin α2 + sin(α1 + α2)``::

        X1 = [R (1 + cos α2) (cos θ ∂x + sin θ ∂y) − sin α2 ∂θ] / D + ∂α1,
        X2 = [−R (1 + cos α1) (cos θ ∂x + sin θ ∂y) − sin α1 ∂θ] / D + ∂α2.

    Undefined where ``D = 0`` (:func:`snake_singularity`, the origin
    included: the straight snake's axles are parallel).  Growth ``(2, 3, 5)``
    off that set (e.g. at the registry's example point ``α1 = α2 = π/2``),
    weights ``(1, 1, 2, 3, 3)``, step 3.  Parameter ``R = 1`` (half a link).

    Examples
    --------
    >>> kinematic_snake().fields[1][3:]
    (0, 1)
    """
    x, y, th, a1, a2 = sp.symbols("x y theta alpha1 alpha2")
    half = sp.Symbol("R")
    den = sp.sin(a1) + sp.sin(a2) + sp.sin(a1 + a2)
    front = half * (1 + sp.cos(a2)) / den
    rear = -half * (1 + sp.cos(a1)) / den
    return ControlSystem(
        "kinematic-snake",
        (x, y, th, a1, a2),
        (
            (front * sp.cos(th), front * sp.sin(th), -sp.sin(a2) / den, _ONE, _ZERO),
            (rear * sp.cos(th), rear * sp.sin(th), -sp.sin(a1) / den, _ZERO, _ONE),
        ),
        (("R", _ONE),),
        "three-link wheeled kinematic snake, joint-rate inputs (Hirose 1993; Ostrowski-Burdick "
        "1998); growth (2,3,5) off sin a1+sin a2+sin(a1+a2)=0, undefined on it (the origin)",
    )


def space_robot() -> ControlSystem:
    r"""A free-floating planar space robot, base and two links: ``(theta0, q1, q2)``.

    A base (mass ``m0``, inertia ``J0`` about its centre of mass) carries a
    two-link arm: joint 1 at distance ``a`` from the base's centre along its
    axis, two uniform rods of mass ``m`` and length ``l`` (inertia
    ``m l²/12``), joint angles ``q1``, ``q2``; ``θ0`` is the base attitude
    (Nakamura & Mukherjee, IEEE TRA 7(4), 1991; Vafa & Dubowsky 1987).  With no
    external force or torque and the robot at rest initially, the linear
    momentum vanishes (the centre of mass ``c`` stays put) and so does the
    angular momentum about ``c``:
    ``Σ_i J_i ω_i + m_i (r_i − c) × (ṙ_i − ċ) = H0 θ̇0 + H1 q̇1 + H2 q̇2 = 0``
    (``ω = θ̇0, θ̇0 + q̇1, θ̇0 + q̇1 + q̇2``).  Expanded, with ``M = m0 + 2m``::

        M H0 = M J0 + 2 a² m m0 + 5 l² m²/6 + 5 l² m m0/3
               + l² m (m/2 + m0) cos q2 + a l m m0 (3 cos q1 + cos(q1 + q2)),
        M H1 = 5 l² m²/6 + 5 l² m m0/3 + l² m (m/2 + m0) cos q2
               + a l m m0 (3 cos q1 + cos(q1 + q2)) / 2,
        M H2 = 5 l² m²/12 + l² m m0/3 + l² m (m/4 + m0/2) cos q2 + a l m m0 cos(q1 + q2) / 2.

    ``H0 > 0`` (it is the moment of inertia of the whole robot about ``c``
    with the joints locked).  The joint rates are the inputs::

        X1 = ∂q1 − (H1/H0) ∂θ0,   X2 = ∂q2 − (H2/H0) ∂θ0.

    The constraint is not integrable: growth ``(2, 3)`` at generic shapes
    (e.g. ``q1 = π/3, q2 = π/2``); at the stretched shape ``q = 0`` the first
    bracket vanishes and the growth is ``(2, 2, 3)`` (singular).  Parameters
    ``m0 = 2, J0 = 1/3, a = 1/2, m = 1, l = 1``.

    Examples
    --------
    >>> space_robot().fields[0][1:]
    (1, 0)
    """
    th, q1, q2 = sp.symbols("theta0 q1 q2")
    m0, j0, a, m, ln = sp.symbols("m0 J0 a m l")
    total = m0 + 2 * m
    c1, c2, c12 = sp.cos(q1), sp.cos(q2), sp.cos(q1 + q2)
    links = 5 * ln**2 * m**2 / 6 + 5 * ln**2 * m * m0 / 3 + ln**2 * m * (m / 2 + m0) * c2
    h0 = total * j0 + 2 * a**2 * m * m0 + links + a * ln * m * m0 * (3 * c1 + c12)
    h1 = links + a * ln * m * m0 * (3 * c1 + c12) / 2
    h2 = (5 * ln**2 * m**2 / 12 + ln**2 * m * m0 / 3 + ln**2 * m * (m / 4 + m0 / 2) * c2
          + a * ln * m * m0 * c12 / 2)
    return ControlSystem(
        "space-robot",
        (th, q1, q2),
        ((-h1 / h0, _ONE, _ZERO), (-h2 / h0, _ZERO, _ONE)),
        (("m0", sp.Integer(2)), ("J0", sp.Rational(1, 3)), ("a", sp.Rational(1, 2)),
         ("m", _ONE), ("l", _ONE)),
        "free-floating planar space robot, base and two links, zero momentum "
        "(Nakamura-Mukherjee 1991); growth (2,3) at generic shapes, (2,2,3) stretched",
    )


def _e(angle: sp.Expr) -> tuple[sp.Expr, sp.Expr]:
    return sp.cos(angle), sp.sin(angle)


def _plus(p: tuple[sp.Expr, sp.Expr], k: sp.Expr, angle: sp.Expr) -> tuple[sp.Expr, sp.Expr]:
    c, s = _e(angle)
    return p[0] + k * c, p[1] + k * s


def car_outline(coords: tuple[sp.Symbol, ...]) -> Outline:
    """The car's body and its two axles' wheels (``car``).

    Body: the rectangle from ``L/4`` behind the rear axle to ``L/4`` ahead of
    the front axle, ``3L/4`` wide; wheels: segments of length ``L/3`` centred
    on the axle centres, along ``θ`` (rear) and ``θ + φ`` (front).
    """
    x, y, th, phi = coords
    wheelbase = sp.Symbol("L")
    c, s = _e(th)
    h = 3 * wheelbase / 8
    body = tuple(
        (x + a * c - b * s, y + a * s + b * c)
        for a, b in ((-wheelbase / 4, -h), (5 * wheelbase / 4, -h),
                     (5 * wheelbase / 4, h), (-wheelbase / 4, h))
    )
    front = _plus((x, y), wheelbase, th)
    tyre = wheelbase / 6
    wheels = (
        (_plus((x, y), -tyre, th), _plus((x, y), tyre, th)),
        (_plus(front, -tyre, th + phi), _plus(front, tyre, th + phi)),
    )
    return Outline(polygons=(body,), segments=wheels)


def snakeboard_outline(coords: tuple[sp.Symbol, ...]) -> Outline:
    """The board (the segment between the trucks) and the two wheel axles (``snakeboard``).

    Each axle is a segment of length ``2l/3`` through its truck, perpendicular
    to its wheels' rolling direction ``θ ± φ``.
    """
    x, y, th, _psi, phi = coords
    half = sp.Symbol("l")
    front, back = _plus((x, y), half, th), _plus((x, y), -half, th)
    w = half / 3
    axles = tuple(
        (_plus(p, -w, th + sign * phi + sp.pi / 2), _plus(p, w, th + sign * phi + sp.pi / 2))
        for p, sign in ((front, 1), (back, -1))
    )
    return Outline(segments=((back, front), *axles))


def snake_outline(coords: tuple[sp.Symbol, ...]) -> Outline:
    """The three links (segments of length ``2R``) and their wheels (points) of the snake."""
    x, y, th, a1, a2 = coords
    half = sp.Symbol("R")
    front_joint, rear_joint = _plus((x, y), half, th), _plus((x, y), -half, th)
    head = _plus(front_joint, 2 * half, th + a1)
    tail = _plus(rear_joint, -2 * half, th + a2)
    wheels = ((x, y), _plus(front_joint, half, th + a1), _plus(rear_joint, -half, th + a2))
    return Outline(
        segments=((rear_joint, front_joint), (front_joint, head), (rear_joint, tail)),
        discs=tuple((w, _ZERO) for w in wheels),
    )


def space_robot_outline(coords: tuple[sp.Symbol, ...]) -> Outline:
    """Base square (half-side ``a``) and the two links, about the fixed centre of mass (origin).

    In the base frame the base centre is at 0, joint 1 at ``a e(θ0)``; every
    point is shifted by minus the centre of mass, which does not move.
    """
    th, q1, q2 = coords
    m0, a, m, ln = (sp.Symbol(k) for k in ("m0", "a", "m", "l"))
    joint1 = _plus((_ZERO, _ZERO), a, th)
    joint2 = _plus(joint1, ln, th + q1)
    tip = _plus(joint2, ln, th + q1 + q2)
    mid1, mid2 = _plus(joint1, ln / 2, th + q1), _plus(joint2, ln / 2, th + q1 + q2)
    total = m0 + 2 * m
    com = tuple((m * mid1[k] + m * mid2[k]) / total for k in range(2))

    def at(p: tuple[sp.Expr, sp.Expr]) -> tuple[sp.Expr, sp.Expr]:
        return p[0] - com[0], p[1] - com[1]

    c, s = _e(th)
    base = tuple(at((u * c - v * s, u * s + v * c))
                 for u, v in ((-a, -a), (a, -a), (a, a), (-a, a)))
    return Outline(polygons=(base,), segments=((at(joint1), at(joint2)), (at(joint2), at(tip))))
