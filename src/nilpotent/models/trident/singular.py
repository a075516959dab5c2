r"""Singular sets of the trident snake's joint-velocity and paper forms.

The joint form (:func:`~nilpotent.models.trident.forms.trident_snake_joints`)
is singular where ``det M(q) = 0``: the three wheel axles are concurrent or
parallel.  The paper's eq. (vf) loses rank where the wheels' body-frame
positions are collinear.  Symbolic loci (sympy) and numeric detectors (numpy)
with a sentence for users.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from nilpotent.core.model.expressions import as_expr
from nilpotent.errors import OptionError
from nilpotent.models.trident.forms import PAPER_LEG_ANGLES, form_symbols, joint_parts
from nilpotent.models.trident.geometry import (
    FLOAT_LEG_ANGLES,
    Configs,
    TridentGeometry,
    as_configs,
)

__all__ = [
    "JointSingularity",
    "PaperSingularity",
    "joint_determinant",
    "joint_singular_locus",
    "joint_singularity",
    "paper_singular_determinant",
    "paper_singular_locus",
    "paper_singularity",
]

_ONE = sp.Integer(1)


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
    (_, _, th, *phis), r, l = form_symbols()
    return joint_parts(r, l, th, phis)[2]


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


def joint_determinant(q: Configs, geometry: TridentGeometry | None = None) -> np.ndarray:
    r"""$D = \det M(q)$ of the joint-velocity form, shape ``q.shape[:-1]``.

    $D = \sum_{(i,j,k)\ \mathrm{cyclic}} (r\cos\varphi_i + l)\sin(\psi_k - \psi_j)$
    (the closed form of :func:`trident_snake_joints`; independent of
    $x, y, \theta$).
    """
    geom = geometry or TridentGeometry()
    qq = as_configs(q)
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
    qq = as_configs(q)
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
    qq = as_configs(q)
    c = np.asarray(FLOAT_LEG_ANGLES["paper"])
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
    qq = as_configs(q)
    if qq.ndim != 1:
        raise OptionError(f"paper_singularity takes one configuration, got shape {qq.shape}")
    det = float(paper_singular_determinant(qq))
    c = np.asarray(FLOAT_LEG_ANGLES["paper"])
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
