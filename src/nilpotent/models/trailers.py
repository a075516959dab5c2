r"""A unicycle-driven car pulling ``K`` trailers hitched at the axle centres.

Derivation (standard "on-axle hitching", Laumond; Sørdalen)::

      trailer K          trailer 1            car (tractor)
     [ o ]----d_K---- ... [ o ]-----d_1------[ o ]  → heading θ0
      P_K                  P_1                 P_0 = (x, y)

``P_0 = (x, y)`` is the midpoint of the car's rear axle, ``θ_0`` its heading.
Trailer ``i`` (``1 ≤ i ≤ K``) is hitched at the axle centre ``P_{i−1}`` of the
vehicle in front, its own axle centre is
``P_i = P_{i−1} − d_i (cos θ_i, sin θ_i)`` and its wheels do not slip
sideways: ``Ṗ_i`` is along ``(cos θ_i, sin θ_i)``.  Write
``Ṗ_{i−1} = v_{i−1} (cos θ_{i−1}, sin θ_{i−1})`` (the vehicle in front does not
slip either).  Then ``Ṗ_i = Ṗ_{i−1} + d_i θ̇_i (sin θ_i, −cos θ_i)``; its
component along ``(−sin θ_i, cos θ_i)`` vanishes iff

    ``θ̇_i = v_{i−1} sin(θ_{i−1} − θ_i) / d_i``,

and its component along the heading gives the trailer's speed
``v_i = v_{i−1} cos(θ_{i−1} − θ_i)``.  With the car's speed ``v_0 = u_1`` and
turning rate ``θ̇_0 = u_2`` as inputs:

$X_1 = \cos\theta_0\,\partial_x + \sin\theta_0\,\partial_y
+ \sum_{i=1}^{K} \Big(\prod_{j=1}^{i-1}\cos(\theta_{j-1}-\theta_j)\Big)
\frac{\sin(\theta_{i-1}-\theta_i)}{d_i}\,\partial_{\theta_i}$,
$X_2 = \partial_{\theta_0}$.

The system is flat (output: the last trailer's axle centre) and converts to
the chained form; its growth vector is ``(2, 3, ..., K + 3)`` at points where
no two consecutive bodies are perpendicular (e.g. the origin), step ``K + 2``.
The hitch lengths ``d1..dK`` are parameters (default 1).
"""

from __future__ import annotations

import sympy as sp

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ModelError

__all__ = ["car_trailers", "hitch_parameter_names"]


def hitch_parameter_names(k: int) -> tuple[str, ...]:
    """The names of the hitch-length parameters of ``car-trailers:k``: ``d1..dk``."""
    return tuple(f"d{i}" for i in range(1, k + 1))


def car_trailers(k: int = 1) -> ControlSystem:
    r"""The car with ``k`` trailers (see the module docstring for the derivation).

    Parameters
    ----------
    k:
        Number of trailers, an integer ``≥ 1``.

    Returns
    -------
    ControlSystem
        Coordinates ``(x, y, theta0, ..., thetak)`` (``n = k + 3``), fields
        ``X1`` (drive the car forward) and ``X2 = ∂θ0`` (steer the car),
        parameters ``d1..dk`` (hitch lengths, default 1).

    Examples
    --------
    >>> car_trailers(1).fields[0]
    (cos(theta0), sin(theta0), 0, sin(theta0 - theta1)/d1)
    """
    if isinstance(k, bool) or not isinstance(k, int) or k < 1:
        raise ModelError(f"car-trailers needs an integer number of trailers K >= 1, got {k!r}")
    x, y = sp.symbols("x y")
    thetas = sp.symbols(" ".join(f"theta{i}" for i in range(k + 1)))
    if not isinstance(thetas, tuple):
        thetas = (thetas,)
    hitches = tuple(sp.Symbol(name) for name in hitch_parameter_names(k))
    drive: list[sp.Expr] = [sp.cos(thetas[0]), sp.sin(thetas[0]), sp.Integer(0)]
    speed_ratio: sp.Expr = sp.Integer(1)  # v_{i-1} / v_0
    for i in range(1, k + 1):
        rel = thetas[i - 1] - thetas[i]
        drive.append(speed_ratio * sp.sin(rel) / hitches[i - 1])
        speed_ratio = speed_ratio * sp.cos(rel)
    steer = [sp.Integer(0)] * (k + 3)
    steer[2] = sp.Integer(1)
    return ControlSystem(
        f"car-trailers:{k}",
        (x, y, *thetas),
        (tuple(drive), tuple(steer)),
        tuple((str(d), sp.Integer(1)) for d in hitches),
        f"unicycle car pulling {k} trailer{'s' if k > 1 else ''} hitched at the axle centres; "
        f"growth ({','.join(str(i) for i in range(2, k + 4))}) at the origin",
    )
