"""Inputs as data: batches of piecewise sums of sinusoids.

The compiled integrators evaluate inputs from coefficient arrays, never by
calling Python.  A batch of ``B`` input signals with ``S`` segments, ``m``
inputs and ``K`` harmonics is

.. math::

    u_i(t) = a_{s,i} + \\sum_{k=1}^{K} b_{s,i,k} \\cos(k ω_s τ) + c_{s,i,k} \\sin(k ω_s τ),

on segment ``s``, where ``τ = t − (d_0 + … + d_{s−1})`` is the time since the
segment started (the plan-segment format of INTERFACE.md).  Piecewise-constant
inputs are the case ``K = 0``; the periodic bracket input is one segment with
``K = 1``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nilpotent.errors import OptionError


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=np.float64)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class HarmonicInputs:
    """A batch of piecewise-sinusoidal input signals (arrays, read-only).

    Attributes
    ----------
    durations:
        ``(B, S)`` segment durations (> 0).
    omegas:
        ``(B, S)`` base angular frequency of each segment.
    constant:
        ``(B, S, m)`` constant terms ``a``.
    cos, sin:
        ``(B, S, m, K)`` coefficients of ``cos(kωτ)`` and ``sin(kωτ)``, ``k = 1..K``.
    """

    durations: np.ndarray
    omegas: np.ndarray
    constant: np.ndarray
    cos: np.ndarray
    sin: np.ndarray

    def __post_init__(self) -> None:
        d = np.asarray(self.durations, dtype=float)
        w = np.asarray(self.omegas, dtype=float)
        a = np.asarray(self.constant, dtype=float)
        c = np.asarray(self.cos, dtype=float)
        s = np.asarray(self.sin, dtype=float)
        if d.ndim != 2 or w.shape != d.shape or a.ndim != 3 or a.shape[:2] != d.shape:
            raise OptionError(
                "inputs: durations/omegas must be (B, S) and constant (B, S, m); got "
                f"{d.shape}, {w.shape}, {a.shape}"
            )
        if c.shape != s.shape or c.ndim != 4 or c.shape[:3] != a.shape:
            raise OptionError(
                f"inputs: cos/sin must be (B, S, m, K) matching constant {a.shape}; "
                f"got {c.shape}, {s.shape}"
            )
        if d.shape[1] == 0:
            raise OptionError("inputs: at least one segment is needed")
        arrays = (d, w, a, c, s)
        if not all(np.all(np.isfinite(x)) for x in arrays):
            raise OptionError("inputs: coefficients must be finite numbers")
        if np.any(d <= 0):
            raise OptionError("inputs: segment durations must be > 0")
        names = ("durations", "omegas", "constant", "cos", "sin")
        for name, arr in zip(names, arrays, strict=True):
            object.__setattr__(self, name, _frozen(arr))

    # --- shape -------------------------------------------------------------
    @property
    def batch(self) -> int:
        return int(self.durations.shape[0])

    @property
    def segments(self) -> int:
        return int(self.durations.shape[1])

    @property
    def m(self) -> int:
        return int(self.constant.shape[2])

    @property
    def harmonics(self) -> int:
        return int(self.cos.shape[3])

    @property
    def total_durations(self) -> np.ndarray:
        """``(B,)`` total duration of each signal."""
        return self.durations.sum(axis=1)

    # --- derived -----------------------------------------------------------
    def broadcast(self, batch: int) -> HarmonicInputs:
        """The same signals repeated to a batch of ``batch`` (from a batch of 1 or ``batch``)."""
        if self.batch == batch:
            return self
        if self.batch != 1:
            raise OptionError(
                f"inputs: a batch of {self.batch} signals cannot serve {batch} states"
            )

        def rep(x: np.ndarray) -> np.ndarray:
            return np.repeat(x, batch, axis=0)

        return HarmonicInputs(
            rep(self.durations), rep(self.omegas), rep(self.constant), rep(self.cos), rep(self.sin)
        )

    def segment_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """``(segment index, local time)`` of global time ``t`` for each signal, ``(B,)`` each.

        Times past the end belong to the last segment.
        """
        starts = np.concatenate([np.zeros((self.batch, 1)), np.cumsum(self.durations, axis=1)], 1)
        idx = np.sum(starts[:, 1:-1] <= t, axis=1)
        local = t - starts[np.arange(self.batch), idx]
        return idx, local

    def evaluate_local(self, segment: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """``(B, m)`` inputs at local times ``tau`` (``(B,)``) in segments ``segment``."""
        rows = np.arange(self.batch)
        a = self.constant[rows, segment]
        out = a.copy()
        k_count = self.harmonics
        if k_count:
            k = np.arange(1, k_count + 1)
            phase = (self.omegas[rows, segment] * tau)[:, None] * k[None, :]  # (B, K)
            out += np.einsum("bik,bk->bi", self.cos[rows, segment], np.cos(phase))
            out += np.einsum("bik,bk->bi", self.sin[rows, segment], np.sin(phase))
        return out

    def evaluate(self, t: float) -> np.ndarray:
        """``(B, m)`` inputs at global time ``t``."""
        seg, tau = self.segment_at(t)
        return self.evaluate_local(seg, tau)


def bracket_inputs(
    m: int,
    i: int,
    j: int,
    amplitudes: np.ndarray | float,
    omega: float = 1.0,
    periods: int = 1,
) -> HarmonicInputs:
    """The periodic bracket inputs ``u_i = −Aω sin ωt``, ``u_j = Aω cos ωt`` (others 0).

    ``i``, ``j`` are 1-based input numbers; one segment of ``periods`` periods
    (duration ``2π·periods/ω``); one signal per amplitude.  The loop
    ``(∫u_i, ∫u_j)`` is a counter-clockwise circle of area ``πA²`` per period.
    """
    amps = np.atleast_1d(np.asarray(amplitudes, dtype=float))
    if amps.ndim != 1:
        raise OptionError("amplitudes must be a number or a 1-d sequence")
    if not (1 <= i <= m and 1 <= j <= m) or i == j:
        raise OptionError(f"bracket ({i},{j}): need two different inputs between 1 and {m}")
    if not (np.isfinite(omega) and omega > 0):
        raise OptionError(f"omega must be > 0, got {omega}")
    if int(periods) != periods or periods < 1:
        raise OptionError(f"periods must be a positive integer, got {periods}")
    b = amps.shape[0]
    durations = np.full((b, 1), 2 * np.pi * periods / omega)
    omegas = np.full((b, 1), float(omega))
    constant = np.zeros((b, 1, m))
    cos = np.zeros((b, 1, m, 1))
    sin = np.zeros((b, 1, m, 1))
    sin[:, 0, i - 1, 0] = -amps * omega
    cos[:, 0, j - 1, 0] = amps * omega
    return HarmonicInputs(durations, omegas, constant, cos, sin)
