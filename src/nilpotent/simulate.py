r"""Simulation of driftless systems and of their nilpotent approximations.

* Inputs: :class:`Signal` (piecewise sums of sinusoids — the plan-segment
  format of INTERFACE.md — with :func:`bracket_signal`, :func:`sinusoids`,
  :func:`piecewise_constant`, :func:`signal_from_segments`) and
  :class:`FunctionSignal` (any Python function of ``t``; integrated by the
  ``solve_ivp`` reference engine, slower).
* :func:`simulate` → :class:`Trajectory`.
* :func:`compare_bracket_motion` → :class:`Comparison`: the original system and
  its nilpotent approximation (:func:`nilpotent.core.approximation.approximate`)
  from the same point under the periodic bracket input, with the prediction
  $p + K\pi A^2 [X_I, X_J](p)$ and the errors per weight group in privileged
  coordinates.
* :func:`scaling_study` → :class:`ScalingStudy`: those errors over a range of
  amplitudes and their fitted log–log slopes (expected $w_j + 1$, MATH.md §6 —
  measured here, not assumed).

Conventions: bracket $[X, Y] = DY\cdot X - DX\cdot Y$; inputs and fields are
numbered from 1 for users; the bracket input for $(I, J)$ is
$u_I = -A\omega\sin\omega t$, $u_J = A\omega\cos\omega t$, all others 0, from
$t = 0$: $(\int u_I, \int u_J)$ runs once per period counter-clockwise round a
circle of area $\pi A^2$.

Plots are :class:`matplotlib.figure.Figure` objects built without pyplot
(headless, nothing is shown); each ``plot`` returns ``(figure, axes)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.core.points import format_point
from nilpotent.core.system import ControlSystem
from nilpotent.errors import OptionError, PointError
from nilpotent.numeric.compile import CompiledSystem, compile_fields, compile_system
from nilpotent.numeric.integrators import (
    Status,
    integrate,
    solve_function_input,
)
from nilpotent.numeric.signals import (
    FunctionSignal,
    Signal,
    bracket_signal,
    check_bracket,
    piecewise_constant,
    sinusoids,
)

# --- single trajectories -------------------------------------------------------------


def _as_compiled(system: ControlSystem | CompiledSystem) -> CompiledSystem:
    if isinstance(system, CompiledSystem):
        return system
    return compile_system(system)


def _float_point(system: ControlSystem | CompiledSystem, x0: Any) -> np.ndarray:
    n = system.n
    if x0 is None:
        return np.zeros(n)
    try:
        arr = np.array([float(v) for v in x0], dtype=float)
    except (TypeError, ValueError):
        raise PointError(f"the start point must be {n} numbers, got {x0!r}") from None
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise PointError(f"the start point must be {n} finite numbers, got {x0!r}")
    return arr


@dataclass(frozen=True, eq=False)
class Trajectory:
    """One simulated trajectory, with what it was computed from.

    Attributes
    ----------
    system:
        Name of the system.
    coordinates:
        Names of the state components.
    x0:
        ``(n,)`` start.
    signal:
        The input (:class:`Signal` or :class:`FunctionSignal`).
    times, states:
        ``(T,)`` sample times and ``(T, n)`` states there.
    final:
        ``(n,)`` state at the end of the input.
    status:
        :class:`~nilpotent.numeric.integrators.Status` of the integration.
    tolerance:
        Accuracy met (see :class:`~nilpotent.numeric.integrators.BatchSolution`).
    method, engine:
        How it was integrated.
    """

    system: str
    coordinates: tuple[str, ...]
    x0: np.ndarray
    signal: Signal | FunctionSignal
    times: np.ndarray
    states: np.ndarray
    final: np.ndarray
    status: Status
    tolerance: float
    method: str
    engine: str

    def plot(self, ax: Any = None) -> tuple[Any, Any]:
        """Plot every coordinate against time; returns ``(figure, axes)``."""
        fig, ax = _figure_axes(ax)
        for k, name in enumerate(self.coordinates):
            ax.plot(self.times, self.states[:, k], label=name)
        ax.set_xlabel("t")
        ax.set_ylabel("state")
        ax.set_title(f"{self.system}")
        ax.legend(loc="best", fontsize="small")
        return fig, ax


def simulate(
    sys: ControlSystem | CompiledSystem,
    signal: Signal | FunctionSignal,
    x0: Any = None,
    *,
    samples: int = 201,
    method: str = "adaptive",
    engine: str = "auto",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    steps: int = 64,
    bound: float = 1e8,
    max_steps: int = 100_000,
) -> Trajectory:
    """Simulate ``dx/dt = Σ u_i(t) X_i(x)`` from ``x0`` (default: the origin).

    ``x0`` is a sequence of numbers or, for a ``ControlSystem``, a mapping
    ``{coordinate name: number}`` (missing names are 0).

    ``samples`` equally spaced times from 0 to the signal's duration are
    recorded.  A :class:`FunctionSignal` is integrated with ``solve_ivp``
    (``method``/``engine`` must then be left at their defaults or be
    ``"adaptive"``/``"scipy"``).
    """
    compiled = _as_compiled(sys)
    if isinstance(x0, Mapping) and isinstance(sys, ControlSystem):
        x0 = sys.point(x0)
    if signal.m != compiled.m:
        raise OptionError(f"the signal has {signal.m} inputs, the system {compiled.m} fields")
    start = _float_point(compiled, x0)
    if samples < 2:
        raise OptionError("samples must be >= 2")
    times = np.linspace(0.0, signal.duration, int(samples))
    if isinstance(signal, FunctionSignal):
        if method != "adaptive" or engine not in ("auto", "scipy"):
            raise OptionError("a function input is integrated by solve_ivp (adaptive, scipy)")
        final, states, status, _ = solve_function_input(
            compiled, start, signal.evaluate, signal.breakpoints, times=times,
            rtol=rtol, atol=atol, max_steps=max_steps, bound=bound,
        )
        return Trajectory(compiled.name, compiled.coordinate_names, start, signal, times,
                          states, final, status, float(rtol), "adaptive", "scipy")
    sol = integrate(
        compiled, start[None], signal, method=method, engine=engine, times=times,
        rtol=rtol, atol=atol, steps=steps, bound=bound, max_steps=max_steps,
    )
    return Trajectory(
        compiled.name, compiled.coordinate_names, start, signal, times, sol.samples[0].copy(),
        sol.final[0].copy(), Status(int(sol.status[0])), sol.tolerance, sol.method, sol.engine,
    )


# --- original vs approximation ------------------------------------------------------


def _map_function(coords: Sequence[sp.Symbol], exprs: Sequence[sp.Expr], name: str):
    """Vectorised ``(B, n) -> (B, k)`` evaluation of the map ``exprs(coords)``."""
    compiled = compile_fields(coords, [tuple(exprs)], name=name, backend="numpy")

    def apply(points: np.ndarray) -> np.ndarray:
        flat = points.reshape(-1, len(coords))
        return compiled.field_values(flat)[:, :, 0].reshape(*points.shape[:-1], len(exprs))

    return apply


def bracket_value(
    system: ControlSystem, bracket: Sequence[int], point: Sequence[Any]
) -> np.ndarray:
    r"""$[X_I, X_J](p)$ as floats (:func:`nilpotent.core.brackets.word_values_at`)."""
    from nilpotent.core.brackets import word_values_at

    i, j = check_bracket(system.m, bracket)
    (values,) = word_values_at(system, [(i, j)], tuple(point))
    return np.array([float(v) for v in values])


@dataclass(frozen=True)
class _Pair:
    """Both systems from the same point under a batch of bracket inputs."""

    times: np.ndarray
    original: np.ndarray  # (B, T, n) model coordinates
    approx_x: np.ndarray  # (B, T, n) the approximation's trajectory in model coordinates
    original_y: np.ndarray  # (B, T, n) privileged coordinates
    approx_y: np.ndarray  # (B, T, n)
    status_original: np.ndarray
    status_approx: np.ndarray
    tolerance: float
    engine: str


def _simulate_pair(
    system: ControlSystem,
    approximation: Any,
    point: np.ndarray,
    bracket: tuple[int, int],
    amplitudes: np.ndarray,
    omega: float,
    periods: int,
    samples: int,
    rtol: float,
    atol: float,
    engine: str,
) -> _Pair:
    from nilpotent.numeric.signals import bracket_inputs

    i, j = bracket
    inputs = bracket_inputs(system.m, i, j, amplitudes, omega=omega, periods=periods)
    times = np.linspace(0.0, 2 * math.pi * periods / omega, int(samples))
    batch = amplitudes.size
    orig = integrate(
        compile_system(system), np.repeat(point[None], batch, 0), inputs, times=times,
        rtol=rtol, atol=atol, engine=engine,
    )
    names = approximation.coordinates.names
    approx_sys = compile_fields(names, approximation.fields, name=f"{system.name}-nilpotent")
    appr = integrate(
        approx_sys, np.zeros((batch, system.n)), inputs, times=times, rtol=rtol, atol=atol,
        engine=engine,
    )
    forward = _map_function(system.coordinates, approximation.coordinates.forward,
                            f"{system.name}-forward")
    inverse = _map_function(names, approximation.coordinates.inverse, f"{system.name}-inverse")
    return _Pair(
        times,
        np.asarray(orig.samples),
        inverse(np.asarray(appr.samples)),
        forward(np.asarray(orig.samples)),
        np.asarray(appr.samples),
        np.asarray(orig.status),
        np.asarray(appr.status),
        max(orig.tolerance, appr.tolerance),
        orig.engine,
    )


def _weight_groups(weights: Sequence[int]) -> dict[int, list[int]]:
    groups: dict[int, list[int]] = {}
    for k, w in enumerate(weights):
        groups.setdefault(int(w), []).append(k)
    return groups


def _check_status(pair: _Pair) -> None:
    for label, st in (("original", pair.status_original), ("approximation", pair.status_approx)):
        bad = np.flatnonzero(st != Status.SUCCESS)
        if bad.size:
            from nilpotent.errors import IntegrationError

            raise IntegrationError(
                f"the {label} system's simulation stopped early: {Status(int(st[bad[0]])).message}"
            )


@dataclass(frozen=True, eq=False)
class Comparison:
    r"""The original system and its nilpotent approximation under one bracket motion.

    Attributes
    ----------
    system:
        The original system (parameters substituted).
    approximation:
        The :class:`~nilpotent.core.approximation.NilpotentApproximation` used.
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
        """The ``nilpotent/simulation@1`` object of INTERFACE.md (plus a few added fields)."""
        return {
            "schema": "nilpotent/simulation@1",
            "model": self.system.name,
            "coordinates": list(self.system.coordinate_names),
            "point": format_point(self.system, self.point),
            "bracket": list(self.bracket),
            "amplitude": self.amplitude,
            "omega": self.omega,
            "periods": self.periods,
            "final": {
                "original": _floats(self.final_original),
                "approximation": _floats(self.final_approximation),
            },
            "prediction": _floats(self.prediction),
            "bracket_value": _floats(self.bracket_value),
            "weights": list(self.weights),
            "privileged_method": self.approximation.coordinates.method,
            "errors": {
                "endpoint": self.endpoint_error,
                "max": self.max_error,
                "by_weight": {str(w): e for w, e in self.errors_by_weight.items()},
                "by_weight_endpoint": {str(w): e for w, e in self.endpoint_by_weight.items()},
            },
            "tolerance": self.tolerance,
        }

    def plot(self, fig: Any = None) -> tuple[Any, Any]:
        """Both trajectories (model coordinates) and the error per weight group against time.

        Returns ``(figure, (ax_states, ax_errors))``.
        """
        from matplotlib.figure import Figure

        fig = fig if fig is not None else Figure(figsize=(10, 4.2), layout="constrained")
        ax1, ax2 = fig.subplots(1, 2)
        for k, name in enumerate(self.system.coordinate_names):
            (line,) = ax1.plot(self.times, self.original[:, k], label=f"{name}")
            ax1.plot(self.times, self.approximate[:, k], "--", color=line.get_color())
        ax1.set_xlabel("t")
        ax1.set_title(f"{self.system.name}: original (solid), approximation (dashed)")
        ax1.legend(loc="best", fontsize="small")
        diff = np.abs(self.original_y - self.approximate_y)
        for w, idx in _weight_groups(self.weights).items():
            err = diff[:, idx].max(axis=1)
            ax2.semilogy(self.times, np.maximum(err, 1e-17), label=f"weight {w}")
        ax2.set_xlabel("t")
        ax2.set_title(f"|y − ŷ| per weight group, A = {self.amplitude:g}")
        ax2.legend(loc="best", fontsize="small")
        return fig, (ax1, ax2)


def _floats(arr: np.ndarray) -> list[float]:
    return [float(v) for v in np.asarray(arr).ravel()]


def _prepare_comparison(
    system: ControlSystem, bracket: Sequence[int], point: Any, approximation: Any
) -> tuple[ControlSystem, tuple[int, int], tuple[sp.Expr, ...], Any, np.ndarray]:
    sysp = system.specialized()
    pair = check_bracket(sysp.m, bracket)
    pt = sysp.point(point) if point is not None else sysp.origin()
    if approximation is None:
        from nilpotent.core.approximation import approximate

        approximation = approximate(sysp, pt)
    elif tuple(approximation.point) != tuple(pt):
        raise OptionError("the approximation given was computed at another point")
    return sysp, pair, pt, approximation, _float_point(sysp, pt)


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
    rtol: float = 1e-12,
    atol: float = 1e-14,
    engine: str = "auto",
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
        A :class:`~nilpotent.core.approximation.NilpotentApproximation` at
        ``point`` (default: ``approximate(system, point)``).
    samples:
        Number of sample times (errors "along the way" are maxima over them).
    rtol, atol:
        Integration tolerances (adaptive DOP853).
    engine:
        Integration engine (:data:`nilpotent.numeric.ENGINES`).
    """
    bracket_signal(sys.m, *check_bracket(sys.m, bracket), amplitude, omega, periods)
    sysp, pair_ij, pt, approx, p = _prepare_comparison(sys, bracket, point, approximation)
    pair = _simulate_pair(sysp, approx, p, pair_ij, np.array([float(amplitude)]), omega,
                          periods, samples, rtol, atol, engine)
    _check_status(pair)
    bval = bracket_value(sysp, pair_ij, pt)
    orig, appr = pair.original[0], pair.approx_x[0]
    oy, ay = pair.original_y[0], pair.approx_y[0]
    dist = np.linalg.norm(orig - appr, axis=1)
    diff_y = np.abs(oy - ay)
    groups = _weight_groups(approx.filtration.weights)
    return Comparison(
        system=sysp,
        approximation=approx,
        point=pt,
        bracket=pair_ij,
        amplitude=float(amplitude),
        omega=float(omega),
        periods=int(periods),
        times=pair.times,
        original=orig,
        approximate=appr,
        original_y=oy,
        approximate_y=ay,
        weights=tuple(approx.filtration.weights),
        bracket_value=bval,
        prediction=p + periods * math.pi * amplitude**2 * bval,
        endpoint_error=float(dist[-1]),
        max_error=float(dist.max()),
        errors_by_weight={w: float(diff_y[:, idx].max()) for w, idx in groups.items()},
        endpoint_by_weight={w: float(diff_y[-1, idx].max()) for w, idx in groups.items()},
        tolerance=pair.tolerance,
        engine=pair.engine,
    )


# --- scaling ---------------------------------------------------------------------------

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
        weight $w$ → $w + 1$ (MATH.md §6).
    floor:
        The noise floor used: errors below it are not fitted.
    tolerance:
        Accuracy of the integrations.
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
        return {
            "schema": "nilpotent/scaling@1",
            "model": self.system.name,
            "coordinates": list(self.system.coordinate_names),
            "point": format_point(self.system, self.point),
            "bracket": list(self.bracket),
            "omega": self.omega,
            "periods": self.periods,
            "weights": list(self.weights),
            "amplitudes": _floats(self.amplitudes),
            "errors": {str(w): _floats(e) for w, e in self.errors.items()},
            "slopes": {str(w): s for w, s in self.slopes.items()},
            "expected_slopes": {str(w): s for w, s in self.expected_slopes.items()},
            "floor": self.floor,
            "tolerance": self.tolerance,
        }

    def plot(self, ax: Any = None) -> tuple[Any, Any]:
        """Log–log errors per weight group with the fitted lines; returns ``(figure, axes)``."""
        fig, ax = _figure_axes(ax)
        a = self.amplitudes
        for w, err in self.errors.items():
            shown = np.where(err > 0, err, np.nan)
            (line,) = ax.loglog(a, shown, "o", label=f"weight {w}")
            slope = self.slopes[w]
            if slope is not None:
                keep = err > self.floor
                coef = np.polyfit(np.log(a[keep]), np.log(err[keep]), 1)
                ax.loglog(a, np.exp(np.polyval(coef, np.log(a))), "-", color=line.get_color(),
                          label=f"fit slope {slope:.2f} (expected {self.expected_slopes[w]})")
        ax.set_xlabel("amplitude A")
        ax.set_ylabel("max |y − ŷ| in the group")
        ax.set_title(f"{self.system.name}: bracket [X{self.bracket[0]},X{self.bracket[1]}]")
        ax.legend(loc="best", fontsize="small")
        return fig, ax


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
    rtol: float = 1e-12,
    atol: float = 1e-14,
    engine: str = "auto",
) -> ScalingStudy:
    r"""Measure how the approximation error scales with the amplitude, per weight group.

    All amplitudes are simulated as one batch (original and approximation).
    The slope of each group is fitted by least squares on the errors above
    the noise floor ``1e3·(atol + rtol·max|y|)``.

    Parameters are those of :func:`compare_bracket_motion`; ``amplitudes``
    must be positive and contain at least two different values.
    """
    amps = np.asarray([float(a) for a in amplitudes])
    if amps.size < 2 or np.unique(amps).size < 2:
        raise OptionError("a scaling study needs at least two different amplitudes")
    if not np.all(np.isfinite(amps)) or np.any(amps <= 0):
        raise OptionError("amplitudes must be > 0")
    for a in amps:
        bracket_signal(sys.m, *check_bracket(sys.m, bracket), float(a), omega, periods)
    sysp, pair_ij, pt, approx, p = _prepare_comparison(sys, bracket, point, approximation)
    pair = _simulate_pair(sysp, approx, p, pair_ij, amps, omega, periods, samples, rtol, atol,
                          engine)
    _check_status(pair)
    diff = np.abs(pair.original_y - pair.approx_y)  # (k, T, n)
    scale = float(np.nanmax(np.abs(pair.original_y))) if pair.original_y.size else 0.0
    floor = 1e3 * (atol + rtol * scale)
    weights = tuple(int(w) for w in approx.filtration.weights)
    errors: dict[int, np.ndarray] = {}
    slopes: dict[int, float | None] = {}
    for w, idx in _weight_groups(weights).items():
        err = diff[:, :, idx].max(axis=(1, 2))
        errors[w] = err
        keep = err > floor
        if np.count_nonzero(keep) >= 2 and np.unique(amps[keep]).size >= 2:
            slopes[w] = float(np.polyfit(np.log(amps[keep]), np.log(err[keep]), 1)[0])
        else:
            slopes[w] = None
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
        tolerance=pair.tolerance,
        engine=pair.engine,
    )


def _figure_axes(ax: Any) -> tuple[Any, Any]:
    if ax is not None:
        return ax.figure, ax
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
    return fig, fig.add_subplot(1, 1, 1)


def signal_from_segments(segments: Sequence[Any]) -> Signal:
    """A :class:`Signal` from plan segments (:meth:`Signal.from_segments`)."""
    return Signal.from_segments(segments)


__all__ = [
    "Comparison", "FunctionSignal", "ScalingStudy", "Signal", "Trajectory", "bracket_signal",
    "bracket_value", "compare_bracket_motion", "piecewise_constant", "scaling_study",
    "signal_from_segments", "simulate", "sinusoids",
]
