r"""How the error of the nilpotent approximation scales with the loop amplitude.

:func:`scaling_study` → :class:`ScalingStudy`: the errors of
:func:`~nilpotent.simulation.comparison.compare_bracket_motion` over a range of
amplitudes (one batch through the pair engine) and their fitted log–log slopes
per weight group (expected $w_j + 1$, the mathematics page, §6 — measured here, not assumed;
:mod:`nilpotent.numeric.fits`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.core.model.points import format_point
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import OptionError
from nilpotent.numeric.fits import loglog_slope
from nilpotent.numeric.settings import IntegrationSettings, resolve_settings
from nilpotent.numeric.signals import bracket_signal, check_bracket
from nilpotent.simulation.comparison import (
    BRACKET_SETTINGS,
    bracket_run,
    floats,
    prepare_comparison,
)
from nilpotent.strict_json import json_object

__all__ = ["DEFAULT_AMPLITUDES", "ScalingStudy", "scaling_study"]


#: Default amplitudes of :func:`scaling_study` (factors of 2).
DEFAULT_AMPLITUDES: tuple[float, ...] = (0.01, 0.02, 0.04, 0.08, 0.16)


@dataclass(frozen=True, eq=False)
class ScalingStudy:
    r"""Errors of the nilpotent approximation against the amplitude, per weight group.

    Attributes
    ----------
    system, approximation, point, bracket, omega, periods:
        What was simulated (as in :class:`Comparison`).
    amplitudes:
        ``(k,)`` amplitudes $A$.
    weights:
        The weights $w_j$.
    errors:
        weight $w$ → ``(k,)``: $\max_t \max_{w_j = w}|y_j - \hat y_j|$ per amplitude.
    slopes:
        weight $w$ → least-squares slope of $\log(\text{error})$ against
        $\log A$, or ``None`` where fewer than two errors are above the
        integration noise floor (the approximation is exact there).
    expected_slopes:
        weight $w$ → $w + 1$ (the mathematics page, §6).
    floor:
        The noise floor used: errors below it are not fitted.
    tolerance:
        Accuracy of the integrations.
    engine:
        The integration engine that computed the trajectories.
    """

    system: ControlSystem
    approximation: Any
    point: tuple[sp.Expr, ...]
    bracket: tuple[int, int]
    omega: float
    periods: int
    amplitudes: np.ndarray
    weights: tuple[int, ...]
    errors: dict[int, np.ndarray]
    slopes: dict[int, float | None]
    expected_slopes: dict[int, int]
    floor: float
    tolerance: float
    engine: str = ""

    def to_json(self) -> dict[str, Any]:
        """The ``nilpotent/scaling@1`` JSON object."""
        return json_object({
            "schema": "nilpotent/scaling@1",
            "model": self.system.name,
            "coordinates": list(self.system.coordinate_names),
            "point": format_point(self.system, self.point),
            "bracket": list(self.bracket),
            "omega": self.omega,
            "periods": self.periods,
            "weights": list(self.weights),
            "amplitudes": floats(self.amplitudes),
            "errors": {str(w): floats(e) for w, e in self.errors.items()},
            "slopes": {str(w): s for w, s in self.slopes.items()},
            "expected_slopes": {str(w): s for w, s in self.expected_slopes.items()},
            "floor": self.floor,
            "tolerance": self.tolerance,
        })

    def plot(self, ax: Any = None) -> tuple[Any, Any]:
        """Log–log errors per weight group with the fitted lines; returns ``(figure, axes)``
        (:func:`nilpotent.viz.simulation.plot_scaling_study`)."""
        from nilpotent.viz.simulation import plot_scaling_study

        return plot_scaling_study(self, ax)


def scaling_study(
    sys: ControlSystem,
    bracket: Sequence[int],
    amplitudes: Sequence[float] = DEFAULT_AMPLITUDES,
    *,
    omega: float = 1.0,
    periods: int = 1,
    point: Any = None,
    approximation: Any = None,
    samples: int = 101,
    settings: IntegrationSettings | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    engine: str | None = None,
) -> ScalingStudy:
    r"""Measure how the approximation error scales with the amplitude, per weight group.

    All amplitudes are simulated as one batch (original and approximation).
    The slope of each group is fitted by least squares on the errors above
    the noise floor ``1e3·(atol + rtol·max|y|)``.

    Parameters
    ----------
    sys : ControlSystem
        The original system.
    bracket : tuple of int
        ``(I, J)``, 1-based, different.
    omega : float
        The input's frequency (as in :func:`compare_bracket_motion`).
    periods : int
        Periods of the input.
    point : sequence or mapping, optional
        The start $p$ (default the origin).
    approximation : NilpotentApproximation, optional
        The approximation to compare with (default: the one at ``point``).
    samples : int
        Sample times per run.
    settings : IntegrationSettings or None
        How to integrate (default
        :data:`~nilpotent.simulation.comparison.BRACKET_SETTINGS`).
    rtol, atol, engine : optional
        The loose form of ``settings``, kept for one release.
    amplitudes : sequence of float
        Positive amplitudes, at least two different values.

    Raises
    ------
    OptionError
        Fewer than two different amplitudes, a non-positive one, or a bad bracket or input.
    IntegrationError
        A simulation stopped before the end.
    """
    chosen = resolve_settings(settings, BRACKET_SETTINGS, rtol=rtol, atol=atol, engine=engine)
    amps = np.asarray([float(a) for a in amplitudes])
    if amps.size < 2 or np.unique(amps).size < 2:
        raise OptionError("a scaling study needs at least two different amplitudes")
    if not np.all(np.isfinite(amps)) or np.any(amps <= 0):
        raise OptionError("amplitudes must be > 0")
    for a in amps:
        bracket_signal(sys.m, *check_bracket(sys.m, bracket), float(a), omega, periods)
    sysp, pair_ij, pt, approx, p = prepare_comparison(sys, bracket, point, approximation)
    run = bracket_run(sysp, approx, p, pair_ij, amps, omega, periods, samples, settings=chosen)
    original_y = run.y()
    diff = np.abs(original_y - run.y_hat)  # (k, T, n)
    scale = float(np.nanmax(np.abs(original_y))) if original_y.size else 0.0
    floor = 1e3 * (chosen.atol + chosen.rtol * scale)
    weights = run.pair.weights
    errors = run.by_weight(diff, (1,))
    slopes = {w: loglog_slope(amps, err, floor) for w, err in errors.items()}
    return ScalingStudy(
        system=sysp,
        approximation=approx,
        point=pt,
        bracket=pair_ij,
        omega=float(omega),
        periods=int(periods),
        amplitudes=amps,
        weights=weights,
        errors=errors,
        slopes=slopes,
        expected_slopes={w: w + 1 for w in errors},
        floor=floor,
        tolerance=run.tolerance,
        engine=run.engines[0],
    )
