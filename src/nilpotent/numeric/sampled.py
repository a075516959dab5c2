"""Inputs as users give them, converted to signals: :func:`as_signal`, the one conversion.

The public integrators (:func:`nilpotent.numeric.integrate`,
:func:`nilpotent.simulation.simulate`) take a :class:`~nilpotent.numeric.signals.Signal`,
a :class:`~nilpotent.numeric.signals.FunctionSignal`, a callable ``u(t)`` or sampled
inputs ``(T, U)`` as python-control's ``input_output_response`` does; this module turns
each into a signal.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from nilpotent.errors import OptionError
from nilpotent.numeric.signals import FunctionSignal, Signal, piecewise_constant

__all__ = ["HOLDS", "as_signal"]


HOLDS = ("linear", "zero")
"""How sampled inputs are read between their samples (:func:`as_signal`): ``"linear"``
interpolation (python-control's ``input_output_response``) or ``"zero"``-order hold."""


def as_signal(
    inputs: Any, m: int, *, duration: float | None = None, hold: str = "linear"
) -> Signal | FunctionSignal:
    """The one conversion of the inputs the public entry points take.

    Parameters
    ----------
    inputs : Signal, FunctionSignal, callable or (T, U)
        * a :class:`Signal` or :class:`FunctionSignal`: returned as is;
        * a callable ``u(t) -> (m,)`` array_like: a :class:`FunctionSignal` on
          ``[0, duration]`` (``duration`` is then required);
        * a pair ``(T, U)`` of samples: ``T`` of shape ``(K,)`` (``K >= 2`` times,
          strictly increasing from ``T[0] = 0``), ``U`` of shape ``(K, m)`` (one row
          per time; python-control's ``(m, K)`` is accepted too where ``K != m``; a
          ``(K,)`` vector where ``m = 1``).  Read between samples as ``hold`` says,
          on ``[0, T[-1]]``.
    m : int
        Number of inputs of the system (fields).
    duration : float or None
        Length of a callable input (seconds of model time, > 0); not used otherwise.
    hold : str
        ``"linear"`` (default; a :class:`FunctionSignal` with the sample times as
        breakpoints, integrated by the scipy engine) or ``"zero"`` (the value of each
        sample held until the next: a piecewise-constant :class:`Signal`, integrated
        by every engine).

    Returns
    -------
    Signal or FunctionSignal

    Raises
    ------
    OptionError
        Inputs of another kind, another number of inputs, non-finite samples, times
        that do not start at 0 or do not increase, a callable without ``duration``,
        an unknown ``hold``.
    """
    if isinstance(inputs, Signal | FunctionSignal):
        if inputs.m != m:
            raise OptionError(f"the inputs have {inputs.m} components, the system {m} fields")
        return inputs
    if hold not in HOLDS:
        raise OptionError(f"hold must be one of {', '.join(HOLDS)}, got {hold!r}")
    if callable(inputs):
        if duration is None:
            raise OptionError("a callable input u(t) needs duration= (the end of [0, duration])")
        return FunctionSignal(inputs, int(m), float(duration))
    if not (isinstance(inputs, tuple | list) and len(inputs) == 2):
        raise OptionError(
            "inputs must be a Signal, a FunctionSignal, a callable u(t) or a pair (T, U) of "
            f"sample times (K,) and values (K, m); got {type(inputs).__name__}")
    times = np.asarray(inputs[0], dtype=float)
    values = np.asarray(inputs[1], dtype=float)
    if times.ndim != 1 or times.size < 2:
        raise OptionError(f"sample times T must have shape (K,) with K >= 2, got {times.shape}")
    k = times.size
    if values.ndim == 1 and m == 1:
        values = values[:, None]
    if values.ndim == 2 and values.shape != (k, m) and values.shape == (m, k):
        values = values.T  # python-control's layout: one row per input
    if values.shape != (k, m):
        raise OptionError(
            f"sample values U must have shape (K, m) = ({k}, {m}) (or ({m}, {k})), got "
            f"{values.shape}")
    if not (np.all(np.isfinite(times)) and np.all(np.isfinite(values))):
        raise OptionError("sample times and values must be finite numbers")
    if times[0] != 0.0 or np.any(np.diff(times) <= 0):
        raise OptionError("sample times T must start at 0 and increase strictly")
    if hold == "zero":
        return piecewise_constant(values[:-1], [float(d) for d in np.diff(times)])
    t_frozen, u_frozen = times.copy(), values.copy()

    def interpolated(t: float) -> np.ndarray:
        return np.array([np.interp(t, t_frozen, u_frozen[:, i]) for i in range(m)])

    return FunctionSignal(interpolated, int(m), float(times[-1]), tuple(times[1:-1]))
