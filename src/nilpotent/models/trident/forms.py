r"""The trident snake robot: its three kinematic forms and the no-slip constraints.

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

(this is the constraint of the mathematics page, §8, re-derived here).  Three forms solve
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

The geometry of one configuration lives in :mod:`nilpotent.models.trident.geometry`,
the singular sets in :mod:`nilpotent.models.trident.singular`.
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ModelError

__all__ = [
    "BODY_LEG_ANGLES",
    "FORMS",
    "PAPER_LEG_ANGLES",
    "constraint_residuals",
    "form_of",
    "form_symbols",
    "joint_parts",
    "trident_snake",
    "trident_snake_joints",
    "trident_snake_paper",
]

#: Polar angles of the legs' vertices in the body frame (the paper's Section 4).
BODY_LEG_ANGLES: tuple[sp.Expr, ...] = (sp.Integer(0), 2 * sp.pi / 3, 4 * sp.pi / 3)
#: The angle offsets that the paper's simplified eq. (vf) uses instead.
PAPER_LEG_ANGLES: tuple[sp.Expr, ...] = (-2 * sp.pi / 3, sp.Integer(0), 2 * sp.pi / 3)
#: The three built-in forms, by model name.
FORMS: tuple[str, ...] = ("trident-snake", "trident-snake-paper", "trident-snake-joints")

_ONE = sp.Integer(1)
_ZERO = sp.Integer(0)


def form_symbols() -> tuple[tuple[sp.Symbol, ...], sp.Symbol, sp.Symbol]:
    """The coordinates ``(x, y, theta, phi1, phi2, phi3)`` and the parameters ``r``, ``l``."""
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
    (x, y, th, *phis), r, l = form_symbols()
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


def joint_parts(
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
    (x, y, th, *phis), r, l = form_symbols()
    psis, cs, det = joint_parts(r, l, th, phis)
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


def form_of(system: ControlSystem) -> str:
    """The built-in form a system is (its name's base), else ``"trident-snake"`` for 6 coordinates.

    Raises
    ------
    ModelError
        A system that is not on the six trident coordinates.
    """
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
    form = form_of(system)
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
