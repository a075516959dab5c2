r"""Log–log fits: the measured exponent of a power law $e \approx C A^s$.

The scaling of the nilpotent approximation's error with the loop amplitude
(the mathematics page, §6: $O(A^{w+1})$ in the privileged coordinates of weight $w$) is
measured, never assumed, as the least-squares slope of $\log e$ against
$\log A$ over the errors above the integration noise floor (the model for
convergence orders fitted from slopes: diffrax's tests).
"""

from __future__ import annotations

import numpy as np

__all__ = ["loglog_line", "loglog_slope"]


def loglog_line(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    r"""``(slope, intercept)`` of the least-squares line $\log y = s \log x + c$ (natural logs).

    ``x`` and ``y`` are ``(k,)`` positive arrays, ``k ≥ 2`` with two different ``x``.
    """
    return np.polyfit(np.log(np.asarray(x, dtype=float)), np.log(np.asarray(y, dtype=float)), 1)


def loglog_slope(x: np.ndarray, y: np.ndarray, floor: float = 0.0) -> float | None:
    r"""The slope $s$ of $\log y$ on $\log x$ over the points with finite ``y > floor``.

    Parameters
    ----------
    x, y : (k,) array_like
        The abscissae (positive) and the values.
    floor : float
        Values at or below it are noise and not fitted.

    Returns
    -------
    float or None
        The slope; ``None`` where fewer than two different ``x`` remain (the
        errors are at the noise floor: the approximation is exact there).

    Examples
    --------
    >>> round(loglog_slope(np.array([0.1, 0.2, 0.4]), np.array([1e-3, 8e-3, 6.4e-2])), 12)
    3.0
    """
    xs = np.asarray(x, dtype=float)
    ys = np.asarray(y, dtype=float)
    keep = np.isfinite(ys) & (ys > floor)
    if np.unique(xs[keep]).size < 2:
        return None
    return float(loglog_line(xs[keep], ys[keep])[0])
