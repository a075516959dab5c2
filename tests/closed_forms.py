"""Closed forms the tests check the product against, derived here independently of the code.

The sub-Riemannian distance of the Heisenberg group: with ``ẋ₃ = (x₁u₂ − x₂u₁)/2`` (the
built-in ``heisenberg`` model, ``X1 = ∂1 − x2/2 ∂3``, ``X2 = ∂2 + x1/2 ∂3``), ``x₃(1)`` is
the signed area swept by ``(x₁, x₂)`` seen from the start.  Minimising the length of a
plane curve from 0 to ``(x₁, x₂)`` (chord ``r``) that encloses, with the chord, the area
``|x₃|`` is Dido's problem: the curve is a circular arc.  An arc of angle ``φ`` and radius
``R`` has length ``L = Rφ``, chord ``r = 2R sin(φ/2)`` and segment area ``R²(φ − sin φ)/2``,
hence

    |x₃| / r² = (φ − sin φ) / (8 sin²(φ/2)),     d = r φ / (2 sin(φ/2)),

``φ ∈ [0, 2π)`` (the left side increases from 0 to ∞); for ``r = 0`` (a full circle)
``d = √(4π|x₃|)``.
"""

from __future__ import annotations

import math

from scipy.optimize import brentq


def dido_distance(r: float, z: float) -> float:
    """Shortest length of a plane curve with chord ``r`` enclosing the area ``|z|``."""
    z = abs(z)
    if r == 0:
        return math.sqrt(4 * math.pi * z)
    if z == 0:
        return r
    q = z / r**2
    phi = brentq(lambda p: (p - math.sin(p)) / (8 * math.sin(p / 2) ** 2) - q,
                 1e-9, 2 * math.pi - 1e-12, xtol=1e-15, rtol=1e-15)
    return r * phi / (2 * math.sin(phi / 2))


def heisenberg_distance(x1: float, x2: float, x3: float) -> float:
    """The sub-Riemannian distance from 0 to ``(x1, x2, x3)`` in the Heisenberg group."""
    return dido_distance(math.hypot(x1, x2), x3)
