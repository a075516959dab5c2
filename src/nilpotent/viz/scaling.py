"""The error of the nilpotent approximation against the input amplitude, log–log.

The mathematics page, §6: for a periodic input of amplitude ``A`` the error of the
approximation in the privileged coordinates of weight ``w`` is ``O(A^{w+1})``.
:func:`fit_slope` measures the exponent as the least-squares slope of
``log(error)`` against ``log(A)`` (the one fitter,
:func:`nilpotent.numeric.fits.loglog_line`, which the scaling studies use too);
:func:`plot_error_scaling` draws the errors with their fitted lines and slopes
in the legend.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure, SubFigure

from nilpotent.errors import OptionError
from nilpotent.numeric.fits import loglog_line

__all__ = ["fit_slope", "plot_error_scaling"]


def fit_slope(amplitudes: np.ndarray, errors: np.ndarray) -> tuple[float, float]:
    """Least-squares fit ``log10(error) = slope · log10(A) + intercept``.

    Only finite positive errors enter; returns ``(slope, intercept)``.  The fit
    is :func:`nilpotent.numeric.fits.loglog_line` (natural logs; the intercept is
    converted to base 10), the one fitter of the scaling studies and sweeps.

    Parameters
    ----------
    amplitudes : (k,) array_like
        The amplitudes ``A`` (positive).
    errors : (k,) array_like
        The errors at those amplitudes.

    Raises
    ------
    OptionError
        If the arrays differ in shape or are not 1-d, or fewer than two finite
        positive errors remain.

    Examples
    --------
    >>> a = np.array([0.01, 0.02, 0.04])
    >>> round(fit_slope(a, 3 * a**3)[0], 6)
    3.0
    """
    a = np.asarray(amplitudes, dtype=float)
    e = np.asarray(errors, dtype=float)
    if a.shape != e.shape or a.ndim != 1:
        raise OptionError(
            f"amplitudes and errors must be 1-d of the same length, got {a.shape} and {e.shape}"
        )
    keep = np.isfinite(e) & (e > 0) & (a > 0)
    if keep.sum() < 2:
        raise OptionError("need at least two positive finite errors to fit a slope")
    slope, intercept = loglog_line(a[keep], e[keep])
    return float(slope), float(intercept / np.log(10.0))


def plot_error_scaling(
    amplitudes: np.ndarray,
    errors: Mapping[str, np.ndarray],
    *,
    lower_bounds: Mapping[str, float] | None = None,
    title: str | None = None,
    ax: Axes | None = None,
    figsize: tuple[float, float] = (6.4, 4.6),
) -> tuple[Figure | SubFigure, Axes, dict[str, float]]:
    """Errors against amplitude on log–log axes, with fitted slopes.

    Parameters
    ----------
    amplitudes:
        ``(K,)`` input amplitudes ``A`` (radians per second times seconds: the
        loop radius in the input plane, dimensionless here).
    errors:
        Label → ``(K,)`` errors (e.g. ``"weight 1"``, ``"weight 2"``, ``"endpoint"``).
    lower_bounds:
        Label → the least slope theory predicts (``O(A^k)`` means slope ≥ k),
        shown beside the measured one.
    title, ax, figsize:
        Figure title; axes to draw on (default: a new figure).

    Returns
    -------
    (Figure, Axes, dict)
        The figure (the subfigure holding ``ax`` if it is in one), the axes and the
        fitted slope per label.
    """
    from matplotlib.figure import Figure

    a = np.asarray(amplitudes, dtype=float)
    if ax is None:
        fig = Figure(figsize=figsize, layout="constrained")
        ax = fig.subplots()
    else:
        fig = ax.figure
    slopes: dict[str, float] = {}
    markers = "osD^v<>"
    for k, (label, err) in enumerate(errors.items()):
        e = np.asarray(err, dtype=float)
        slope, intercept = fit_slope(a, e)
        slopes[label] = slope
        text = f"{label}: slope {slope:.2f}"
        if lower_bounds and label in lower_bounds:
            text += f" (theory ≥ {lower_bounds[label]:g})"
        (line,) = ax.loglog(a, e, markers[k % len(markers)], label=text)
        ax.loglog(a, 10**intercept * a**slope, "-", color=line.get_color(), linewidth=0.8)
    from matplotlib.ticker import LogLocator, NullFormatter, ScalarFormatter

    ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("amplitude A of the periodic input")
    ax.set_ylabel("error after one period (lengths / r, angles rad)")
    ax.grid(True, which="both", linewidth=0.3, alpha=0.5)
    if errors:  # no series (every group exact): no legend to draw
        ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    return fig, ax, slopes
