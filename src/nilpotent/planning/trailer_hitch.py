"""The hitch limits in the lattice search of :mod:`nilpotent.planning.trailer_lattice`.

The search checks its motions on samples with an extra margin that covers the motion between
them.  On the hitch limits ``|θ0 − θ1|, |θ1 − θ2| ≤ φ_max`` a fixed margin refused every
motion from a state nearer a limit than the margin (a goal at ``φ2 = 1.37``, a start on the
limit) although a motion away from the limit is admissible.  Here the limits are checked
as :meth:`~nilpotent.planning.verify.Checker.valid_motion` checks them (the samples within
the limits and the interpolation bound between them,
:func:`~nilpotent.planning.verify.limits_between`), with the samples kept the margin
inside, or as far inside as the motion's ends are when they are nearer (:func:`limit_slack`):
the search never comes nearer a limit than its ends, and leaves a limit it starts on.

And trailer 2's hitch angle along a drive of the lattice, in closed form (:func:`hitch_flow`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from nilpotent.planning.verify import Checker, limits_between

__all__ = ["hitch_flow", "limit_margin", "limit_slack", "within_limits"]


def limit_margin(checker: Checker, q: np.ndarray) -> np.ndarray:
    """The least margin of the states ``q (N, n)`` to the limits, ``(N,)`` (``+inf``
    without limits; negative outside)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    assert checker.limits is not None
    if not checker.limits:
        return np.full(len(q), np.inf)
    g, lo, hi = checker.limit_values(q)
    return np.minimum(g - lo, hi - g).min(axis=1)


def limit_slack(checker: Checker, margin: float, *ends: np.ndarray) -> float:
    """The margin to the limits that a motion between ``ends`` keeps at its samples:
    ``margin``, or the ends' own least margin when it is smaller (at least 0)."""
    own = float(limit_margin(checker, np.array(ends)).min()) if ends else margin
    return max(0.0, min(margin, own))


def within_limits(checker: Checker, pieces: Sequence[np.ndarray], slack: float) -> np.ndarray:
    """For each piece (the samples ``(N_i, n)`` of one continuous motion, evenly spaced in
    its time), whether its samples keep ``slack`` from the limits and the motion keeps
    within them between the samples (:func:`~nilpotent.planning.verify.limits_between`);
    a piece with a non-finite sample fails.  ``(len(pieces),)`` booleans."""
    assert checker.limits is not None
    out = np.ones(len(pieces), dtype=bool)
    if not checker.limits or not pieces:
        return out
    sizes = [len(p) for p in pieces]
    flat = np.vstack(pieces)
    g, lo, hi = checker.limit_values(flat)
    margins = np.minimum(g - lo, hi - g).min(axis=1)
    start = 0
    for k, size in enumerate(sizes):
        part = slice(start, start + size)
        start += size
        out[k] = bool(np.all(margins[part] >= slack)) and limits_between(g[part], lo, hi)
    return out


def hitch_flow(phi: float, kappa: float, d2: float, s: np.ndarray) -> np.ndarray:
    r"""Trailer 2's hitch angle ``φ2(s)`` after trailer 1 has run the signed arc length
    ``s`` (any shape) on a circle of curvature ``κ``, from ``φ2(0) = phi``: the solution of
    $d\varphi/ds = \kappa - \sin\varphi / d_2$ in closed form (module doc).  With
    $t = \tan(\varphi/2)$, $b = 1/d_2$: for $b^2 \ge \kappa^2$ the roots $r_1 = \kappa /
    (b + \sqrt{b^2-\kappa^2})$, $r_2 = 1/r_1$ give $t = (r_1(r_1 t_0 - 1) - (t_0 - r_1)E) /
    ((r_1 t_0 - 1) - r_1 (t_0 - r_1) E)$, $E = e^{-\sqrt{b^2-\kappa^2}\,s}$; for
    $\kappa^2 > b^2$, $t = b/\kappa + c \tan(\kappa c s / 2 + \arctan((t_0 - b/\kappa)/c))$,
    $c = \sqrt{\kappa^2-b^2}/|\kappa|$.  ``nan`` where ``φ2`` would pass ``±π``.
    """
    s = np.asarray(s, dtype=float)
    b = 1.0 / d2
    t0 = math.tan(phi / 2.0)
    disc = b * b - kappa * kappa
    if abs(disc) < 1e-12:  # a double root r = κ/b: 1/(t - r) = 1/(t0 - r) - κ s/2
        r = kappa / b
        den = 1.0 - kappa * s * (t0 - r) / 2.0
        t = np.where(den > 0, r + (t0 - r) / np.where(den > 0, den, 1.0), np.nan)
    elif disc > 0.0:
        root = math.sqrt(disc)
        r1 = kappa / (b + root)
        e = np.exp(-root * s)
        den = (r1 * t0 - 1.0) - r1 * (t0 - r1) * e  # r1² - 1 < 0 at s = 0; 0 at a pole
        t = np.where(den < 0, (r1 * (r1 * t0 - 1.0) - (t0 - r1) * e) / np.where(
            den < 0, den, -1.0), np.nan)
    else:
        c = math.sqrt(-disc) / abs(kappa)
        arg = kappa * c * s / 2.0 + math.atan((t0 - b / kappa) / c)
        t = np.where(np.abs(arg) < math.pi / 2, b / kappa + c * np.tan(arg), np.nan)
    return 2.0 * np.arctan(t)
