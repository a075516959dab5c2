"""Classic driftless systems: unicycle, Heisenberg, Engel, Cartan, Martinet.

Each builder returns a :class:`~nilpotent.core.model.system.ControlSystem`; the
docstring of each carries the derivation and the growth vector, stated in the
project convention ``[X, Y] = DY·X − DX·Y`` (so ``[X, Y]f = X(Yf) − Y(Xf)``).
These systems have no parameters.
"""

from __future__ import annotations

import sympy as sp

from nilpotent.core.model.system import ControlSystem

__all__ = ["cartan", "engel", "heisenberg", "martinet", "unicycle"]

_HALF = sp.Rational(1, 2)


def unicycle() -> ControlSystem:
    r"""The unicycle (kinematic car without steering): coordinates ``(x, y, theta)``.

    A wheel rolling on the plane without slipping sideways: its contact point
    ``(x, y)`` moves along its heading ``(cos θ, sin θ)``, so the only
    constraint is ``−sin θ ẋ + cos θ ẏ = 0``.  Solving it with the forward
    speed ``u_1`` and the turning rate ``u_2`` as inputs::

              y ^     heading θ
                |    ↗
                |   o  (x, y)
                +---------> x

    $X_1 = \cos\theta\,\partial_x + \sin\theta\,\partial_y$ (drive),
    $X_2 = \partial_\theta$ (turn).  $[X_1, X_2] = \sin\theta\,\partial_x -
    \cos\theta\,\partial_y$ (the sideways direction), so the growth vector is
    $(2, 3)$ at every point, weights $(1, 1, 2)$, step 2.

    Examples
    --------
    >>> unicycle().fields[0]
    (cos(theta), sin(theta), 0)
    """
    x, y, th = sp.symbols("x y theta")
    return ControlSystem(
        "unicycle",
        (x, y, th),
        ((sp.cos(th), sp.sin(th), sp.Integer(0)), (sp.Integer(0), sp.Integer(0), sp.Integer(1))),
        (),
        "unicycle: drive along the heading (X1) and turn (X2); growth (2,3)",
    )


def heisenberg() -> ControlSystem:
    r"""The Heisenberg system (nonholonomic integrator, symmetric form): ``(x1, x2, x3)``.

    $X_1 = \partial_1 - \tfrac{x_2}{2}\partial_3$,
    $X_2 = \partial_2 + \tfrac{x_1}{2}\partial_3$: along any path
    $\dot x_3 = \tfrac12(x_1\dot x_2 - x_2\dot x_1)$, i.e. $x_3$ is the signed
    area swept by $(x_1, x_2)$ (Brockett's integrator).
    $[X_1, X_2] = \partial_3$, so the growth vector is $(2, 3)$ everywhere,
    weights $(1, 1, 2)$.  The system is nilpotent and homogeneous: it is its
    own nilpotent approximation at the origin.

    Examples
    --------
    >>> heisenberg().fields[1]
    (0, 1, x1/2)
    """
    x1, x2, x3 = sp.symbols("x1 x2 x3")
    zero, one = sp.Integer(0), sp.Integer(1)
    return ControlSystem(
        "heisenberg",
        (x1, x2, x3),
        ((one, zero, -x2 * _HALF), (zero, one, x1 * _HALF)),
        (),
        "Heisenberg group (nonholonomic integrator, x3 = swept area); growth (2,3)",
    )


def engel() -> ControlSystem:
    r"""The Engel system (4D, growth (2, 3, 4)): coordinates ``(x1, x2, x3, x4)``.

    $X_1 = \partial_1$, $X_2 = \partial_2 + x_1\partial_3 + \tfrac{x_1^2}{2}\partial_4$.
    Then $[X_1, X_2] = \partial_3 + x_1\partial_4$ and
    $[X_1, [X_1, X_2]] = \partial_4$, while $[X_2, [X_1, X_2]] = 0$: the
    growth vector is $(2, 3, 4)$ at every point, weights $(1, 1, 2, 3)$,
    step 3.  The fields are homogeneous of degree −1 for the dilation
    $(x_1, x_2, x_3, x_4) \mapsto (\lambda x_1, \lambda x_2, \lambda^2 x_3,
    \lambda^3 x_4)$, so the system is its own nilpotent approximation at 0.

    Examples
    --------
    >>> engel().fields[1]
    (0, 1, x1, x1**2/2)
    """
    x1, x2, x3, x4 = sp.symbols("x1 x2 x3 x4")
    zero, one = sp.Integer(0), sp.Integer(1)
    return ControlSystem(
        "engel",
        (x1, x2, x3, x4),
        ((one, zero, zero, zero), (zero, one, x1, x1**2 * _HALF)),
        (),
        "Engel system (rank-2 distribution in R^4); growth (2,3,4)",
    )


def cartan() -> ControlSystem:
    r"""Cartan's (2, 3, 5) distribution, the flat model: coordinates ``(x1, ..., x5)``.

    $X_1 = \partial_1$,
    $X_2 = \partial_2 + x_1\partial_3 + \tfrac{x_1^2}{2}\partial_4 + x_1x_2\partial_5$.
    With $X_3 = [X_1, X_2] = \partial_3 + x_1\partial_4 + x_2\partial_5$ one
    gets $[X_1, X_3] = \partial_4$ and $[X_2, X_3] = \partial_5$: the five
    fields $X_1, X_2, X_3, [X_1, X_3], [X_2, X_3]$ are a frame everywhere, so
    the growth vector is $(2, 3, 5)$, weights $(1, 1, 2, 3, 3)$, step 3.  It is
    the nilpotent (free step-3 rank-2) model of a generic rank-2 distribution
    in dimension 5, e.g. a ball rolling on a plane without slipping or twisting.

    Examples
    --------
    >>> cartan().fields[1][4]
    x1*x2
    """
    x1, x2, x3, x4, x5 = sp.symbols("x1 x2 x3 x4 x5")
    zero, one = sp.Integer(0), sp.Integer(1)
    return ControlSystem(
        "cartan",
        (x1, x2, x3, x4, x5),
        ((one, zero, zero, zero, zero), (zero, one, x1, x1**2 * _HALF, x1 * x2)),
        (),
        "Cartan's (2,3,5) distribution (flat model, free nilpotent of step 3)",
    )


def martinet() -> ControlSystem:
    r"""The Martinet distribution: coordinates ``(x1, x2, x3)``; singular on ``x2 = 0``.

    $X_1 = \partial_1 + \tfrac{x_2^2}{2}\partial_3$, $X_2 = \partial_2$.
    $[X_1, X_2] = -x_2\,\partial_3$ and $[X_2, [X_1, X_2]] = -\partial_3$.
    Off the Martinet surface $\{x_2 = 0\}$ the growth vector is $(2, 3)$
    (weights $(1, 1, 2)$); on it, the first bracket vanishes and the growth
    vector is $(2, 2, 3)$ (weights $(1, 1, 3)$, step 3): those points are
    singular (the growth vector is not locally constant there).

    Examples
    --------
    >>> martinet().fields[0]
    (1, 0, x2**2/2)
    """
    x1, x2, x3 = sp.symbols("x1 x2 x3")
    zero, one = sp.Integer(0), sp.Integer(1)
    return ControlSystem(
        "martinet",
        (x1, x2, x3),
        ((one, zero, x2**2 * _HALF), (zero, one, zero)),
        (),
        "Martinet distribution; growth (2,3) off x2=0, (2,2,3) on the singular surface x2=0",
    )
