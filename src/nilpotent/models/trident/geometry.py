r"""The trident snake's geometry: body centre, vertices, wheels, headings, axle lines, slip.

:class:`TridentGeometry` gives the world positions of the robot's parts for one
configuration ``q = (x, y, θ, φ1, φ2, φ3)`` or arrays of shape ``(..., 6)``
(the notation of :mod:`nilpotent.models.trident.forms`); :func:`wheel_slip`
measures how far the wheels slide sideways along a trajectory that does not
come from the true system (the paper's closing remark).  Uses numpy
(``nilpotent.core`` does not).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import sympy as sp

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ModelError, OptionError
from nilpotent.models.trident.forms import BODY_LEG_ANGLES, FORMS, PAPER_LEG_ANGLES, form_of

__all__ = [
    "FLOAT_LEG_ANGLES",
    "Configs",
    "SampledConfigs",
    "TridentGeometry",
    "WheelSlip",
    "as_configs",
    "wheel_slip",
]

#: Configurations ``(x, y, θ, φ1, φ2, φ3)``: array-like of shape ``(..., 6)``.
Configs = npt.ArrayLike
#: Configurations sampled along a path: array-like of shape ``(T, 6)``; its times: shape ``(T,)``.
SampledConfigs = npt.ArrayLike


#: The legs' angle offsets as floats, by form family (``"body"``, ``"paper"``).
def _float_angles(angles: Sequence[sp.Expr | float]) -> tuple[float, float, float]:
    a, b, c = (float(v) for v in angles)
    return (a, b, c)


FLOAT_LEG_ANGLES = {
    "body": _float_angles(BODY_LEG_ANGLES),
    "paper": _float_angles(PAPER_LEG_ANGLES),
}


def as_configs(q: Configs) -> np.ndarray:
    """``q`` as a float array of shape ``(..., 6)``.

    Raises
    ------
    OptionError
        The last axis is not of length 6.
    """
    arr = np.asarray(q, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] != 6:
        raise OptionError(
            f"trident configurations need a last axis of length 6 (x, y, theta, phi1..phi3), "
            f"got shape {arr.shape}"
        )
    return arr


@dataclass(frozen=True)
class TridentGeometry:
    r"""Positions of the trident snake's parts, for one configuration or a batch.

    Every method takes ``q`` of shape ``(..., 6)`` = ``(x, y, θ, φ1, φ2, φ3)``
    and returns arrays with the same leading shape.  World frame.

    Parameters
    ----------
    r:
        Circumradius of the triangular body (> 0).
    l:
        Leg length (> 0).
    offsets:
        Polar angles $\alpha_i$ of the legs' vertices in the body frame (the
        angle offsets in $\psi_i = \theta + \alpha_i + \varphi_i$); default
        :data:`BODY_LEG_ANGLES` ``(0, 2π/3, 4π/3)``.  The paper's eq. (vf) reads
        the legs with ``(−2π/3, 0, 2π/3)`` (:meth:`for_form`); the body is the
        same triangle, only the legs' numbering differs.

    Raises
    ------
    ModelError
        Non-positive ``r`` or ``l``, or not three offsets.

    Examples
    --------
    >>> g = TridentGeometry()
    >>> g.wheels([0, 0, 0, 0, 0, 0])[0]
    array([2., 0.])
    """

    r: float = 1.0
    l: float = 1.0
    offsets: tuple[float, float, float] = FLOAT_LEG_ANGLES["body"]

    def __post_init__(self) -> None:
        r, l = float(self.r), float(self.l)
        if not (np.isfinite(r) and np.isfinite(l) and r > 0 and l > 0):
            raise ModelError(f"trident geometry needs r > 0 and l > 0, got r={r}, l={l}")
        if len(self.offsets) != 3:
            raise ModelError(f"trident geometry needs three leg offsets, got {len(self.offsets)}")
        offs = _float_angles(self.offsets)
        object.__setattr__(self, "r", r)
        object.__setattr__(self, "l", l)
        object.__setattr__(self, "offsets", offs)

    @classmethod
    def for_form(cls, form: str, r: float = 1.0, l: float = 1.0) -> TridentGeometry:
        """The geometry that reads the coordinates of the built-in ``form``.

        ``"trident-snake"`` and ``"trident-snake-joints"``: offsets
        ``(0, 2π/3, 4π/3)``; ``"trident-snake-paper"``: ``(−2π/3, 0, 2π/3)``
        (and ``r = l = 1`` is what that form assumes).
        """
        if form not in FORMS:
            raise ModelError(f"unknown trident form {form!r}; forms: {', '.join(FORMS)}")
        key = "paper" if form == "trident-snake-paper" else "body"
        return cls(r, l, FLOAT_LEG_ANGLES[key])

    @classmethod
    def from_system(cls, system: ControlSystem) -> TridentGeometry:
        """The geometry of a built-in trident form, with its ``r`` and ``l`` values."""
        form = form_of(system)
        values = system.parameter_values
        return cls.for_form(form, float(values.get("r", 1)), float(values.get("l", 1)))

    # --- positions -----------------------------------------------------------------
    def body_centre(self, q: Configs) -> np.ndarray:
        """Centre of the body (the circumcentre), shape ``(..., 2)``."""
        return as_configs(q)[..., 0:2].copy()

    def vertex_angles(self, q: Configs) -> np.ndarray:
        """World polar angles ``θ + α_i`` of the three vertices, shape ``(..., 3)``."""
        qq = as_configs(q)
        return qq[..., 2:3] + np.asarray(self.offsets)

    def vertices(self, q: Configs) -> np.ndarray:
        """The triangle's vertices (where the legs are jointed), shape ``(..., 3, 2)``."""
        qq = as_configs(q)
        ang = self.vertex_angles(qq)
        return qq[..., None, 0:2] + self.r * np.stack([np.cos(ang), np.sin(ang)], axis=-1)

    def leg_headings(self, q: Configs) -> np.ndarray:
        """World headings ``ψ_i = θ + α_i + φ_i`` of the legs (and wheels), shape ``(..., 3)``."""
        qq = as_configs(q)
        return self.vertex_angles(qq) + qq[..., 3:6]

    def leg_directions(self, q: Configs) -> np.ndarray:
        """Unit vectors ``(cos ψ_i, sin ψ_i)`` (the wheels' rolling direction), ``(..., 3, 2)``."""
        psi = self.leg_headings(q)
        return np.stack([np.cos(psi), np.sin(psi)], axis=-1)

    def lateral_directions(self, q: Configs) -> np.ndarray:
        """Unit vectors ``n_i = (−sin ψ_i, cos ψ_i)`` (along the axles), ``(..., 3, 2)``."""
        psi = self.leg_headings(q)
        return np.stack([-np.sin(psi), np.cos(psi)], axis=-1)

    def wheels(self, q: Configs) -> np.ndarray:
        """Wheel positions (the legs' free ends) ``W_i``, shape ``(..., 3, 2)``."""
        return self.vertices(q) + self.l * self.leg_directions(q)

    # --- velocities ----------------------------------------------------------------
    def wheel_velocities(self, q: Configs, qdot: Configs) -> np.ndarray:
        """``Ẇ_i`` for configuration velocities ``q̇`` (same shape as ``q``), ``(..., 3, 2)``.

        ``Ẇ_i = (ẋ, ẏ) + r θ̇ J u(θ+α_i) + l (θ̇ + φ̇_i) J u(ψ_i)``, ``J`` the
        rotation by +π/2, ``u(a) = (cos a, sin a)``.
        """
        qq = as_configs(q)
        qd = as_configs(qdot)
        ang = self.vertex_angles(qq)
        psi = ang + qq[..., 3:6]
        thd = qd[..., 2:3]
        vert = self.r * thd[..., None] * np.stack([-np.sin(ang), np.cos(ang)], axis=-1)
        leg = (self.l * (thd + qd[..., 3:6]))[..., None] * np.stack(
            [-np.sin(psi), np.cos(psi)], axis=-1
        )
        return qd[..., None, 0:2] + vert + leg

    def lateral_velocities(self, q: Configs, qdot: Configs) -> np.ndarray:
        """Sideways speed ``n_i · Ẇ_i`` of each wheel (0 = no slip), shape ``(..., 3)``."""
        return np.sum(self.wheel_velocities(q, qdot) * self.lateral_directions(q), axis=-1)

    def constraint_matrix(self, q: Configs) -> np.ndarray:
        """Rows of constraints (C_i): ``A(q) q̇ = 0`` with ``A`` of shape ``(..., 3, 6)``.

        Row ``i`` is ``(−sin ψ_i, cos ψ_i, r cos φ_i + l, l δ_{i1}, l δ_{i2}, l δ_{i3})``;
        ``A(q) q̇`` equals :meth:`lateral_velocities`.
        """
        qq = as_configs(q)
        psi = self.leg_headings(qq)
        out = np.zeros((*qq.shape[:-1], 3, 6))
        out[..., 0] = -np.sin(psi)
        out[..., 1] = np.cos(psi)
        out[..., 2] = self.r * np.cos(qq[..., 3:6]) + self.l
        for i in range(3):
            out[..., i, 3 + i] = self.l
        return out

    def axle_lines(self, q: Configs) -> np.ndarray:
        """Coefficients ``(a, b, c)`` of each axle line ``a X + b Y = c``, shape ``(..., 3, 3)``.

        The axle of wheel ``i`` is the line through ``W_i`` perpendicular to
        its leg: ``(cos ψ_i, sin ψ_i) · P = (cos ψ_i, sin ψ_i) · W_i``.
        """
        e = self.leg_directions(q)
        w = self.wheels(q)
        return np.concatenate([e, np.sum(e * w, axis=-1, keepdims=True)], axis=-1)


@dataclass(frozen=True)
class WheelSlip:
    """How much each wheel slides sideways along a trajectory.

    Attributes
    ----------
    times:
        Sample times, shape ``(T,)``.
    lateral_velocity:
        ``n_i · Ẇ_i`` at each sample, shape ``(T, 3)`` (0 for the true system).
    slip_distance:
        ``∫ |n_i · Ẇ_i| dt`` per wheel (trapezoid rule), shape ``(3,)``: the
        total distance slid sideways.
    net_slip:
        ``∫ n_i · Ẇ_i dt`` per wheel, shape ``(3,)`` (signed).
    max_lateral_speed:
        ``max_t |n_i · Ẇ_i|`` per wheel, shape ``(3,)``.
    velocity_source:
        ``"given"`` (velocities passed in) or ``"finite-difference"``
        (second-order ``numpy.gradient`` of the samples).
    """

    times: np.ndarray
    lateral_velocity: np.ndarray
    slip_distance: np.ndarray
    net_slip: np.ndarray
    max_lateral_speed: np.ndarray
    velocity_source: str

    @property
    def total_slip(self) -> float:
        """Sum over the three wheels of :attr:`slip_distance`."""
        return float(np.sum(self.slip_distance))


def wheel_slip(
    geometry: TridentGeometry,
    trajectory: SampledConfigs,
    times: npt.ArrayLike,
    coords_form: str | None = None,
    *,
    velocities: SampledConfigs | None = None,
) -> WheelSlip:
    r"""Lateral (sideways) velocity of each wheel along a trajectory, and its integral.

    Along a trajectory of the true system every wheel rolls without slipping
    (lateral velocity 0).  Along one that is not (e.g. the nilpotent
    approximation's motion mapped back to the configuration space) the wheels
    must slide sideways: this measures by how much (the paper's closing
    remark, quantified).

    Parameters
    ----------
    geometry:
        The robot (``r``, ``l`` and leg offsets).
    trajectory:
        Configurations ``(x, y, θ, φ1, φ2, φ3)`` at each time, shape ``(T, 6)``.
    times:
        Strictly increasing sample times, shape ``(T,)``, ``T ≥ 3``.
    coords_form:
        The trident form whose coordinates ``trajectory`` is written in; it
        selects the leg offsets used to read it (``"trident-snake-paper"``:
        ``(−2π/3, 0, 2π/3)``; ``"trident-snake"``, ``"trident-snake-joints"``:
        ``(0, 2π/3, 4π/3)``), keeping ``geometry``'s ``r`` and ``l``.
        ``None``: use ``geometry.offsets`` as they are.
    velocities:
        Optional ``q̇`` at each sample (shape ``(T, 6)``), e.g. the fields of
        the system that produced the trajectory times its inputs; otherwise
        ``q̇`` is estimated by second-order finite differences of the samples
        (after unwrapping the angles ``θ, φ_i``, which may be given modulo 2π;
        the samples must be dense enough that no angle moves by π between two).

    Returns
    -------
    WheelSlip

    Raises
    ------
    OptionError
        A trajectory that is not ``(T, 6)`` with ``(T,)`` times, velocities of
        another shape, fewer than 3 samples, or times that do not increase
        strictly.

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> q = np.zeros((11, 6)); q[:, 1] = t          # slide sideways, legs locked
    >>> s = wheel_slip(TridentGeometry(), q, t)
    >>> np.round(s.slip_distance, 6).tolist()        # wheel 1's leg points along x
    [1.0, 0.5, 0.5]
    """
    geom = geometry
    if coords_form is not None:
        geom = TridentGeometry.for_form(coords_form, geometry.r, geometry.l)
    traj = as_configs(trajectory)
    t = np.asarray(times, dtype=float)
    if traj.ndim != 2 or t.ndim != 1 or t.shape[0] != traj.shape[0]:
        raise OptionError(
            f"wheel_slip needs a (T, 6) trajectory and (T,) times, got {traj.shape} and {t.shape}"
        )
    if t.shape[0] < 3:
        raise OptionError(f"wheel_slip needs at least 3 samples, got {t.shape[0]}")
    if not np.all(np.diff(t) > 0):
        raise OptionError("wheel_slip needs strictly increasing times")
    if velocities is None:
        # angles live on the circle: unwrap them so that a jump by 2π is not a velocity
        continuous = traj.copy()
        continuous[:, 2:6] = np.unwrap(traj[:, 2:6], axis=0)
        qdot = np.gradient(continuous, t, axis=0, edge_order=2)
        source = "finite-difference"
    else:
        qdot = as_configs(velocities)
        if qdot.shape != traj.shape:
            raise OptionError(
                f"velocities must have the trajectory's shape {traj.shape}, got {qdot.shape}"
            )
        source = "given"
    lateral = geom.lateral_velocities(traj, qdot)
    return WheelSlip(
        times=t,
        lateral_velocity=lateral,
        slip_distance=np.trapezoid(np.abs(lateral), t, axis=0),
        net_slip=np.trapezoid(lateral, t, axis=0),
        max_lateral_speed=np.max(np.abs(lateral), axis=0),
        velocity_source=source,
    )
