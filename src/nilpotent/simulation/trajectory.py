"""One simulated trajectory of ``dx/dt = Σ u_i(t) X_i(x)``: :func:`simulate` → :class:`Trajectory`.

The one trajectory type of the project: simulations, plans
(:attr:`nilpotent.planning.Plan.trajectory`) and figures use it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import OptionError, PointError
from nilpotent.numeric.compile import CompiledSystem, compile_system
from nilpotent.numeric.integrate import Status, integrate
from nilpotent.numeric.sampled import as_signal
from nilpotent.numeric.settings import DEFAULT_SETTINGS, IntegrationSettings, resolve_settings
from nilpotent.numeric.signals import FunctionSignal, Signal
from nilpotent.numeric.types import State, States, Times

__all__ = ["Trajectory", "as_compiled", "float_point", "simulate"]


def as_compiled(system: ControlSystem | CompiledSystem) -> CompiledSystem:
    """``system`` compiled (a :class:`CompiledSystem` is returned as it is)."""
    if isinstance(system, CompiledSystem):
        return system
    return compile_system(system)


def float_point(system: ControlSystem | CompiledSystem, x0: Any) -> State:
    """``x0`` as ``(n,)`` finite floats (``None``: the origin); :class:`PointError` otherwise."""
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
    """One trajectory: its samples, and what it was computed from.

    ``Trajectory(times, states)`` alone is a trajectory sampled elsewhere
    (``x0`` and ``final`` are then its first and last samples); :func:`simulate`
    fills in the rest.

    Attributes
    ----------
    times, states:
        ``(T,)`` sample times and ``(T, n)`` states there.
    system:
        Name of the system.
    coordinates:
        Names of the state components.
    x0:
        ``(n,)`` start.
    final:
        ``(n,)`` state at the end of the input.
    signal:
        The input (:class:`~nilpotent.numeric.signals.Signal` or
        :class:`~nilpotent.numeric.signals.FunctionSignal`; ``None`` for the
        empty control, or when not known).
    status:
        :class:`~nilpotent.numeric.integrate.Status` of the integration.
    tolerance:
        Accuracy met (see :class:`~nilpotent.numeric.integrate.BatchSolution`;
        NaN when not known).
    method, engine:
        How it was integrated (``""`` when not known).

    Raises
    ------
    OptionError
        States that are not ``(T, n)`` for the ``T`` sample times.
    """

    times: Times
    states: States
    system: str = ""
    coordinates: tuple[str, ...] = ()
    x0: State | None = None
    final: State | None = None
    signal: Signal | FunctionSignal | None = None
    status: Status = Status.SUCCESS
    tolerance: float = float("nan")
    method: str = ""
    engine: str = ""

    def __post_init__(self) -> None:
        states = np.asarray(self.states, dtype=float)
        if states.ndim != 2 or states.shape[0] != np.shape(self.times)[0]:
            raise OptionError(f"a trajectory needs states (T, n) for its T times, got "
                              f"{states.shape} for {np.shape(self.times)}")
        if self.x0 is None and states.shape[0]:
            object.__setattr__(self, "x0", states[0].copy())
        if self.final is None and states.shape[0]:
            object.__setattr__(self, "final", states[-1].copy())

    def plot(self, ax: Any = None) -> tuple[Any, Any]:
        """Every coordinate against time; returns ``(figure, axes)`` (:mod:`nilpotent.viz`)."""
        from nilpotent.viz.simulation import plot_trajectory

        return plot_trajectory(self, ax)


def simulate(
    sys: ControlSystem | CompiledSystem,
    signal: Signal | FunctionSignal | Callable[[float], Any] | tuple[Any, Any],
    x0: Any = None,
    *,
    duration: float | None = None,
    hold: str = "linear",
    samples: int = 201,
    times: Sequence[float] | np.ndarray | None = None,
    settings: IntegrationSettings | None = None,
    method: str | None = None,
    engine: str | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    steps: int | None = None,
    bound: float | None = None,
    max_steps: int | None = None,
) -> Trajectory:
    """Simulate ``dx/dt = Σ u_i(t) X_i(x)`` from ``x0`` (default: the origin).

    Parameters
    ----------
    sys:
        The system, symbolic or compiled.
    signal:
        A single control (a :class:`~nilpotent.numeric.signals.Signal` of
        batch 1), a :class:`~nilpotent.numeric.signals.FunctionSignal`, a
        callable ``u(t) -> (m,)`` (with ``duration``) or sampled inputs ``(T, U)``,
        ``T`` of shape ``(K,)`` from 0, ``U`` of shape ``(K, m)``
        (:func:`~nilpotent.numeric.sampled.as_signal`, the one conversion).  A
        function input (a callable, or samples with ``hold="linear"``) is
        integrated with ``solve_ivp``: ``method``/``engine`` must then be left at
        their defaults or be ``"adaptive"``/``"scipy"``.
    x0:
        A sequence of numbers or, for a ``ControlSystem``, a mapping
        ``{coordinate name: number}`` (missing names are 0).
    duration:
        End of a callable input's interval ``[0, duration]``.
    hold:
        How samples ``(T, U)`` are read between times: ``"linear"`` or ``"zero"``.
    samples:
        Equally spaced times from 0 to the signal's duration to record (≥ 2).
    times:
        Sample times instead (sorted, within the duration).
    settings : IntegrationSettings or None
        How to integrate (default
        :data:`~nilpotent.numeric.settings.DEFAULT_SETTINGS`).
    method, engine, rtol, atol, steps, bound, max_steps : optional
        The loose form of ``settings`` (kept for one release): each one given
        overrides that field.

    Raises
    ------
    OptionError
        A signal with another number of inputs, a batch of controls, or bad settings.
    PointError
        A start point that is not ``n`` finite numbers.
    """
    chosen = resolve_settings(settings, DEFAULT_SETTINGS, method=method, engine=engine,
                              rtol=rtol, atol=atol, steps=steps, bound=bound, max_steps=max_steps)
    compiled = as_compiled(sys)
    if isinstance(x0, Mapping) and isinstance(sys, ControlSystem):
        x0 = sys.point(x0)
    signal = as_signal(signal, compiled.m, duration=duration, hold=hold)
    if signal.m != compiled.m:
        raise OptionError(f"the signal has {signal.m} inputs, the system {compiled.m} fields")
    if isinstance(signal, Signal) and signal.batch != 1:
        raise OptionError(f"simulate takes one control, got a batch of {signal.batch}")
    start = float_point(compiled, x0)
    if times is None:
        if samples < 2:
            raise OptionError("samples must be >= 2")
        ts = np.linspace(0.0, signal.duration, int(samples))
    else:
        ts = np.asarray(times, dtype=float)
    if isinstance(signal, FunctionSignal):
        from nilpotent.numeric.integrate import solve_function_input

        if chosen.method != "adaptive" or chosen.engine not in ("auto", "scipy"):
            raise OptionError("a function input is integrated by solve_ivp (adaptive, scipy)")
        final, states, status, _ = solve_function_input(
            compiled, start, signal.evaluate, signal.breakpoints, times=ts,
            rtol=chosen.rtol, atol=chosen.atol, max_steps=chosen.max_steps, bound=chosen.bound,
        )
        return Trajectory(ts, states, compiled.name, compiled.coordinate_names, start, final,
                          signal, status, float(chosen.rtol), "adaptive", "scipy")
    sol = integrate(compiled, start[None], signal, settings=chosen, times=ts)
    return Trajectory(
        np.asarray(sol.times), sol.samples[0].copy(), compiled.name, compiled.coordinate_names,
        start, sol.final[0].copy(), signal, Status(int(sol.status[0])), sol.tolerance,
        sol.method, sol.engine,
    )


def stationary(sys: ControlSystem | CompiledSystem, x0: Any) -> Trajectory:
    """The trajectory of the empty control: one sample, at ``x0``, at time 0."""
    compiled = as_compiled(sys)
    start = float_point(compiled, x0)
    return Trajectory(np.zeros(1), start[None, :].copy(), compiled.name,
                      compiled.coordinate_names, start, start.copy(), None, Status.SUCCESS, 0.0,
                      "none", "none")
