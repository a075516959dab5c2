r"""The original system against its nilpotent approximation under one bracket motion.

:func:`compare_bracket_motion` → :class:`Comparison`: the original system and
its nilpotent approximation (:func:`nilpotent.core.coordinates.approximation.approximate`)
from the same point under the periodic bracket input, with the prediction
$p + K\pi A^2 [X_I, X_J](p)$ and the errors per weight group in privileged
coordinates.  Both run through the one pair engine
(:class:`~nilpotent.simulation.pair.CompiledPair`).

Conventions: bracket $[X, Y] = DY\cdot X - DX\cdot Y$; inputs and fields are
numbered from 1 for users; the bracket input for $(I, J)$ is
$u_I = -A\omega\sin\omega t$, $u_J = A\omega\cos\omega t$, all others 0, from
$t = 0$: $(\int u_I, \int u_J)$ runs once per period counter-clockwise round a
circle of area $\pi A^2$.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.core.model.points import format_point
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import IntegrationError, OptionError
from nilpotent.numeric.integrate import Status
from nilpotent.numeric.settings import DEFAULT_SETTINGS, IntegrationSettings, resolve_settings
from nilpotent.numeric.signals import bracket_inputs, bracket_signal, check_bracket
from nilpotent.simulation.pair import CompiledPair, PairRun
from nilpotent.simulation.trajectory import float_point
from nilpotent.strict_json import json_object

__all__ = [
    "BRACKET_SETTINGS", "Comparison", "bracket_run", "bracket_value", "compare_bracket_motion",
]

#: The integration of bracket motions (:func:`compare_bracket_motion`,
#: :func:`nilpotent.simulation.scaling_study`): the one default
#: (:data:`nilpotent.numeric.settings.DEFAULT_SETTINGS`) with ``rtol = 1e-12``,
#: ``atol = 1e-14``, so that the integration error stays far below the
#: ``O(A^{r+1})`` differences measured (a documented override, not a second default).
BRACKET_SETTINGS = DEFAULT_SETTINGS.replace(rtol=1e-12, atol=1e-14)


def bracket_run(
    system: ControlSystem,
    approximation: Any,
    point: np.ndarray,
    bracket: tuple[int, int],
    amplitudes: np.ndarray,
    omega: float,
    periods: int,
    samples: int,
    **settings: Any,
) -> PairRun:
    """Both systems from ``point`` (the approximation from ``y = 0``) under the bracket
    inputs of ``amplitudes`` (one row each); raises :class:`IntegrationError` if one stopped."""
    pair = CompiledPair.build(system, approximation)
    inputs = bracket_inputs(system.m, *bracket, amplitudes, omega=omega, periods=periods)
    times = np.linspace(0.0, 2 * math.pi * periods / omega, int(samples))
    batch = amplitudes.size
    run = pair.run(np.repeat(point[None], batch, 0), inputs, times,
                   y0=np.zeros((batch, system.n)), **settings)
    for label, st in (("original", run.status_original),
                      ("approximation", run.status_approximation)):
        bad = np.flatnonzero(st != Status.SUCCESS)
        if bad.size:
            raise IntegrationError(
                f"the {label} system's simulation stopped early: {Status(int(st[bad[0]])).message}"
            )
    return run


def bracket_value(
    system: ControlSystem, bracket: Sequence[int], point: Sequence[Any]
) -> np.ndarray:
    r"""$[X_I, X_J](p)$ as floats (:func:`nilpotent.core.lie.brackets.word_values_at`)."""
    from nilpotent.core.lie.brackets import word_values_at

    i, j = check_bracket(system.m, bracket)
    (values,) = word_values_at(system, [(i, j)], tuple(point))
    return np.array([float(v) for v in values])


@dataclass(frozen=True, eq=False)
class Comparison:
    r"""The original system and its nilpotent approximation under one bracket motion.

    Attributes
    ----------
    system:
        The original system (parameters substituted).
    approximation:
        The :class:`~nilpotent.core.coordinates.approximation.NilpotentApproximation` used.
    point:
        $p$ (exact), the common start.
    bracket, amplitude, omega, periods:
        The input (module docstring).
    times:
        ``(T,)`` sample times.
    original, approximate:
        ``(T, n)`` both trajectories in the model coordinates (the
        approximation is integrated in privileged coordinates $y$ from 0 and
        mapped back with ``coordinates.inverse``).
    original_y, approximate_y:
        ``(T, n)`` both in privileged coordinates (the original mapped with
        ``coordinates.forward``).
    weights:
        $w_1 \le \dots \le w_n$.
    bracket_value:
        $[X_I, X_J](p)$.
    prediction:
        $p + K\pi A^2 [X_I, X_J](p)$.
    endpoint_error, max_error:
        Euclidean distance of the two end points, and its maximum along the
        way (model coordinates).
    errors_by_weight:
        For each weight $w$: $\max_t \max_{w_j = w} |y_j(t) - \hat y_j(t)|$.
    endpoint_by_weight:
        The same at the end point only.
    tolerance:
        Accuracy of the integrations (largest of the two).
    engine:
        Engine that integrated them.
    """

    system: ControlSystem
    approximation: Any
    point: tuple[sp.Expr, ...]
    bracket: tuple[int, int]
    amplitude: float
    omega: float
    periods: int
    times: np.ndarray
    original: np.ndarray
    approximate: np.ndarray
    original_y: np.ndarray
    approximate_y: np.ndarray
    weights: tuple[int, ...]
    bracket_value: np.ndarray
    prediction: np.ndarray
    endpoint_error: float
    max_error: float
    errors_by_weight: dict[int, float] = field(default_factory=dict)
    endpoint_by_weight: dict[int, float] = field(default_factory=dict)
    tolerance: float = float("nan")
    engine: str = ""

    @property
    def final_original(self) -> np.ndarray:
        return self.original[-1]

    @property
    def final_approximation(self) -> np.ndarray:
        return self.approximate[-1]

    def to_json(self) -> dict[str, Any]:
        """The ``nilpotent/simulation@1`` object of the interface page (plus a few added fields)."""
        return json_object({
            "schema": "nilpotent/simulation@1",
            "model": self.system.name,
            "coordinates": list(self.system.coordinate_names),
            "point": format_point(self.system, self.point),
            "bracket": list(self.bracket),
            "amplitude": self.amplitude,
            "omega": self.omega,
            "periods": self.periods,
            "final": {
                "original": floats(self.final_original),
                "approximation": floats(self.final_approximation),
            },
            "prediction": floats(self.prediction),
            "bracket_value": floats(self.bracket_value),
            "weights": list(self.weights),
            "privileged_method": self.approximation.coordinates.method,
            "errors": {
                "endpoint": self.endpoint_error,
                "max": self.max_error,
                "by_weight": {str(w): e for w, e in self.errors_by_weight.items()},
                "by_weight_endpoint": {str(w): e for w, e in self.endpoint_by_weight.items()},
            },
            "tolerance": self.tolerance,
        })

    def plot(self, fig: Any = None) -> tuple[Any, Any]:
        """Both trajectories (model coordinates) and the error per weight group against time.

        Returns ``(figure, (ax_states, ax_errors))``
        (:func:`nilpotent.viz.simulation.plot_comparison`).
        """
        from nilpotent.viz.simulation import plot_comparison

        return plot_comparison(self, fig)

    # --- display (nilpotent.typeset) -------------------------------------------------
    def to_latex(self) -> str:
        """The input, the predicted motion and the errors by weight as LaTeX (``align*``)."""
        from nilpotent import typeset

        return typeset.comparison_display(self).latex()

    def _repr_latex_(self) -> str:
        return self.to_latex()

    def _repr_html_(self) -> str:
        from nilpotent import typeset

        return typeset.comparison_display(self).html()


def floats(arr: np.ndarray) -> list[float]:
    """The entries of ``arr`` as a flat list of Python floats (for JSON)."""
    return [float(v) for v in np.asarray(arr).ravel()]


def prepare_comparison(
    system: ControlSystem, bracket: Sequence[int], point: Any, approximation: Any
) -> tuple[ControlSystem, tuple[int, int], tuple[sp.Expr, ...], Any, np.ndarray]:
    """``(system specialised, (I, J) checked, p exact, approximation at p, p as floats)``.

    The approximation defaults to ``approximate(system, p)``; one given must be at ``p``
    (:class:`OptionError` otherwise).
    """
    sysp = system.specialized()
    pair = check_bracket(sysp.m, bracket)
    pt = sysp.point(point) if point is not None else sysp.origin()
    if approximation is None:
        from nilpotent.core.coordinates.approximation import approximate

        approximation = approximate(sysp, pt)
    elif tuple(approximation.point) != tuple(pt):
        raise OptionError("the approximation given was computed at another point")
    return sysp, pair, pt, approximation, float_point(sysp, pt)


def compare_bracket_motion(
    sys: ControlSystem,
    bracket: Sequence[int],
    amplitude: float,
    *,
    omega: float = 1.0,
    periods: int = 1,
    point: Any = None,
    approximation: Any = None,
    samples: int = 201,
    settings: IntegrationSettings | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    engine: str | None = None,
) -> Comparison:
    r"""Simulate the system and its nilpotent approximation under the bracket input.

    Parameters
    ----------
    sys:
        The original system.
    bracket:
        ``(I, J)``, 1-based, different.
    amplitude, omega, periods:
        $u_I = -A\omega\sin\omega t$, $u_J = A\omega\cos\omega t$, ``periods`` periods.
    point:
        $p$ (sequence or name→value mapping of numbers; default the origin).
    approximation:
        A :class:`~nilpotent.core.coordinates.approximation.NilpotentApproximation` at
        ``point`` (default: ``approximate(system, point)``).
    samples:
        Number of sample times (errors "along the way" are maxima over them).
    settings : IntegrationSettings or None
        How to integrate (default :data:`BRACKET_SETTINGS`: the one default
        with tighter tolerances).
    rtol, atol, engine : optional
        The loose form of ``settings`` (kept for one release): each one given
        overrides that field.

    Raises
    ------
    OptionError
        A bad bracket, amplitude, point, approximation or setting.
    IntegrationError
        One of the two simulations stopped early.
    """
    chosen = resolve_settings(settings, BRACKET_SETTINGS, rtol=rtol, atol=atol, engine=engine)
    bracket_signal(sys.m, *check_bracket(sys.m, bracket), amplitude, omega, periods)
    sysp, pair_ij, pt, approx, p = prepare_comparison(sys, bracket, point, approximation)
    run = bracket_run(sysp, approx, p, pair_ij, np.array([float(amplitude)]), omega, periods,
                      samples, settings=chosen)
    bval = bracket_value(sysp, pair_ij, pt)
    orig, appr = run.x[0], run.x_hat()[0]
    oy, ay = run.y()[0], run.y_hat[0]
    dist = np.linalg.norm(orig - appr, axis=1)
    diff_y = np.abs(oy - ay)
    groups = run.pair.groups
    return Comparison(
        system=sysp,
        approximation=approx,
        point=pt,
        bracket=pair_ij,
        amplitude=float(amplitude),
        omega=float(omega),
        periods=int(periods),
        times=run.times,
        original=orig,
        approximate=appr,
        original_y=oy,
        approximate_y=ay,
        weights=tuple(approx.filtration.weights),
        bracket_value=bval,
        prediction=p + periods * math.pi * amplitude**2 * bval,
        endpoint_error=float(dist[-1]),
        max_error=float(dist.max()),
        errors_by_weight={w: float(diff_y[:, list(idx)].max()) for w, idx in groups},
        endpoint_by_weight={w: float(diff_y[-1, list(idx)].max()) for w, idx in groups},
        tolerance=run.tolerance,
        engine=run.engines[0],
    )

