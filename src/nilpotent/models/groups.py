r"""Left-invariant systems on Lie groups: the rigid body on SO(3), the roto-translation group.

* :func:`rigid_body` — a rigid body controlled by two of its three body
  angular velocities (Crouch, IEEE TAC 29(4), 1984; Brockett 1973), in
  roll–pitch–yaw (Z-Y-X Euler) angles;
* :func:`roto_translation` — the sub-Riemannian structure of the
  roto-translation group SE(2) (Citti & Sarti, J. Math. Imaging Vis. 24, 2006;
  Sachkov, ESAIM COCV 16, 2010 and 17, 2011).
"""

from __future__ import annotations

import sympy as sp

from nilpotent.core.model.system import ControlSystem

__all__ = ["PITCH_LIMIT", "rigid_body", "roto_translation"]

#: Default bound of ``rigid-body``'s pitch, ``|pitch| ≤ 17π/36`` (85°): the chart ends at ±π/2.
PITCH_LIMIT = 17 * sp.pi / 36

_ZERO, _ONE = sp.Integer(0), sp.Integer(1)


def rigid_body() -> ControlSystem:
    r"""A rigid body on SO(3) with two body angular velocities as inputs: ``(roll, pitch, yaw)``.

    Attitude ``R = R_z(yaw) R_y(pitch) R_x(roll)`` (Z-Y-X Euler angles; a chart
    of SO(3) on ``|pitch| < π/2``).  The body angular velocity ``ω``
    (``Rᵀ Ṙ = ω^``) and the angle rates are related by (with ``φ`` = roll,
    ``θ`` = pitch)::

        roll'  = ω1 + (ω2 sin φ + ω3 cos φ) tan θ,
        pitch' = ω2 cos φ − ω3 sin φ,
        yaw'   = (ω2 sin φ + ω3 cos φ) / cos θ.

    With ``ω3 = 0`` (two actuated axes, Crouch 1984) the fields are
    ``X1 = ∂roll`` and ``X2 = sin φ tan θ ∂roll + cos φ ∂pitch + sin φ / cos θ ∂yaw``,
    the left-invariant fields of the body axes ``e1, e2``.  ``[X1, X2]`` is the
    field of ``e3`` (``cos φ tan θ ∂roll − sin φ ∂pitch + cos φ / cos θ ∂yaw``)
    and ``det(X1, X2, [X1, X2]) = 1 / cos θ``: growth ``(2, 3)`` on the whole
    chart, weights ``(1, 1, 2)``.  Default limit ``|pitch| ≤ 17π/36``
    (:data:`PITCH_LIMIT`), inside the chart.

    Examples
    --------
    >>> rigid_body().fields[0]
    (1, 0, 0)
    """
    roll, pitch, yaw = sp.symbols("roll pitch yaw")
    s, c = sp.sin(roll), sp.cos(roll)
    return ControlSystem(
        "rigid-body",
        (roll, pitch, yaw),
        ((_ONE, _ZERO, _ZERO), (s * sp.tan(pitch), c, s / sp.cos(pitch))),
        (),
        "rigid body on SO(3), two body angular velocities as inputs, Z-Y-X Euler angles "
        "(Crouch 1984); growth (2,3) on the chart |pitch| < pi/2",
    )


def roto_translation() -> ControlSystem:
    r"""The roto-translation group SE(2) with its sub-Riemannian frame: ``(x, y, theta)``.

    ``X1 = cos θ ∂x + sin θ ∂y``, ``X2 = ∂θ``, declared orthonormal: the model
    of the primary visual cortex (Citti & Sarti 2006) whose geodesics and
    cut locus Sachkov computed (2010, 2011).  The fields are the unicycle's;
    ``[X1, X2] = sin θ ∂x − cos θ ∂y``, growth ``(2, 3)`` everywhere, weights
    ``(1, 1, 2)``.  It is its own symmetry group: every left translation maps
    the frame to itself.

    Examples
    --------
    >>> roto_translation().fields[1]
    (0, 0, 1)
    """
    x, y, th = sp.symbols("x y theta")
    return ControlSystem(
        "roto-translation",
        (x, y, th),
        ((sp.cos(th), sp.sin(th), _ZERO), (_ZERO, _ZERO, _ONE)),
        (),
        "roto-translation group SE(2), sub-Riemannian frame (Citti-Sarti 2006; Sachkov 2010); "
        "growth (2,3) everywhere",
    )
