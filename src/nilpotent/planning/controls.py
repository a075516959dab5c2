"""Open-loop controls as data: segments of constants plus finitely many sinusoids.

A control is a sequence of :class:`Segment`; within a segment of duration
``T`` and base frequency ``ω`` the input of field ``X_{i+1}`` is

.. math::

    u_i(t) = c_i + \\sum_{k\\ge 1} a_{ik}\\cos(k\\omega t) + b_{ik}\\sin(k\\omega t),
    \\qquad 0 \\le t \\le T,

with ``t`` restarting from 0 in every segment (``a_{ik}`` is ``cos[k-1]``,
``b_{ik}`` is ``sin[k-1]``: exactly the segment format of the
``nilpotent/plan@1`` JSON in INTERFACE.md).  Segments follow one another.

Everything here is float data; nothing is symbolic.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from nilpotent.errors import OptionError
from nilpotent.numeric.types import State


def _floats(values: Sequence[float], what: str) -> tuple[float, ...]:
    out = tuple(float(v) for v in values)
    if not all(math.isfinite(v) for v in out):
        raise OptionError(f"{what}: every value must be a finite number")
    return out


@dataclass(frozen=True)
class InputSignal:
    """One input within a segment: ``c + Σ_k cos[k-1]·cos(kωt) + sin[k-1]·sin(kωt)``.

    Parameters
    ----------
    constant:
        The constant part ``c``.
    cos, sin:
        Coefficients of ``cos(kωt)`` and ``sin(kωt)`` for ``k = 1, 2, ...``
        (entry ``k-1``); the two tuples may have different lengths.

    Examples
    --------
    >>> s = InputSignal(1.0, cos=(0.0, 2.0), sin=(3.0,))
    >>> round(float(s.value(0.0, omega=1.0)), 12)
    3.0
    """

    constant: float = 0.0
    cos: tuple[float, ...] = ()
    sin: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "constant", _floats([self.constant], "input constant")[0])
        object.__setattr__(self, "cos", _floats(self.cos, "input cos coefficients"))
        object.__setattr__(self, "sin", _floats(self.sin, "input sin coefficients"))

    @property
    def harmonics(self) -> int:
        """The highest harmonic ``k`` present (0 for a constant input)."""
        return max(len(self.cos), len(self.sin))

    def value(self, t: float | np.ndarray, omega: float) -> np.ndarray:
        """``u(t)`` (vectorised over ``t``)."""
        t = np.asarray(t, dtype=float)
        out = np.full(t.shape, self.constant, dtype=float)
        for k, a in enumerate(self.cos, start=1):
            if a:
                out = out + a * np.cos(k * omega * t)
        for k, b in enumerate(self.sin, start=1):
            if b:
                out = out + b * np.sin(k * omega * t)
        return out

    def integral(self, duration: float, omega: float) -> float:
        """``∫_0^T u(t) dt``, exactly (closed form)."""
        total = self.constant * duration
        for k, a in enumerate(self.cos, start=1):
            total += a * math.sin(k * omega * duration) / (k * omega)
        for k, b in enumerate(self.sin, start=1):
            total += b * (1.0 - math.cos(k * omega * duration)) / (k * omega)
        return total

    def to_dict(self) -> dict[str, Any]:
        return {"constant": self.constant, "cos": list(self.cos), "sin": list(self.sin)}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> InputSignal:
        return cls(
            float(data.get("constant", 0.0)),
            tuple(data.get("cos", ())),
            tuple(data.get("sin", ())),
        )


@dataclass(frozen=True)
class Segment:
    """A piece of control of the given ``duration``: one :class:`InputSignal` per field.

    ``omega`` is the base frequency of the sinusoids (irrelevant, but kept, for
    constant inputs).
    """

    duration: float
    omega: float
    inputs: tuple[InputSignal, ...]

    def __post_init__(self) -> None:
        duration, omega = _floats([self.duration, self.omega], "segment duration/omega")
        if duration <= 0:
            raise OptionError(f"segment duration must be positive, got {duration}")
        if omega <= 0:
            raise OptionError(f"segment omega must be positive, got {omega}")
        object.__setattr__(self, "duration", duration)
        object.__setattr__(self, "omega", omega)
        object.__setattr__(self, "inputs", tuple(self.inputs))

    @property
    def m(self) -> int:
        """Number of inputs."""
        return len(self.inputs)

    def values(self, t: float | np.ndarray) -> np.ndarray:
        """The inputs at times ``t``: shape ``(m,)`` for scalar ``t``, else ``(m, len(t))``."""
        return np.stack([s.value(t, self.omega) for s in self.inputs])

    def integrals(self) -> np.ndarray:
        """``(∫_0^T u_i dt)_i`` (closed form)."""
        return np.array([s.integral(self.duration, self.omega) for s in self.inputs])

    def l1_norm(self, samples: int = 257) -> float:
        """``∫_0^T Σ_i |u_i(t)| dt`` (trapezoidal estimate): the size of the control."""
        t = np.linspace(0.0, self.duration, samples)
        f = np.abs(self.values(t)).sum(axis=0)
        return float(np.sum((f[1:] + f[:-1]) * np.diff(t)) / 2)

    def scaled(self, factor: float) -> Segment:
        """The segment with every input multiplied by ``factor``."""
        return Segment(
            self.duration,
            self.omega,
            tuple(
                InputSignal(
                    factor * s.constant,
                    tuple(factor * a for a in s.cos),
                    tuple(factor * b for b in s.sin),
                )
                for s in self.inputs
            ),
        )

    def reversed(self) -> Segment:
        """The segment ``v(t) = −u(T − t)``: for a driftless system it retraces the path.

        Uses ``cos(kω(T−t)) = cos(kωT)cos(kωt) + sin(kωT)sin(kωt)`` and
        ``sin(kω(T−t)) = sin(kωT)cos(kωt) − cos(kωT)sin(kωt)``.
        """
        new_inputs = []
        for s in self.inputs:
            k_max = s.harmonics
            a = np.zeros(k_max)
            b = np.zeros(k_max)
            a[: len(s.cos)] = s.cos
            b[: len(s.sin)] = s.sin
            k = np.arange(1, k_max + 1)
            ck = np.cos(k * self.omega * self.duration)
            sk = np.sin(k * self.omega * self.duration)
            new_a = -(a * ck + b * sk)
            new_b = -(a * sk - b * ck)
            new_inputs.append(InputSignal(-s.constant, tuple(new_a), tuple(new_b)))
        return Segment(self.duration, self.omega, tuple(new_inputs))

    def to_dict(self) -> dict[str, Any]:
        return {
            "duration": self.duration,
            "omega": self.omega,
            "inputs": [s.to_dict() for s in self.inputs],
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Segment:
        return cls(
            float(data["duration"]),
            float(data.get("omega", 1.0)),
            tuple(InputSignal.from_dict(d) for d in data["inputs"]),
        )


def constant_segment(values: Sequence[float] | State, duration: float = 1.0) -> Segment:
    """A segment of constant inputs."""
    return Segment(duration, 2 * math.pi / duration, tuple(InputSignal(float(v)) for v in values))


def reverse_segments(segments: Sequence[Segment]) -> tuple[Segment, ...]:
    """Controls that retrace ``segments`` backwards (last segment first, each reversed)."""
    return tuple(s.reversed() for s in reversed(segments))


def input_at(segments: Sequence[Segment], t: float) -> np.ndarray:
    """The input vector at global time ``t`` (segments one after another from 0)."""
    start = 0.0
    for seg in segments:
        if t <= start + seg.duration:
            return seg.values(t - start)
        start += seg.duration
    return segments[-1].values(segments[-1].duration)


def coefficients(segments: Sequence[Segment], harmonics: Sequence[int]) -> np.ndarray:
    """The input coefficients as one vector: per segment, per input, ``constant``,
    ``cos[0..K-1]``, ``sin[0..K-1]`` with ``K = harmonics[segment]`` (zero-padded)."""
    out: list[float] = []
    for seg, k in zip(segments, harmonics, strict=True):
        for s in seg.inputs:
            if s.harmonics > k:
                raise OptionError(f"an input has {s.harmonics} harmonics, more than {k}")
            cos = list(s.cos) + [0.0] * (k - len(s.cos))
            sin = list(s.sin) + [0.0] * (k - len(s.sin))
            out.extend([s.constant, *cos, *sin])
    return np.array(out)


def from_coefficients(
    theta: np.ndarray, template: Sequence[Segment], harmonics: Sequence[int], m: int
) -> list[Segment]:
    """Inverse of :func:`coefficients`: segments with the durations and ω of ``template``."""
    segs = []
    pos = 0
    for seg, k in zip(template, harmonics, strict=True):
        inputs = []
        for _ in range(m):
            c = float(theta[pos])
            cos = tuple(float(v) for v in theta[pos + 1 : pos + 1 + k])
            sin = tuple(float(v) for v in theta[pos + 1 + k : pos + 1 + 2 * k])
            inputs.append(InputSignal(c, cos, sin))
            pos += 2 * k + 1
        segs.append(Segment(seg.duration, seg.omega, tuple(inputs)))
    return segs
