r"""Controls as data: the one control type of the project.

A control is a sequence of *segments*; on segment ``s`` (local time
$\tau = t - (d_0 + \dots + d_{s-1})$ from 0 to $d_s$) input ``i`` is

.. math::

    u_i(t) = a_{s,i} + \sum_{k=1}^{K} b_{s,i,k}\cos(k\omega_s\tau) + c_{s,i,k}\sin(k\omega_s\tau),

exactly the segment format of the ``nilpotent/plan@1`` JSON of the interface page
(``constant`` = $a$, ``cos[k-1]`` = $b_k$, ``sin[k-1]`` = $c_k$).

* :class:`Signal` — ``B`` such controls as read-only arrays (a single control
  is a batch of one); what every integrator, simulation, sweep and plan uses.
  Built by :func:`bracket_inputs` (periodic bracket inputs, one pair per row
  allowed), :func:`bracket_signal`, :func:`sinusoids`,
  :func:`piecewise_constant`, :meth:`Signal.from_segments` /
  :meth:`Signal.stack`; read back with :meth:`Signal.segments` /
  :meth:`Signal.to_segments`.
* :class:`Segment` / :class:`InputSignal` — one segment as a value (the
  planner's unit of work: scaling, time reversal, closed-form integrals).
* :class:`FunctionSignal` — inputs given by any Python function of ``t``
  (integrated by the ``scipy`` engine only).

Piecewise-constant inputs are the case ``K = 0``; the periodic bracket input
of $(I, J)$ is one segment with ``K = 1``: $u_I = -A\omega\sin\omega t$,
$u_J = A\omega\cos\omega t$, whose loop $(\int u_I, \int u_J)$ runs
counter-clockwise round a circle of area $\pi A^2$ per period.  Inputs are
numbered from 1 for users.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from nilpotent.errors import OptionError

__all__ = [
    "FunctionSignal", "InputSignal", "Segment", "Signal", "bracket_inputs", "bracket_signal",
    "check_bracket", "piecewise_constant", "sinusoids",
]


def _frozen(a: Any) -> np.ndarray:
    a = np.array(a, dtype=np.float64, order="C")
    a.setflags(write=False)
    return a


def _floats(values: Sequence[float], what: str) -> tuple[float, ...]:
    out = tuple(float(v) for v in values)
    if not all(math.isfinite(v) for v in out):
        raise OptionError(f"{what}: every value must be a finite number")
    return out


# --- one segment as a value ------------------------------------------------------------


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
        """The plan-segment object (``nilpotent/plan@1``) ``{"duration", "omega", "inputs"}``."""
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


# --- the array form: a batch of controls -----------------------------------------------


@dataclass(frozen=True, eq=False)
class Signal:
    """``B`` piecewise-sinusoidal controls as read-only arrays (a single control: ``B = 1``).

    Attributes
    ----------
    durations:
        ``(B, S)`` segment durations (> 0).
    omegas:
        ``(B, S)`` base angular frequency of each segment.
    constant:
        ``(B, S, m)`` constant terms ``a``.
    cos, sin:
        ``(B, S, m, K)`` coefficients of ``cos(kωτ)`` and ``sin(kωτ)``, ``k = 1..K``
        (``K`` may be 0).

    Raises
    ------
    OptionError
        Shapes that do not match, non-finite coefficients, no segment, or a
        duration ≤ 0.
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
        """``B``, the number of controls."""
        return int(self.durations.shape[0])

    @property
    def segment_count(self) -> int:
        """``S``, segments per control."""
        return int(self.durations.shape[1])

    @property
    def m(self) -> int:
        """Number of inputs."""
        return int(self.constant.shape[2])

    @property
    def harmonics(self) -> int:
        """``K``, the highest harmonic."""
        return int(self.cos.shape[3])

    @property
    def total_durations(self) -> np.ndarray:
        """``(B,)`` total duration of each control."""
        return self.durations.sum(axis=1)

    @property
    def duration(self) -> float:
        """The duration of a single control (the shortest one of a batch)."""
        return float(self.total_durations.min())

    @property
    def breakpoints(self) -> np.ndarray:
        """``(S+1,)`` segment boundaries ``0 = t_0 < … < t_S`` of the first control."""
        return np.concatenate([[0.0], np.cumsum(self.durations[0])])

    # --- derived -----------------------------------------------------------
    def __getitem__(self, rows: int | slice | np.ndarray) -> Signal:
        """The controls ``rows`` as a :class:`Signal` (an integer keeps a batch of one)."""
        if isinstance(rows, int | np.integer):
            rows = slice(int(rows), int(rows) + 1)
        return Signal(self.durations[rows], self.omegas[rows], self.constant[rows],
                      self.cos[rows], self.sin[rows])

    def broadcast(self, batch: int) -> Signal:
        """The same controls repeated to a batch of ``batch`` (from a batch of 1 or ``batch``)."""
        if self.batch == batch:
            return self
        if self.batch != 1:
            raise OptionError(
                f"inputs: a batch of {self.batch} signals cannot serve {batch} states"
            )

        def rep(x: np.ndarray) -> np.ndarray:
            return np.repeat(x, batch, axis=0)

        return Signal(
            rep(self.durations), rep(self.omegas), rep(self.constant), rep(self.cos), rep(self.sin)
        )

    def segment_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """``(segment index, local time)`` of global time ``t`` for each control, ``(B,)`` each.

        Times past the end belong to the last segment.
        """
        starts = np.concatenate([np.zeros((self.batch, 1)), np.cumsum(self.durations, axis=1)], 1)
        idx = np.sum(starts[:, 1:-1] <= t, axis=1)
        local = t - starts[np.arange(self.batch), idx]
        return idx, local

    def evaluate_local(self, segment: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """``(B, m)`` inputs at local times ``tau`` (``(B,)``) in segments ``segment``."""
        rows = np.arange(self.batch)
        out = self.constant[rows, segment].copy()
        k_count = self.harmonics
        if k_count:
            k = np.arange(1, k_count + 1)
            phase = (self.omegas[rows, segment] * tau)[:, None] * k[None, :]  # (B, K)
            out += np.einsum("bik,bk->bi", self.cos[rows, segment], np.cos(phase))
            out += np.einsum("bik,bk->bi", self.sin[rows, segment], np.sin(phase))
        return out

    def evaluate_batch(self, t: float) -> np.ndarray:
        """``(B, m)`` inputs at global time ``t``."""
        seg, tau = self.segment_at(float(t))
        return self.evaluate_local(seg, tau)

    def evaluate(self, t: float) -> np.ndarray:
        """Inputs at global time ``t``: ``(m,)`` for a single control, ``(B, m)`` for a batch."""
        out = self.evaluate_batch(t)
        return out[0] if self.batch == 1 else out

    # --- plan segments ---------------------------------------------------------------
    @classmethod
    def from_segments(cls, segments: Sequence[Any]) -> Signal:
        """A single control from plan segments: :class:`Segment` objects or plan-segment dicts.

        Each segment has ``duration``, ``omega`` and ``inputs``; each input has
        ``constant``, ``cos`` (coefficients of ``cos kωt``, k = 1..) and ``sin``.
        """
        return cls.stack([segments])

    @classmethod
    def stack(cls, batch: Sequence[Sequence[Any]]) -> Signal:
        """``B`` controls from ``B`` sequences of plan segments (same number each)."""
        rows = [[_as_segment(seg) for seg in segs] for segs in batch]
        if not rows or not rows[0]:
            raise OptionError("a signal needs at least one segment")
        s_count = len(rows[0])
        m = rows[0][0].m
        if any(len(segs) != s_count for segs in rows):
            raise OptionError("controls stacked into one batch need the same number of segments")
        if any(seg.m != m for segs in rows for seg in segs):
            raise OptionError("plan segments must all have the same number of inputs")
        k = max((i.harmonics for segs in rows for seg in segs for i in seg.inputs), default=0)
        b = len(rows)
        durations = np.zeros((b, s_count))
        omegas = np.zeros((b, s_count))
        constant = np.zeros((b, s_count, m))
        cos = np.zeros((b, s_count, m, k))
        sin = np.zeros((b, s_count, m, k))
        for bi, segs in enumerate(rows):
            for si, seg in enumerate(segs):
                durations[bi, si] = seg.duration
                omegas[bi, si] = seg.omega
                for i, sig in enumerate(seg.inputs):
                    constant[bi, si, i] = sig.constant
                    cos[bi, si, i, : len(sig.cos)] = sig.cos
                    sin[bi, si, i, : len(sig.sin)] = sig.sin
        return cls(durations, omegas, constant, cos, sin)

    def segments(self, row: int = 0) -> tuple[Segment, ...]:
        """Control ``row`` as :class:`Segment` values."""
        return tuple(
            Segment(
                float(self.durations[row, s]),
                float(self.omegas[row, s]),
                tuple(
                    InputSignal(float(self.constant[row, s, i]),
                                tuple(float(v) for v in self.cos[row, s, i]),
                                tuple(float(v) for v in self.sin[row, s, i]))
                    for i in range(self.m)
                ),
            )
            for s in range(self.segment_count)
        )

    def to_segments(self, row: int = 0) -> list[dict[str, Any]]:
        """Control ``row`` in the plan-segment form of ``nilpotent/plan@1``:
        ``[{"duration", "omega", "inputs": [{"constant", "cos", "sin"}, ...]}, ...]``."""
        return [seg.to_dict() for seg in self.segments(row)]


def _as_segment(seg: Any) -> Segment:
    if isinstance(seg, Segment):
        return seg
    if isinstance(seg, Mapping):
        for name in ("duration", "omega", "inputs"):
            if name not in seg:
                raise OptionError(f"plan segment: missing {name!r}")
        for inp in seg["inputs"]:
            for name in ("constant", "cos", "sin"):
                if not isinstance(inp, Mapping) or name not in inp:
                    raise OptionError(f"plan segment input: missing {name!r}")
        return Segment.from_dict(seg)
    return Segment(float(seg.duration), float(seg.omega),
                   tuple(InputSignal(float(i.constant), tuple(i.cos), tuple(i.sin))
                         for i in seg.inputs))


# --- constructors ----------------------------------------------------------------------


def check_bracket(m: int, bracket: Sequence[int]) -> tuple[int, int]:
    """``(I, J)`` checked: two different field numbers between 1 and ``m``."""
    if len(bracket) != 2:
        raise OptionError(f"a bracket is a pair of field numbers I,J, got {bracket!r}")
    i, j = (int(v) for v in bracket)
    if not (1 <= i <= m and 1 <= j <= m):
        raise OptionError(f"bracket {i},{j}: field numbers must be between 1 and {m}")
    if i == j:
        raise OptionError(f"bracket {i},{j}: the two fields must differ")
    return i, j


def bracket_inputs(
    m: int,
    i: int | Sequence[int] | np.ndarray,
    j: int | Sequence[int] | np.ndarray,
    amplitudes: npt.ArrayLike,
    omega: float = 1.0,
    periods: int = 1,
) -> Signal:
    """The periodic bracket inputs ``u_i = −Aω sin ωt``, ``u_j = Aω cos ωt`` (others 0).

    One segment of ``periods`` periods (duration ``2π·periods/ω``); one
    control per amplitude.  The loop ``(∫u_i, ∫u_j)`` is a counter-clockwise
    circle of area ``πA²`` per period.

    Parameters
    ----------
    m : int
        Number of inputs.
    i, j : int or (B,) int array
        1-based input numbers: one pair for every row, or one pair per row.
    amplitudes : float or (B,) array
        The amplitudes ``A``, one control each.
    omega : float
        ``ω > 0`` (rad/s).
    periods : int
        Whole periods ``≥ 1``.

    Raises
    ------
    OptionError
        A pair out of range or equal, or a non-positive frequency or period count.
    """
    amps = np.atleast_1d(np.asarray(amplitudes, dtype=float))
    if amps.ndim != 1:
        raise OptionError("amplitudes must be a number or a 1-d sequence")
    b = amps.shape[0]
    ii = np.broadcast_to(np.asarray(i, dtype=np.int64), (b,))
    jj = np.broadcast_to(np.asarray(j, dtype=np.int64), (b,))
    bad = (ii < 1) | (ii > m) | (jj < 1) | (jj > m) | (ii == jj)
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise OptionError(
            f"bracket ({int(ii[k])},{int(jj[k])}): need two different inputs between 1 and {m}"
        )
    if not (np.isfinite(omega) and omega > 0):
        raise OptionError(f"omega must be > 0, got {omega}")
    if int(periods) != periods or periods < 1:
        raise OptionError(f"periods must be a positive integer, got {periods}")
    rows = np.arange(b)
    durations = np.full((b, 1), 2 * np.pi * periods / omega)
    omegas = np.full((b, 1), float(omega))
    constant = np.zeros((b, 1, m))
    cos = np.zeros((b, 1, m, 1))
    sin = np.zeros((b, 1, m, 1))
    sin[rows, 0, ii - 1, 0] = -amps * omega
    cos[rows, 0, jj - 1, 0] = amps * omega
    return Signal(durations, omegas, constant, cos, sin)


def bracket_signal(
    m: int, i: int, j: int, amplitude: float, omega: float = 1.0, periods: int = 1
) -> Signal:
    r"""One periodic bracket input $u_i = -A\omega\sin\omega t$, $u_j = A\omega\cos\omega t$.

    Over each period it moves a system by $\pi A^2 [X_i, X_j](p) + O(A^3)$.

    Parameters
    ----------
    m : int
        Number of inputs.
    i, j : int
        The bracket's inputs, 1-based, different, at most ``m``.
    amplitude : float
        $A > 0$.
    omega : float
        $\omega > 0$ (rad/s).
    periods : int
        Whole periods $K \ge 1$ (duration $2\pi K/\omega$).

    Raises
    ------
    OptionError
        Inputs out of range or equal, or a non-positive amplitude, frequency or period count.
    """
    check_bracket(m, (i, j))
    if not (math.isfinite(amplitude) and amplitude > 0):
        raise OptionError(f"amplitude must be > 0, got {amplitude}")
    return bracket_inputs(m, i, j, [amplitude], omega=omega, periods=periods)


def sinusoids(
    constant: Sequence[float],
    cos: Sequence[Sequence[float]],
    sin: Sequence[Sequence[float]],
    omega: float,
    duration: float,
) -> Signal:
    r"""One segment $u_i = a_i + \sum_k b_{ik}\cos k\omega t + c_{ik}\sin k\omega t$.

    Parameters
    ----------
    constant : sequence of float
        ``(a_i)``, one per input.
    cos, sin : sequence of sequences of float
        ``cos[i][k-1]`` $= b_{ik}$, ``sin[i][k-1]`` $= c_{ik}$; the lengths may
        differ per input (padded with 0).
    omega : float
        $\omega > 0$.
    duration : float
        The segment's duration (> 0).
    """
    m = len(constant)
    if len(cos) != m or len(sin) != m:
        raise OptionError("sinusoids: constant, cos and sin need one entry per input")
    inputs = tuple(InputSignal(float(constant[i]), tuple(cos[i]), tuple(sin[i]))
                   for i in range(m))
    return Signal.from_segments([Segment(duration, omega, inputs)])


def piecewise_constant(values: Any, durations: Sequence[float]) -> Signal:
    """Inputs constant on each segment.

    Parameters
    ----------
    values : (S, m) array_like
        The inputs on each segment.
    durations : (S,) sequence of float
        The segments' durations (> 0).
    """
    vals = np.atleast_2d(np.asarray(values, dtype=float))
    s, m = vals.shape
    d = np.asarray(durations, dtype=float).reshape(1, -1)
    if d.shape[1] != s:
        raise OptionError(f"piecewise_constant: {s} rows of values but {d.shape[1]} durations")
    return Signal(d, np.ones((1, s)), vals[None], np.zeros((1, s, m, 0)), np.zeros((1, s, m, 0)))


@dataclass(frozen=True, eq=False)
class FunctionSignal:
    """Inputs given by a Python function ``func(t) -> (m,)`` on ``[0, duration]``.

    ``breakpoints_inside`` (inside ``(0, duration)``) are times where ``func``
    may jump; integration restarts there.  Integrated by the ``scipy`` engine only.
    """

    func: Callable[[float], Any]
    m: int
    duration: float
    breakpoints_inside: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if not callable(self.func):
            raise OptionError("FunctionSignal needs a callable func(t)")
        if not (math.isfinite(self.duration) and self.duration > 0):
            raise OptionError(f"duration must be > 0, got {self.duration}")
        inside = tuple(sorted(float(b) for b in self.breakpoints_inside))
        if any(not 0 < b < self.duration for b in inside):
            raise OptionError("breakpoints must lie strictly inside (0, duration)")
        object.__setattr__(self, "breakpoints_inside", inside)

    @property
    def breakpoints(self) -> np.ndarray:
        return np.array([0.0, *self.breakpoints_inside, float(self.duration)])

    def evaluate(self, t: float) -> np.ndarray:
        """``(m,)`` inputs at time ``t``."""
        return np.asarray(self.func(float(t)), dtype=float).reshape(self.m)

