"""Planning's view of controls: sequences of segments and their coefficient vectors.

The control type itself (:class:`Segment`, :class:`InputSignal`, and the
array form :class:`~nilpotent.numeric.signals.Signal`) lives in
:mod:`nilpotent.numeric.signals`; here are the operations only the planner
needs (reversal of a sequence, the coefficient vector that Newton iterates on).

A control is a sequence of :class:`Segment`; within a segment of duration
``T`` and base frequency ``ω`` the input of field ``X_{i+1}`` is

.. math::

    u_i(t) = c_i + \\sum_{k\\ge 1} a_{ik}\\cos(k\\omega t) + b_{ik}\\sin(k\\omega t),
    \\qquad 0 \\le t \\le T,

with ``t`` restarting from 0 in every segment (``a_{ik}`` is ``cos[k-1]``,
``b_{ik}`` is ``sin[k-1]``: exactly the segment format of the
``nilpotent/plan@1`` JSON of the interface page).  Segments follow one another.

Everything here is float data; nothing is symbolic.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from nilpotent.errors import OptionError
from nilpotent.numeric.signals import InputSignal as InputSignal
from nilpotent.numeric.signals import Segment as Segment
from nilpotent.numeric.types import State


def constant_segment(values: Sequence[float] | State, duration: float = 1.0) -> Segment:
    """A segment of constant inputs."""
    return Segment(duration, 2 * math.pi / duration, tuple(InputSignal(float(v)) for v in values))


def reverse_segments(segments: Sequence[Segment]) -> tuple[Segment, ...]:
    """Controls that retrace ``segments`` backwards (last segment first, each reversed)."""
    return tuple(s.reversed() for s in reversed(segments))


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
