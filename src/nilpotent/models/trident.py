r"""The trident snake robot: three kinematic forms and the robot's geometry.

The robot (Ishikawa 2004; the paper's Sections 3–4)::

                        wheel 2
                          ‖
                           \  leg 2 (length l, joint angle φ2)
                            \
                    vertex 2 ●
                            / \
                           /   \          body: equilateral triangle,
          wheel 1 ═══ ● ──●  +  \         circumradius r, centre (x, y),
                  leg 1  vertex1 \        heading θ (towards vertex 1)
                           \     /
                            \   /
                             ● vertex 3
                            /
                           /  leg 3
                          ‖
                        wheel 3

Configuration ``q = (x, y, θ, φ1, φ2, φ3)``.  Leg ``i`` is attached at the
vertex of polar angle ``α_i`` in the body frame (``α = (0, 2π/3, 4π/3)``),
``φ_i`` is the joint angle (0 = leg pointing radially outwards), and
``ψ_i = θ + α_i + φ_i`` is the leg's heading in the world.  Its wheel is at

    ``W_i = (x, y) + r (cos(θ+α_i), sin(θ+α_i)) + l (cos ψ_i, sin ψ_i)``.

**No side slip.**  Differentiating,
``Ẇ_i = (ẋ, ẏ) + r θ̇ (−sin(θ+α_i), cos(θ+α_i)) + l (θ̇ + φ̇_i)(−sin ψ_i, cos ψ_i)``.
The wheel may only roll along its leg ``(cos ψ_i, sin ψ_i)``, so the
component of ``Ẇ_i`` along the lateral direction ``n_i = (−sin ψ_i, cos ψ_i)``
vanishes; since ``sin ψ_i sin(θ+α_i) + cos ψ_i cos(θ+α_i) = cos φ_i``:

    ``−sin ψ_i ẋ + cos ψ_i ẏ + (r cos φ_i + l) θ̇ + l φ̇_i = 0``    (C_i)

(this is ``MATH.md`` §8's constraint, re-derived here).  Three forms solve
(C_1..C_3) for ``q̇`` with different inputs:

* :func:`trident_snake` — **body-velocity inputs** ``(v1, v2, v3)`` = forward
  and sideways speed in the body frame and turning rate:
  ``(ẋ, ẏ) = R_θ (v1, v2)``, ``θ̇ = v3``; then
  ``−sin ψ_i ẋ + cos ψ_i ẏ = −v1 sin(α_i+φ_i) + v2 cos(α_i+φ_i)`` and (C_i) gives
  ``φ̇_i = (v1 sin(α_i+φ_i) − v2 cos(α_i+φ_i) − (r cos φ_i + l) v3) / l``.
  With ``r = l = 1`` these are exactly the paper's Section 4 fields
  ``g1, g2, g3`` (angles 0, 2π/3, 4π/3).
* :func:`trident_snake_paper` — the paper's simplified eq. ``(vf)`` in
  ``x1..x6``, as printed.  It is *not* the body form: ``R_θ`` is dropped
  (``ẋ1 = u1``, ``ẋ2 = u2`` in the world frame while the leg terms keep the
  body angle ``α_i + φ_i`` instead of the world angle ``ψ_i``), and the angle
  offsets are ``(−2π/3, 0, 2π/3)`` instead of ``(0, 2π/3, 4π/3)``.  Read with
  those offsets it satisfies (C_i) exactly on ``θ = 0 (mod 2π)`` only; see
  :func:`constraint_residuals`.
* :func:`trident_snake_joints` — **joint-velocity inputs** ``u_i = φ̇_i`` (the
  motors): (C) reads ``M(q) (ẋ, ẏ, θ̇)ᵀ = −l u`` with rows
  ``M_i = (−sin ψ_i, cos ψ_i, r cos φ_i + l)``, solved by Cramer's rule.  ``M_i``
  are the homogeneous coordinates of wheel ``i``'s *axle line* (through
  ``W_i`` along ``n_i``), so ``det M = 0`` exactly when the three axles meet
  in one point or are parallel; see :func:`joint_singularity`.

The geometry (:class:`TridentGeometry`: body centre, vertices, wheels,
headings, for one configuration or arrays of shape ``(..., 6)``), the slip of
the wheels along a trajectory that does not come from the true system
(:func:`wheel_slip`, the paper's closing remark measured), and the singular
sets of the joint and paper forms live here too.  This module uses numpy
(``nilpotent.core`` does not).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import sympy as sp

from nilpotent.core.expressions import as_expr
from nilpotent.core.system import ControlSystem
from nilpotent.errors import ModelError, OptionError

__all__ = [
    "BODY_LEG_ANGLES",
    "FORMS",
    "PAPER_LEG_ANGLES",
    "Configs",
    "JointSingularity",
    "PaperSingularity",
    "Trajectory",
    "TridentGeometry",
    "WheelSlip",
    "constraint_residuals",
    "joint_determinant",
    "joint_singular_locus",
    "joint_singularity",
    "paper_singular_determinant",
    "paper_singular_locus",
    "paper_singularity",
    "trident_snake",
    "trident_snake_joints",
    "trident_snake_paper",
    "wheel_slip",
]

#: Polar angles of the legs' vertices in the body frame (the paper's Section 4).
BODY_LEG_ANGLES: tuple[sp.Expr, ...] = (sp.Integer(0), 2 * sp.pi / 3, 4 * sp.pi / 3)
#: The angle offsets that the paper's simplified eq. (vf) uses instead.
PAPER_LEG_ANGLES: tuple[sp.Expr, ...] = (-2 * sp.pi / 3, sp.Integer(0), 2 * sp.pi / 3)
#: The three built-in forms, by model name.
FORMS: tuple[str, ...] = ("trident-snake", "trident-snake-paper", "trident-snake-joints")

_ONE = sp.Integer(1)
_ZERO = sp.Integer(0)

#: Configurations ``(x, y, θ, φ1, φ2, φ3)``: array-like of shape ``(..., 6)``.
Configs = npt.ArrayLike
#: A trajectory: array-like of shape ``(T, 6)``; its times: shape ``(T,)``.
Trajectory = npt.ArrayLike


def _symbols() -> tuple[tuple[sp.Symbol, ...], sp.Symbol, sp.Symbol]:
    coords = sp.symbols("x y theta phi1 phi2 phi3")
    return tuple(coords), sp.Symbol("r"), sp.Symbol("l")


def trident_snake() -> ControlSystem:
    r"""Trident snake with body-velocity inputs (the paper's Section 4, general ``r``, ``l``).

    Coordinates ``(x, y, theta, phi1, phi2, phi3)``; parameters ``r`` (body
    circumradius) and ``l`` (leg length), default 1.  With
    $\beta_i = \alpha_i + \varphi_i$ and $\alpha = (0, 2\pi/3, 4\pi/3)$:

    * $X_1 = \cos\theta\,\partial_x + \sin\theta\,\partial_y
      + \sum_i \tfrac{\sin\beta_i}{l}\,\partial_{\varphi_i}$ (forward),
    * $X_2 = -\sin\theta\,\partial_x + \cos\theta\,\partial_y
      - \sum_i \tfrac{\cos\beta_i}{l}\,\partial_{\varphi_i}$ (sideways),
    * $X_3 = \partial_\theta - \sum_i \tfrac{r\cos\varphi_i + l}{l}\,\partial_{\varphi_i}$ (turn).

    Derivation: module docstring.  Every field satisfies the three
    no-side-slip constraints identically.  The growth vector is $(3, 6)$ at
    every point: $[X_1, X_2] = l^{-2}\sum_i\partial_{\varphi_i}$,
    $[X_2, X_3] - X_1$ and $[X_1, X_3] + X_2$ have $\varphi$-components
    $r l^{-2}\sin\alpha_i$ and $r l^{-2}\cos\alpha_i$, whose 3×3 determinant
    with $(1, 1, 1)$ is the nonzero constant $r^2 l^{-6}\det(1, \sin\alpha_i,
    \cos\alpha_i)$.

    Examples
    --------
    >>> s = trident_snake()
    >>> s.specialized_fields[2][3]
    -cos(phi1) - 1
    """
    (x, y, th, *phis), r, l = _symbols()
    f1: list[sp.Expr] = [sp.cos(th), sp.sin(th), _ZERO]
    f2: list[sp.Expr] = [-sp.sin(th), sp.cos(th), _ZERO]
    f3: list[sp.Expr] = [_ZERO, _ZERO, _ONE]
    for alpha, phi in zip(BODY_LEG_ANGLES, phis, strict=True):
        f1.append(sp.sin(phi + alpha) / l)
        f2.append(-sp.cos(phi + alpha) / l)
        f3.append(-(r * sp.cos(phi) + l) / l)
    return ControlSystem(
        "trident-snake",
        (x, y, th, *phis),
        (tuple(f1), tuple(f2), tuple(f3)),
        (("r", _ONE), ("l", _ONE)),
        "trident snake robot, body-velocity inputs (paper Sec. 4); growth (3,6) everywhere",
    )


def trident_snake_paper() -> ControlSystem:
    r"""The paper's simplified trident snake, eq. ``(vf)``, exactly as printed: ``x1..x6``.

    * $g_1 = \partial_{x_1} + \sin(x_4 - \tfrac{2\pi}{3})\partial_{x_4}
      + \sin x_5\,\partial_{x_5} + \sin(x_6 + \tfrac{2\pi}{3})\partial_{x_6}$,
    * $g_2 = \partial_{x_2} - \cos(x_4 - \tfrac{2\pi}{3})\partial_{x_4}
      - \cos x_5\,\partial_{x_5} - \cos(x_6 + \tfrac{2\pi}{3})\partial_{x_6}$,
    * $g_3 = \partial_{x_3} - (1 + \cos x_4)\partial_{x_4}
      - (1 + \cos x_5)\partial_{x_5} - (1 + \cos x_6)\partial_{x_6}$.

    (sympy stores e.g. $\sin(x_6 + 2\pi/3)$ as $\sin(x_6 + \pi/3)\cdot$…
    canonical forms; the values are identical.)  No parameters (``r = l = 1``
    is built in).

    **Not equivalent to** :func:`trident_snake`.  Two differences: the
    rotation $R_\theta$ is dropped (the planar velocity is $(u_1, u_2)$ in
    the world frame while the leg terms use the body angle
    $c_i + x_{3+i}$, not the world heading), and the offsets are
    $c = (-2\pi/3, 0, 2\pi/3)$, not $(0, 2\pi/3, 4\pi/3)$.  Consequences,
    each checked in the tests and in :func:`constraint_residuals`:

    * read with its own offsets $c$, $g_3$ satisfies the no-slip constraints
      everywhere, $g_1$, $g_2$ only on $\theta = x_3 \equiv 0$; elsewhere the
      lateral velocity of wheel $i$ is $-\sin(x_3 + \beta_i) + \sin\beta_i$
      (along $g_1$) and $\cos(x_3 + \beta_i) - \cos\beta_i$ (along $g_2$), of
      joint size $2|\sin(x_3/2)|$ per wheel, $\beta_i = c_i + x_{3+i}$;
    * read with the Section 4 placement $(0, 2\pi/3, 4\pi/3)$ the joint size
      is $2|\sin(x_3/2 + \pi/3)|$, i.e. $\sqrt3$ already at the origin;
    * its brackets differ: $[g_2, g_3]$ and $[g_1, g_3]$ have no
      $\partial_{x_1}, \partial_{x_2}$ components (the body form's have
      $\cos\theta\,\partial_x + \sin\theta\,\partial_y$ and
      $\sin\theta\,\partial_x - \cos\theta\,\partial_y$), and its growth vector
      drops below $(3, 6)$ where the points $e^{ic_i}(1 + e^{ix_{3+i}})$ (the
      wheels' body-frame positions) are collinear (:func:`paper_singularity`).

    Examples
    --------
    >>> trident_snake_paper().fields[2][3]
    -cos(x4) - 1
    """
    xs = sp.symbols("x1 x2 x3 x4 x5 x6")
    third = 2 * sp.pi / 3
    x4, x5, x6 = xs[3:]
    g1 = (_ONE, _ZERO, _ZERO, sp.sin(x4 - third), sp.sin(x5), sp.sin(x6 + third))
    g2 = (_ZERO, _ONE, _ZERO, -sp.cos(x4 - third), -sp.cos(x5), -sp.cos(x6 + third))
    g3 = (_ZERO, _ZERO, _ONE, -(1 + sp.cos(x4)), -(1 + sp.cos(x5)), -(1 + sp.cos(x6)))
    return ControlSystem(
        "trident-snake-paper",
        tuple(xs),
        (g1, g2, g3),
        (),
        "trident snake, the paper's simplified eq. (vf) as printed (R_theta dropped: "
        "not the body form)",
    )


def _joint_parts(
    r: sp.Expr, l: sp.Expr, th: sp.Expr, phis: Sequence[sp.Expr]
) -> tuple[list[sp.Expr], list[sp.Expr], sp.Expr]:
    """Headings ``ψ_i``, coefficients ``c_i = r cos φ_i + l`` and ``det M``."""
    psis = [th + a + p for a, p in zip(BODY_LEG_ANGLES, phis, strict=True)]
    cs = [r * sp.cos(p) + l for p in phis]
    # det M = Σ_cyclic c_i sin(ψ_k − ψ_j), (i, j, k) cyclic; θ cancels in ψ_k − ψ_j.
    det = sp.Integer(0)
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        diff = (BODY_LEG_ANGLES[k] - BODY_LEG_ANGLES[j]) + phis[k] - phis[j]
        det += cs[i] * sp.sin(diff)
    return psis, cs, det


def trident_snake_joints() -> ControlSystem:
    r"""Trident snake with joint-velocity inputs ``u_i = φ̇_i`` (the motors' rates).

    Coordinates ``(x, y, theta, phi1, phi2, phi3)``, parameters ``r``, ``l``
    (default 1).  The constraints (C_i) read $M(q)\,(\dot x, \dot y,
    \dot\theta)^T = -l\,u$ with rows $M_i = (-\sin\psi_i, \cos\psi_i, c_i)$,
    $c_i = r\cos\varphi_i + l$.  Column $i$ of $M^{-1}$ is $(M_j \times M_k)/D$
    for $(i, j, k)$ cyclic (Cramer), with

    $D = \det M = \sum_{(i,j,k)\ \mathrm{cyclic}} c_i \sin(\psi_k - \psi_j)
    = \sum c_i \sin(\tfrac{2\pi}{3} + \varphi_k - \varphi_j)$ (independent of
    $\theta$), hence

    $X_i = -\tfrac{l}{D}\big[(c_k\cos\psi_j - c_j\cos\psi_k)\partial_x
    + (c_k\sin\psi_j - c_j\sin\psi_k)\partial_y
    + \sin(\psi_k - \psi_j)\partial_\theta\big] + \partial_{\varphi_i}$.

    The fields are rational in sines and cosines with denominator $D$; they
    are undefined where $D = 0$: the three axle lines (through $W_i$,
    perpendicular to leg $i$; $M_i$ are their homogeneous line coordinates
    relative to the body centre) are concurrent or all parallel.  Then a
    rigid motion of the robot with the joints locked (about the common point,
    or a translation) is compatible with all three wheels, and the motors can
    no longer set all three joint rates independently.  At $\varphi = 0$,
    $D = \tfrac{3\sqrt3}{2}(r + l) \ne 0$.  Where $D \ne 0$ the fields span the
    same distribution as :func:`trident_snake` (a feedback transformation),
    so the growth vector is $(3, 6)$ there too.

    Examples
    --------
    >>> s = trident_snake_joints()
    >>> s.fields[0][3], s.fields[0][4]
    (1, 0)
    """
    (x, y, th, *phis), r, l = _symbols()
    psis, cs, det = _joint_parts(r, l, th, phis)
    fields = []
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        fx = -l * (cs[k] * sp.cos(psis[j]) - cs[j] * sp.cos(psis[k])) / det
        fy = -l * (cs[k] * sp.sin(psis[j]) - cs[j] * sp.sin(psis[k])) / det
        ft = -l * sp.sin(psis[k] - psis[j]) / det
        joint = [_ONE if a == i else _ZERO for a in range(3)]
        fields.append((fx, fy, ft, *joint))
    return ControlSystem(
        "trident-snake-joints",
        (x, y, th, *phis),
        tuple(fields),
        (("r", _ONE), ("l", _ONE)),
        "trident snake, joint-velocity inputs (the motors); singular where the wheel axles "
        "are concurrent or parallel",
    )


# --------------------------------------------------------------------------------------
# Symbolic: constraint residuals and singular loci
# --------------------------------------------------------------------------------------


def _form_of(system: ControlSystem) -> str:
    base = system.name.partition(":")[0]
    if base in FORMS:
        return base
    if system.n != 6:
        raise ModelError(
            f"model {system.name!r} is not a trident snake form "
            f"(6 coordinates x, y, theta, phi1..phi3 expected, got {system.n})"
        )
    return "trident-snake"


def _offsets_for(form: str) -> tuple[sp.Expr, ...]:
    return PAPER_LEG_ANGLES if form == "trident-snake-paper" else BODY_LEG_ANGLES


def constraint_residuals(
    system: ControlSystem, offsets: Sequence[sp.Expr] | None = None
) -> tuple[tuple[sp.Expr, ...], ...]:
    r"""Lateral velocity of each wheel along each field (0 iff no side slip).

    ``result[a][i]`` is the left-hand side of constraint (C_i) evaluated on the
    field $X_{a+1}$:

    $-\sin\psi_i X^x + \cos\psi_i X^y + (r\cos\varphi_i + l) X^\theta + l X^{\varphi_i}$,
    $\psi_i = \theta + \text{offset}_i + \varphi_i$,

    with ``r``, ``l`` the system's parameter values (1 for the paper form).
    Coordinates are read in order ``(x, y, θ, φ1, φ2, φ3)`` (``x1..x6`` for the
    paper form).

    Parameters
    ----------
    system:
        A trident snake form (or any system on those six coordinates).
    offsets:
        The legs' angle offsets $\alpha_i$; default: the form's own
        (:data:`PAPER_LEG_ANGLES` for the paper form, else :data:`BODY_LEG_ANGLES`).

    Examples
    --------
    >>> res = constraint_residuals(trident_snake_paper())
    >>> res[0][1]
    sin(x5) - sin(x3 + x5)
    """
    form = _form_of(system)
    offs = tuple(offsets) if offsets is not None else _offsets_for(form)
    values = system.parameter_values
    r = values.get("r", _ONE)
    l = values.get("l", _ONE)
    _, _, th, *phis = system.coordinates
    out = []
    for f in system.specialized_fields:
        row = []
        for i, (a, p) in enumerate(zip(offs, phis, strict=True)):
            psi = th + a + p
            expr = -sp.sin(psi) * f[0] + sp.cos(psi) * f[1] + (r * sp.cos(p) + l) * f[2]
            row.append(sp.expand(expr + l * f[3 + i]))
        out.append(tuple(row))
    return tuple(out)


def joint_singular_locus() -> sp.Expr:
    r"""$D(\varphi) = \det M$ of the joint-velocity form, symbolic in ``phi1..phi3``, ``r``, ``l``.

    $D = \sum_{(i,j,k)\ \mathrm{cyclic}} (r\cos\varphi_i + l)
    \sin(\tfrac{2\pi}{3} + \varphi_k - \varphi_j)$; the joint form is singular on
    $D = 0$ (axles concurrent or parallel).

    Examples
    --------
    >>> joint_singular_locus().subs({"phi1": 0, "phi2": 0, "phi3": 0, "r": 1, "l": 1})
    3*sqrt(3)
    """
    (_, _, th, *phis), r, l = _symbols()
    return _joint_parts(r, l, th, phis)[2]


def paper_singular_locus() -> sp.Expr:
    r"""Where the paper form's brackets stop spanning: a function of ``x4, x5, x6``.

    For eq. (vf), $g_a$ have the constant $(x_1, x_2, x_3)$-part $e_a$ and
    $\varphi_i$-components depending on $x_{3+i}$ only, so (with the bracket
    $[X, Y] = DY\cdot X - DX\cdot Y$) the brackets have no
    $\partial_{x_1..x_3}$-part and, with $\beta_i = c_i + x_{3+i}$:
    $[g_1, g_2] = \sum_i \partial_{x_{3+i}}$,
    $[g_2, g_3] = \sum_i (\sin\beta_i + \sin c_i)\partial_{x_{3+i}}$,
    $[g_1, g_3] = \sum_i (\cos\beta_i + \cos c_i)\partial_{x_{3+i}}$.
    The determinant of the frame $(g_1, g_2, g_3, [g_1,g_2], [g_2,g_3],
    [g_1,g_3])$ is therefore the 3×3 determinant with rows
    $(1, \sin\beta_i + \sin c_i, \cos\beta_i + \cos c_i)$, returned here.  It
    vanishes iff the three points $p_i = e^{ic_i}(1 + e^{ix_{3+i}})$ (the
    wheels' positions in the body frame for $r = l = 1$) are collinear; there
    the growth vector drops below $(3, 6)$ (all length-3 brackets are then
    needed).  At the origin it equals $-6\sqrt3$.

    Examples
    --------
    >>> sp.nsimplify(paper_singular_locus().subs({"x4": 0, "x5": 0, "x6": 0}))
    -6*sqrt(3)
    """
    phis = sp.symbols("x4 x5 x6")
    rows = []
    for c, p in zip(PAPER_LEG_ANGLES, phis, strict=True):
        rows.append([_ONE, sp.sin(p + c) + sp.sin(c), sp.cos(p + c) + sp.cos(c)])
    return as_expr(sp.Matrix(rows).det())


# --------------------------------------------------------------------------------------
# Numeric geometry
# --------------------------------------------------------------------------------------

def _float_angles(angles: Sequence[sp.Expr | float]) -> tuple[float, float, float]:
    a, b, c = (float(v) for v in angles)
    return (a, b, c)


_FLOAT_OFFSETS = {"body": _float_angles(BODY_LEG_ANGLES), "paper": _float_angles(PAPER_LEG_ANGLES)}


def _configs(q: Configs) -> np.ndarray:
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
    offsets: tuple[float, float, float] = _FLOAT_OFFSETS["body"]

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
        return cls(r, l, _FLOAT_OFFSETS[key])

    @classmethod
    def from_system(cls, system: ControlSystem) -> TridentGeometry:
        """The geometry of a built-in trident form, with its ``r`` and ``l`` values."""
        form = _form_of(system)
        values = system.parameter_values
        return cls.for_form(form, float(values.get("r", 1)), float(values.get("l", 1)))

    # --- positions -----------------------------------------------------------------
    def body_centre(self, q: Configs) -> np.ndarray:
        """Centre of the body (the circumcentre), shape ``(..., 2)``."""
        return _configs(q)[..., 0:2].copy()

    def vertex_angles(self, q: Configs) -> np.ndarray:
        """World polar angles ``θ + α_i`` of the three vertices, shape ``(..., 3)``."""
        qq = _configs(q)
        return qq[..., 2:3] + np.asarray(self.offsets)

    def vertices(self, q: Configs) -> np.ndarray:
        """The triangle's vertices (where the legs are jointed), shape ``(..., 3, 2)``."""
        qq = _configs(q)
        ang = self.vertex_angles(qq)
        return qq[..., None, 0:2] + self.r * np.stack([np.cos(ang), np.sin(ang)], axis=-1)

    def leg_headings(self, q: Configs) -> np.ndarray:
        """World headings ``ψ_i = θ + α_i + φ_i`` of the legs (and wheels), shape ``(..., 3)``."""
        qq = _configs(q)
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
        qq = _configs(q)
        qd = _configs(qdot)
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
        qq = _configs(q)
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


# --------------------------------------------------------------------------------------
# Slip along a trajectory
# --------------------------------------------------------------------------------------


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
    trajectory: Trajectory,
    times: npt.ArrayLike,
    coords_form: str | None = None,
    *,
    velocities: Trajectory | None = None,
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
    traj = _configs(trajectory)
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
        qdot = _configs(velocities)
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


# --------------------------------------------------------------------------------------
# Singularities of the joint and paper forms
# --------------------------------------------------------------------------------------


def joint_determinant(q: Configs, geometry: TridentGeometry | None = None) -> np.ndarray:
    r"""$D = \det M(q)$ of the joint-velocity form, shape ``q.shape[:-1]``.

    $D = \sum_{(i,j,k)\ \mathrm{cyclic}} (r\cos\varphi_i + l)\sin(\psi_k - \psi_j)$
    (the closed form of :func:`trident_snake_joints`; independent of
    $x, y, \theta$).
    """
    geom = geometry or TridentGeometry()
    qq = _configs(q)
    psi = geom.leg_headings(qq)
    c = geom.r * np.cos(qq[..., 3:6]) + geom.l
    out = np.zeros(qq.shape[:-1])
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        out = out + c[..., i] * np.sin(psi[..., k] - psi[..., j])
    return out


@dataclass(frozen=True)
class JointSingularity:
    """Is a configuration singular for the joint-velocity form, and why.

    Attributes
    ----------
    determinant:
        ``det M(q)`` (see :func:`joint_determinant`).
    singular:
        ``|det M| ≤ tol · scale`` with ``scale = (r + l)``.
    kind:
        ``"regular"``, ``"concurrent"`` (the three axles meet in one point) or
        ``"parallel"`` (the three axles are parallel).
    point:
        Where the axles meet (world frame) for ``"concurrent"``, else ``None``.
    description:
        One sentence for users.
    """

    determinant: float
    singular: bool
    kind: str
    point: tuple[float, float] | None
    description: str


def joint_singularity(
    q: Configs, geometry: TridentGeometry | None = None, *, tol: float = 1e-9
) -> JointSingularity:
    """Detect and describe a singularity of the joint-velocity form at one configuration.

    The joint form solves ``M(q)(ẋ, ẏ, θ̇) = −l φ̇``; ``M`` is singular exactly
    when some rigid motion of the robot with locked joints keeps every wheel
    rolling: a rotation about a point on all three axles (the axles are
    concurrent) or a translation along all three legs (the axles are
    parallel).

    Examples
    --------
    >>> import math
    >>> q = [0, 0, 0, math.pi / 2, -math.pi / 6, -5 * math.pi / 6]   # all legs along +y
    >>> joint_singularity(q).kind
    'parallel'
    """
    geom = geometry or TridentGeometry()
    qq = _configs(q)
    if qq.ndim != 1:
        raise OptionError(f"joint_singularity takes one configuration, got shape {qq.shape}")
    det = float(joint_determinant(qq, geom))
    singular = abs(det) <= tol * (geom.r + geom.l)
    lines = geom.axle_lines(qq)
    normals = lines[:, 0:2]
    cross = [
        abs(normals[i, 0] * normals[j, 1] - normals[i, 1] * normals[j, 0])
        for i, j in ((0, 1), (1, 2), (0, 2))
    ]
    if not singular:
        return JointSingularity(
            det, False, "regular", None, f"regular: det M = {det:.6g} (axles form a triangle)"
        )
    if max(cross) <= 1e3 * tol:
        return JointSingularity(
            det,
            True,
            "parallel",
            None,
            "singular: the three wheel axles are parallel (all legs parallel); a translation "
            "along the legs with the joints locked violates no constraint",
        )
    point, *_ = np.linalg.lstsq(normals, lines[:, 2], rcond=None)
    px, py = (round(float(v), 12) + 0.0 for v in point)  # + 0.0 turns -0.0 into 0.0
    return JointSingularity(
        det,
        True,
        "concurrent",
        (px, py),
        f"singular: the three wheel axles meet at ({px:.6g}, {py:.6g}); a rotation about that "
        "point with the joints locked violates no constraint",
    )


def paper_singular_determinant(q: Configs) -> np.ndarray:
    """:func:`paper_singular_locus` evaluated numerically, shape ``q.shape[:-1]``.

    ``q`` holds the paper form's ``x1..x6``; only ``x4..x6`` enter.
    """
    qq = _configs(q)
    c = np.asarray(_FLOAT_OFFSETS["paper"])
    beta = qq[..., 3:6] + c
    s = np.sin(beta) + np.sin(c)
    co = np.cos(beta) + np.cos(c)
    mat = np.stack([np.ones_like(s), s, co], axis=-1)
    return np.linalg.det(mat)


@dataclass(frozen=True)
class PaperSingularity:
    """Does the paper form's frame ``(g1, g2, g3, [g1,g2], [g2,g3], [g1,g3])`` lose rank.

    Attributes
    ----------
    determinant:
        The frame's determinant (:func:`paper_singular_determinant`).
    singular:
        ``|determinant| ≤ tol``.
    wheel_points:
        The body-frame wheel positions ``p_i = e^{ic_i}(1 + e^{i x_{3+i}})``,
        shape ``(3, 2)``; singular iff collinear.
    description:
        One sentence for users.
    """

    determinant: float
    singular: bool
    wheel_points: np.ndarray
    description: str


def paper_singularity(q: Configs, *, tol: float = 1e-9) -> PaperSingularity:
    """Detect and describe where the paper's eq. (vf) fields and brackets lose rank.

    Examples
    --------
    >>> paper_singularity([0, 0, 0, 0, 0, 0]).singular
    False
    """
    qq = _configs(q)
    if qq.ndim != 1:
        raise OptionError(f"paper_singularity takes one configuration, got shape {qq.shape}")
    det = float(paper_singular_determinant(qq))
    c = np.asarray(_FLOAT_OFFSETS["paper"])
    pts = np.stack([np.cos(c) + np.cos(c + qq[3:6]), np.sin(c) + np.sin(c + qq[3:6])], axis=-1)
    singular = abs(det) <= tol
    if singular:
        text = (
            "singular: the wheels' body-frame positions are collinear, so g1, g2, g3 and "
            "their first brackets span only a proper subspace (growth below (3,6))"
        )
    else:
        text = f"regular: frame determinant {det:.6g}, growth (3,6)"
    return PaperSingularity(det, singular, pts, text)
