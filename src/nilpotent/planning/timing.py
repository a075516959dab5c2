r"""Plans re-timed under input bounds (TOPP-RA), and the reversals of their inputs.

A driftless system ``ẋ = Σ u_i X_i(x)`` can be re-timed freely along its path: with
the planned controls ``u(s)`` (``s``, the plan's own time) and any increasing
``t ↦ s(t)``, the inputs

.. math::

    \tilde u(t) = u(s(t))\,\dot s(t)

move the system along the same path, ``x̃(t) = x(s(t))``.  The re-timing is a
time-optimal path parametrisation of the *input displacement*
``w(s) = ∫_0^s u(σ) dσ`` (``m``-dimensional): ``dw/dt = ũ`` and
``d²w/dt² = dũ/dt = u'(s) ṡ² + u(s) s̈``, so the bounds ``|ũ_i| ≤ V_i`` and
``|dũ_i/dt| ≤ A_i`` are the joint velocity and acceleration constraints of TOPP-RA
(Pham & Pham, "A new approach to time-optimal path parameterization based on
reachability analysis", IEEE T-RO 34(3), 2018; the ``toppra`` package), with
``w``, ``w' = u`` and ``w'' = u'`` given exactly (closed forms of the sinusoids).

The inputs of the re-timed motion are continuous: the path is cut where the
planned input jumps (a segment boundary whose two sides differ), every piece is
re-timed from rest to rest (``ṡ = 0`` at both of its ends) and the pieces are
concatenated; inside a piece ``ũ`` is continuous (``u`` is, and TOPP-RA's ``ṡ`` is).
An input that reverses inside a piece passes through 0 there (``ũ_i = u_i ṡ``).

TOPP-RA keeps the bounds at its grid points; between them they can be exceeded
by a little.  Each piece is therefore sampled densely (:data:`CHECK_FACTOR` points
per grid cell) and at the exported samples, and slowed down uniformly by the
factor ``c = max(1, max|ũ_i|/V_i, √(max|dũ_i/dt|/A_i))`` measured there
(``t ↦ c t`` divides speeds by ``c`` and accelerations by ``c²``; the exported
samples sit at the same fractions of the piece's duration, so they are within the
bounds).  The states ``x`` of the samples are the true system's re-simulation of
the plan at the plan times ``s(t)``.

:func:`input_reversals` counts, per input, the sign changes of ``u_i`` along the
plan (the re-timing changes none: ``ṡ > 0``); :func:`drive_reversals` those of the
drive input of the vehicle models (:data:`DRIVE_INPUTS`).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ComputationLimitError, IntegrationError, OptionError, PlanningError
from nilpotent.models import is_builtin
from nilpotent.numeric.settings import IntegrationSettings
from nilpotent.numeric.signals import InputSignal, Segment, Signal
from nilpotent.numeric.types import State
from nilpotent.planning import budget
from nilpotent.strict_json import json_object

__all__ = [
    "DRIVE_INPUTS", "InputBounds", "TimedTrajectory", "bound_values", "drive_reversals",
    "input_bounds", "input_names", "input_reversals", "motion_fields", "retime",
]

#: Vehicle models and their drive input (0-based): the forward speed, whose sign
#: changes are the vehicle's reversals (``car-trailers:K`` for every ``K``).
DRIVE_INPUTS: dict[str, int] = {"car": 0, "unicycle": 0, "car-trailers": 0}
#: The range of a bound (model units per unit time, or per unit time squared): TOPP-RA's
#: sets are computed on squared path speeds, which leave the doubles' range far out.
MIN_BOUND, MAX_BOUND = 1e-9, 1e6
#: A value ``|u_i|`` below this fraction of ``max |u_i|`` over the plan has no sign
#: (reversals are counted between values above it).
REVERSAL_FRACTION = 1e-6
#: Samples per segment and per harmonic where reversals are counted.
REVERSAL_SAMPLES = 64
#: A segment boundary is a jump when the inputs on its two sides differ by more than
#: this fraction of the largest input (or absolutely, for inputs below 1).
JUMP_FRACTION = 1e-9
#: A piece whose inputs stay below this fraction of the plan's largest input does not
#: move (it is left out of the re-timed motion: plan time passes at a stop).
REST_FRACTION = 1e-12
#: TOPP-RA grid points per segment of the plan and per harmonic (at least one harmonic).
GRID_PER_SEGMENT = 100
#: Points per grid cell where the bounds are checked after TOPP-RA (module doc).
CHECK_FACTOR = 4
#: Exported samples of the whole trajectory when no step is given.
DEFAULT_SAMPLES = 500
#: Most exported samples (memory of the JSON and CSV outputs).
MAX_SAMPLES = 200_000
#: Most TOPP-RA grid points of a plan (time).
MAX_GRID = 2_000_000


def input_names(m: int) -> tuple[str, ...]:
    """The names of the inputs in bounds and exports: ``u1`` … ``um`` (``u_i`` drives ``X_i``)."""
    return tuple(f"u{i}" for i in range(1, m + 1))


def bound_values(
    m: int, value: float | Sequence[float] | Mapping[str, float], option: str, *,
    every: bool = False,
) -> tuple[float, ...]:
    """One bound per input from a number (every input), ``m`` numbers, or ``{"u1": V, ...}``.

    Inputs a mapping leaves out are unbounded (``inf``) unless ``every`` is set, when
    each input must be named and bounded; without ``every`` a bound may also be
    ``math.inf`` (none).

    Raises
    ------
    OptionError
        A bound that is not a number > 0 (finite with ``every``) or is outside
        [:data:`MIN_BOUND`, :data:`MAX_BOUND`], an unknown input name, ``m`` numbers
        expected and another count given, an input left out with ``every``.
    """
    names = input_names(m)
    if isinstance(value, Mapping):
        unknown = [str(k) for k in value if k not in names]
        if unknown:
            raise OptionError(
                f"{option}: unknown input {unknown[0][:40]!r} (inputs: {', '.join(names)})")
        missing = [k for k in names if k not in value]
        if every and missing:
            raise OptionError(
                f"{option} must bound every input ({', '.join(names)}); missing "
                f"{', '.join(missing)}")
        values = [value.get(k, math.inf) for k in names]
        given = [value[k] for k in names if k in value]
    elif isinstance(value, int | float | np.floating | np.integer) and not isinstance(value, bool):
        values = given = [float(value)] * m
    elif isinstance(value, Sequence) and not isinstance(value, str):
        if len(value) != m:
            raise OptionError(f"{option}: {len(value)} bounds given for {m} inputs")
        values = given = list(value)
    else:
        raise OptionError(
            f"{option} must be a number, {m} numbers or a mapping {{'u1': bound, ...}}")
    for v in given:
        if isinstance(v, bool) or not isinstance(v, int | float | np.floating | np.integer):
            raise OptionError(f"{option}: a bound must be a number, got {type(v).__name__}")
        number = float(v)
        if not (number > 0 and (math.isfinite(number) or (number == math.inf and not every))):
            raise OptionError(f"{option}: a bound must be a finite number > 0, got {v}")
        if math.isfinite(number) and not MIN_BOUND <= number <= MAX_BOUND:
            raise OptionError(
                f"{option}: a bound must be between {MIN_BOUND:g} and {MAX_BOUND:g}, got {v}")
    return tuple(float(v) for v in values)


@dataclass(frozen=True)
class InputBounds:
    """Bounds on every input ``|ũ_i| ≤ speed[i]`` and ``|dũ_i/dt| ≤ accel[i]``.

    ``speed`` entries may be ``inf`` (no speed bound on that input); ``accel`` ones
    are finite (the inputs are continuous only with bounded accelerations).
    """

    speed: tuple[float, ...]
    accel: tuple[float, ...]

    def to_json(self) -> dict[str, Any]:
        """``{"max_speed": [...], "max_accel": [...]}`` (``null``: no bound)."""
        return json_object({"max_speed": [v if math.isfinite(v) else None for v in self.speed],
                            "max_accel": list(self.accel)})


def input_bounds(
    m: int, max_speed: float | Sequence[float] | Mapping[str, float] | None,
    max_accel: float | Sequence[float] | Mapping[str, float] | None,
    speed_option: str = "max_speed", accel_option: str = "max_accel", *,
    step: float | None = None,
) -> InputBounds | None:
    """The bounds of :func:`retime` from the user's values (:func:`bound_values`), or
    ``None`` when neither is given; ``step`` (the samples' spacing, ``None``: the
    default) is checked with them.

    Raises
    ------
    OptionError
        A bad bound (:func:`bound_values`), a speed bound without an acceleration
        bound (the re-timed inputs would jump at rest points), a step that is not a
        positive number or is given without bounds.
    """
    if step is not None and not (math.isfinite(step) and step > 0):
        raise OptionError(f"the trajectory step must be a positive number, got {step}")
    if max_speed is None and max_accel is None:
        if step is not None:
            raise OptionError(f"a trajectory step needs {accel_option} (the re-timing's bounds)")
        return None
    if max_accel is None:
        raise OptionError(
            f"{speed_option} needs {accel_option} too: without an acceleration bound the "
            "re-timed inputs jump from rest to full speed")
    accel = bound_values(m, max_accel, accel_option, every=True)
    speed = (math.inf,) * m if max_speed is None else bound_values(m, max_speed, speed_option)
    if all(v == math.inf for v in speed) and max_speed is not None and not isinstance(
            max_speed, Mapping):
        raise OptionError(f"{speed_option}: every bound is infinite (leave it out instead)")
    return InputBounds(speed, accel)


# --- the controls as a geometric path ----------------------------------------------------


def _derivative(sig: InputSignal, omega: float) -> InputSignal:
    """``u'``: ``d/dτ (a cos kωτ + b sin kωτ) = kω (b cos kωτ − a sin kωτ)``."""
    return InputSignal(
        0.0, tuple(k * omega * b for k, b in enumerate(sig.sin, start=1)),
        tuple(-k * omega * a for k, a in enumerate(sig.cos, start=1)))


def _antiderivative(sig: InputSignal, omega: float) -> InputSignal:
    """``∫_0^τ u − cτ``: ``a sin(kωτ)/(kω) + b (1 − cos kωτ)/(kω)``."""
    return InputSignal(
        sum(b / (k * omega) for k, b in enumerate(sig.sin, start=1)),
        tuple(-b / (k * omega) for k, b in enumerate(sig.sin, start=1)),
        tuple(a / (k * omega) for k, a in enumerate(sig.cos, start=1)))


def _toppra() -> Any:
    try:
        import toppra
        import toppra.algorithm
        import toppra.constraint
        import toppra.interpolator
        import toppra.parametrizer
    except ImportError as exc:  # pragma: no cover - a default dependency
        raise OptionError(f"re-timing needs the toppra package ({exc})") from None
    return toppra


def _input_path(segments: Sequence[Segment], starts: np.ndarray, scale: float) -> Any:
    """``W = w / D`` as a toppra geometric path of ``σ = (s − s₀)/d`` on ``[0, 1]``
    (``d``, the piece's plan duration; ``D = scale``, the size of its input
    displacement; ``w = 0`` at the start; right-continuous at the segment boundaries
    inside): ``dW/dσ = u d/D``, ``d²W/dσ² = u' d²/D`` (module doc of :func:`_profile`)."""
    toppra = _toppra()
    lo, span = float(starts[0]), float(starts[-1] - starts[0])

    class InputPath(toppra.interpolator.AbstractGeometricPath):
        def __init__(self) -> None:
            self.segments = tuple(segments)
            self.starts = np.asarray(starts, dtype=float)
            self.derivatives = tuple(
                Segment(s.duration, s.omega, tuple(_derivative(i, s.omega) for i in s.inputs))
                for s in segments)
            self.primitives = tuple(
                Segment(s.duration, s.omega, tuple(_antiderivative(i, s.omega)
                                                   for i in s.inputs))
                for s in segments)
            self.linear = tuple(np.array([i.constant for i in s.inputs]) for s in segments)
            self.offsets = np.vstack([np.zeros(segments[0].m),
                                      np.cumsum([s.integrals() for s in segments], axis=0)])

        @property
        def dof(self) -> int:
            return self.segments[0].m

        @property
        def path_interval(self) -> np.ndarray:
            return np.array([0.0, 1.0])

        def __call__(self, path_positions: Any, order: int = 0) -> np.ndarray:
            scalar = np.ndim(path_positions) == 0
            s = lo + span * np.atleast_1d(np.asarray(path_positions, dtype=float))
            idx = np.clip(np.searchsorted(self.starts, s, side="right") - 1, 0,
                          len(self.segments) - 1)
            out = np.empty((s.size, self.dof))
            for k in np.unique(idx):
                sel = idx == k
                tau = s[sel] - self.starts[k]
                if order == 0:
                    vals = (self.primitives[k].values(tau).T + self.offsets[k]
                            + tau[:, None] * self.linear[k][None, :]) / scale
                elif order == 1:
                    vals = self.segments[k].values(tau).T * (span / scale)
                elif order == 2:
                    vals = self.derivatives[k].values(tau).T * (span**2 / scale)
                else:
                    raise ValueError(f"order {order} is not supported")
                out[sel] = vals
            return out[0] if scalar else out

    return InputPath()


def _clock(lo: float, span: float) -> Any:
    """The path ``σ ↦ s = lo + span·σ`` on ``[0, 1]``: re-timed by toppra's parametrizer
    it gives the plan time ``s``."""
    toppra = _toppra()

    class Clock(toppra.interpolator.AbstractGeometricPath):
        @property
        def dof(self) -> int:
            return 1

        @property
        def path_interval(self) -> np.ndarray:
            return np.array([0.0, 1.0])

        def __call__(self, path_positions: Any, order: int = 0) -> np.ndarray:
            sigma = np.atleast_1d(np.asarray(path_positions, dtype=float))[:, None]
            if order == 0:
                out = lo + span * sigma
            else:
                out = np.full_like(sigma, span if order == 1 else 0.0)
            return out[0] if np.ndim(path_positions) == 0 else out

    return Clock()


def _pieces(segments: Sequence[Segment]) -> list[tuple[int, int]]:
    """``(first, last + 1)`` segment ranges between the jumps of the inputs."""
    scale = max(1.0, max(float(np.max(np.abs(s.values(np.linspace(0, s.duration, 9)))))
                         for s in segments))
    cuts = [0]
    for k in range(1, len(segments)):
        left = segments[k - 1].values(segments[k - 1].duration)
        right = segments[k].values(0.0)
        if float(np.max(np.abs(left - right))) > JUMP_FRACTION * scale:
            cuts.append(k)
    cuts.append(len(segments))
    return list(itertools.pairwise(cuts))


def _grid(segments: Sequence[Segment], starts: np.ndarray) -> np.ndarray:
    parts = [np.linspace(starts[k], starts[k + 1],
                         GRID_PER_SEGMENT * max(1, max(i.harmonics for i in s.inputs)) + 1)
             for k, s in enumerate(segments)]
    grid = np.unique(np.concatenate(parts))
    grid[0], grid[-1] = starts[0], starts[-1]
    return grid


@dataclass(frozen=True)
class _Profile:
    """One piece re-timed in the scaled variables of :func:`_profile`: toppra's
    trajectories of ``W`` and of the clock (in ``τ = t/T₀``), their duration in ``τ``,
    the units ``T₀`` and ``D``, and the slow-down measured on the dense check."""

    inputs: Any
    clock: Any
    duration: float
    unit_time: float
    unit_input: float
    slowdown: float = 1.0

    def at(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(s, ũ, dũ/dt)`` at the scaled times ``tau`` (before the slow-down)."""
        d, t0 = self.unit_input, self.unit_time
        return (self.clock(tau, 0)[:, 0], self.inputs(tau, 1) * (d / t0),
                self.inputs(tau, 2) * (d / t0**2))


def _slowdown(profile: _Profile, tau: np.ndarray, bounds: InputBounds) -> float:
    """``c ≥ 1`` such that ``t ↦ c t`` brings the samples at ``tau`` within the bounds."""
    _, speed, accel = profile.at(tau)
    ratio_v = float(np.max(np.abs(speed) / np.asarray(bounds.speed)[None, :]))
    ratio_a = float(np.max(np.abs(accel) / np.asarray(bounds.accel)[None, :]))
    return max(1.0, ratio_v, math.sqrt(ratio_a))


def _profile(segments: Sequence[Segment], starts: np.ndarray, bounds: InputBounds) -> _Profile:
    """TOPP-RA on one piece, in scaled variables so that its numbers are of order one
    whatever the size of the piece (the corrections at the end of a plan move by 1e-8):
    ``σ = (s − s₀)/d ∈ [0, 1]``, ``W = w/D`` (``D = d·max|u|``, so ``|dW/dσ| ≤ 1``),
    ``τ = t/T₀`` with ``T₀ = √(D / min A)``; the bounds become ``V T₀/D`` and
    ``A T₀²/D`` (``min A`` of them is 1)."""
    toppra = _toppra()
    span = float(starts[-1] - starts[0])
    biggest = max(float(np.max(np.abs(s.values(np.linspace(0, s.duration, 33)))))
                  for s in segments)
    unit_input = span * biggest
    unit_time = math.sqrt(unit_input / min(bounds.accel))
    path = _input_path(segments, starts, unit_input)
    grid = (_grid(segments, starts) - starts[0]) / span
    grid[0], grid[-1] = 0.0, 1.0
    accel = np.asarray(bounds.accel) * (unit_time**2 / unit_input)
    constraints: list[Any] = [toppra.constraint.JointAccelerationConstraint(accel)]
    if any(math.isfinite(v) for v in bounds.speed):
        # an unbounded input: a bound it never reaches (toppra takes finite limits only)
        finite = max(v for v in bounds.speed if math.isfinite(v))
        speed = np.array([v if math.isfinite(v) else 1e6 * finite for v in bounds.speed])
        constraints.insert(0, toppra.constraint.JointVelocityConstraint(
            speed * (unit_time / unit_input)))
    algorithm = toppra.algorithm.TOPPRA(constraints, path, gridpoints=grid,
                                        solver_wrapper="seidel",
                                        parametrizer="ParametrizeConstAccel")
    result = algorithm.compute_parameterization(0.0, 0.0)
    sd = None if result is None else result[1]
    if sd is None or not np.all(np.isfinite(sd)):
        raise PlanningError(
            "TOPP-RA found no time parametrisation of the plan under the input bounds "
            f"(the piece of plan time {starts[0]:.6g} to {starts[-1]:.6g})")
    sd = np.maximum(np.asarray(sd, dtype=float), 0.0)
    sd[0] = sd[-1] = 0.0
    profile = _Profile(toppra.parametrizer.ParametrizeConstAccel(path, grid, sd),
                       toppra.parametrizer.ParametrizeConstAccel(_clock(starts[0], span),
                                                                 grid, sd),
                       0.0, unit_time, unit_input)
    duration = float(profile.clock.duration)
    if not (math.isfinite(duration) and duration > 0):
        raise PlanningError("TOPP-RA gave a time parametrisation of no positive duration")
    check = np.linspace(0.0, duration, CHECK_FACTOR * (grid.size - 1) + 1)
    profile = dataclasses.replace(profile, duration=duration)
    return dataclasses.replace(profile, slowdown=_slowdown(profile, check, bounds))


# --- the re-timed trajectory ---------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class TimedTrajectory:
    """The plan re-timed under input bounds, sampled (:func:`retime`).

    Attributes
    ----------
    times:
        ``(N,)`` sample times ``t`` (from 0; at most the step apart, and at every stop).
    states:
        ``(N, n)`` configurations (model coordinates) at the samples.
    inputs:
        ``(N, m)`` re-timed inputs ``ũ(t) = u(s(t)) ṡ(t)``.
    accelerations:
        ``(N, m)`` ``dũ/dt`` at the samples (at a stop: the one of the piece that ends
        there; at ``t = 0``: of the first piece).
    plan_times:
        ``(N,)`` ``s(t)``, the plan's own time reached at each sample.
    stops:
        Times where the motion is at rest (``ũ = 0``): both ends and every jump of the
        planned inputs.
    bounds:
        The bounds kept.
    coordinate_names:
        The model's coordinates (the CSV header).
    """

    times: np.ndarray
    states: np.ndarray
    inputs: np.ndarray
    accelerations: np.ndarray
    plan_times: np.ndarray
    stops: tuple[float, ...]
    bounds: InputBounds
    coordinate_names: tuple[str, ...]

    @property
    def duration(self) -> float:
        """The re-timed motion's duration."""
        return float(self.times[-1])

    def to_json(self) -> dict[str, Any]:
        """``{"t": [...], "x": [[...]], "u": [[...]]}`` (one row per sample) with
        ``duration``, ``plan_time`` (``s(t)``), ``stops``, ``max_speed``, ``max_accel``."""
        return json_object({
            "t": self.times.tolist(), "x": self.states.tolist(), "u": self.inputs.tolist(),
            "plan_time": self.plan_times.tolist(), "duration": self.duration,
            "stops": list(self.stops), **self.bounds.to_json(),
        })

    def to_csv(self) -> str:
        """The samples as CSV: header ``t,<coordinates>,u1..um``, one row per sample
        (numbers written to round-trip, 17 significant digits)."""
        header = ["t", *self.coordinate_names, *input_names(self.inputs.shape[1])]
        rows = np.hstack([self.times[:, None], self.states, self.inputs])
        lines = [",".join(header)]
        lines += [",".join(format(float(v), ".17g") for v in row) for row in rows]
        return "\n".join(lines) + "\n"


def retime(
    system: ControlSystem, start: Sequence[float] | State, segments: Sequence[Segment],
    bounds: InputBounds, *, step: float | None = None, reached: Sequence[float] | None = None,
    settings: IntegrationSettings | None = None,
) -> TimedTrajectory:
    """The plan ``segments`` from ``start`` re-timed under ``bounds`` (module doc), sampled.

    Parameters
    ----------
    system : ControlSystem
        The model the plan steers.
    start : sequence of float
        Where the plan starts (model coordinates).
    segments : sequence of Segment
        The plan's controls.
    bounds : InputBounds
        ``|ũ_i| ≤ speed[i]``, ``|dũ_i/dt| ≤ accel[i]`` at every sample.
    step : float or None
        Largest time between samples (> 0; default: the duration over
        :data:`DEFAULT_SAMPLES`).  Every stop is a sample.
    reached : sequence of float or None
        The plan's verified end point: the last sample's state must agree with it
        (to ``1e-8`` relative), and is then set to it.
    settings : IntegrationSettings or None
        How the re-simulation that gives the states integrates (default
        :data:`~nilpotent.planning.simulation.PLANNING_SETTINGS`).

    Raises
    ------
    OptionError
        Segments of another number of inputs than ``bounds``, a bad ``step``.
        (A plan without segments, or whose inputs are all 0, gives one sample at rest.)
    ComputationLimitError
        More than :data:`MAX_SAMPLES` samples or :data:`MAX_GRID` grid points.
    PlanningError
        TOPP-RA finds no parametrisation.
    IntegrationError
        The re-simulation fails, or ends away from ``reached``.
    """
    segs = tuple(segments)
    if step is not None and not (math.isfinite(step) and step > 0):
        raise OptionError(f"the trajectory step must be a positive number, got {step}")
    if not segs:  # the goal is the start: the motion is one sample at rest
        return _at_rest(system, start, 0.0, bounds, reached)
    m = segs[0].m
    if len(bounds.speed) != m or len(bounds.accel) != m:
        raise OptionError(f"bounds for {len(bounds.accel)} inputs, the plan has {m}")
    starts = np.concatenate([[0.0], np.cumsum([s.duration for s in segs])])
    grid_points = sum(GRID_PER_SEGMENT * max(1, max(i.harmonics for i in s.inputs)) for s in segs)
    if grid_points > MAX_GRID:
        raise ComputationLimitError(
            f"re-timing this plan needs {grid_points:,} TOPP-RA grid points, above the limit "
            f"{MAX_GRID:,}")
    scale = max(float(np.max(np.abs(s.values(np.linspace(0, s.duration, 17))))) for s in segs)
    profiles: list[tuple[float, float, _Profile | None]] = []
    for a, b in _pieces(segs):
        budget.check("re-timing the plan under the input bounds (TOPP-RA)")
        piece = segs[a:b]
        moving = max(float(np.max(np.abs(s.values(np.linspace(0, s.duration, 17)))))
                     for s in piece)
        if moving <= REST_FRACTION * scale:
            profiles.append((starts[a], starts[b], None))  # no motion: skipped
            continue
        profiles.append((starts[a], starts[b], _profile(piece, starts[a:b + 1], bounds)))
    moving_profiles = [p for _, _, p in profiles if p is not None]
    if not moving_profiles:  # every input is 0: the plan stays where it starts
        return _at_rest(system, start, float(starts[-1]), bounds, reached)
    total = sum(p.duration * p.unit_time * p.slowdown for p in moving_profiles)
    if step is None:
        step = total / DEFAULT_SAMPLES
    count = sum(math.ceil(p.duration * p.unit_time * p.slowdown / step) + 1
                for p in moving_profiles)
    if count > MAX_SAMPLES:
        raise ComputationLimitError(
            f"the re-timed trajectory of duration {total:.4g} would have {count:,} samples "
            f"of step {step:g}, above the limit {MAX_SAMPLES:,}; use a larger step")
    times: list[np.ndarray] = []
    plan_times: list[np.ndarray] = []
    inputs: list[np.ndarray] = []
    accels: list[np.ndarray] = []
    stops = [0.0]
    clock = 0.0
    for _lo, _hi, p in profiles:
        if p is None:
            continue
        k = max(2, math.ceil(p.duration * p.unit_time * p.slowdown / step) + 1)
        tau = np.linspace(0.0, p.duration, k)
        c = max(p.slowdown, _slowdown(p, tau, bounds))
        first = 0 if not times else 1  # the shared stop is the previous piece's last sample
        s_k, u_k, du_k = p.at(tau[first:])
        times.append(clock + c * p.unit_time * tau[first:])
        plan_times.append(s_k)
        inputs.append(u_k / c)
        accels.append(du_k / c**2)
        clock = float(times[-1][-1])
        stops.append(clock)
    t_all = np.concatenate(times)
    s_all = np.clip(np.concatenate(plan_times), 0.0, starts[-1])
    s_all[0], s_all[-1] = 0.0, starts[-1]
    u_all = np.vstack(inputs)
    if settings is None:
        from nilpotent.planning.simulation import PLANNING_SETTINGS

        settings = PLANNING_SETTINGS
    states = _states_at(system, start, segs, s_all, settings)
    if reached is not None:
        want = np.asarray(reached, dtype=float)
        if not np.allclose(states[-1], want, rtol=1e-8, atol=1e-8):
            raise IntegrationError(
                "the re-simulation of the re-timed plan ends "
                f"{float(np.linalg.norm(states[-1] - want)):.3g} away from the plan's point")
        states[-1] = want
    for arr in (t_all, states, u_all):
        arr.setflags(write=False)
    acc = np.vstack(accels)
    acc.setflags(write=False)
    s_all.setflags(write=False)
    return TimedTrajectory(t_all, states, u_all, acc, s_all, tuple(stops), bounds,
                           tuple(system.coordinate_names))


def _at_rest(system: ControlSystem, start: Sequence[float] | State, plan_time: float,
             bounds: InputBounds, reached: Sequence[float] | None) -> TimedTrajectory:
    """The re-timing of a plan that does not move: one sample at ``t = 0``, inputs 0."""
    state = np.asarray(start, dtype=float).reshape(1, -1).copy()
    if reached is not None:
        want = np.asarray(reached, dtype=float)
        if not np.allclose(state[0], want, rtol=1e-8, atol=1e-8):
            raise IntegrationError("a plan that does not move ends away from its start")
        state[0] = want
    m = len(bounds.accel)
    arrays = (np.zeros(1), state, np.zeros((1, m)), np.zeros((1, m)), np.array([plan_time]))
    for arr in arrays:
        arr.setflags(write=False)
    return TimedTrajectory(*arrays, (0.0,), bounds, tuple(system.coordinate_names))


def _states_at(system: ControlSystem, start: Sequence[float] | State,
               segments: Sequence[Segment], plan_times: np.ndarray,
               settings: IntegrationSettings) -> np.ndarray:
    """The true system's states at the plan times (non-decreasing), one re-simulation."""
    from nilpotent.planning.local_model import compiled_system
    from nilpotent.planning.simulation import single_engine
    from nilpotent.simulation.trajectory import simulate

    budget.check("re-simulating the re-timed plan")
    unique, inverse = np.unique(plan_times, return_inverse=True)
    traj = simulate(compiled_system(system), Signal.from_segments(segments),
                    np.asarray(start, dtype=float), times=unique,
                    settings=settings.replace(engine=single_engine(settings, system)))
    states = np.asarray(traj.states, dtype=float)
    if states.shape[0] != unique.size or not np.all(np.isfinite(states)):
        raise IntegrationError("the re-simulation of the re-timed plan failed")
    return states[inverse].copy()


# --- reversals ---------------------------------------------------------------------------


def _sampled_inputs(segments: Sequence[Segment]) -> np.ndarray:
    rows = [s.values(np.linspace(0.0, s.duration,
                                 REVERSAL_SAMPLES * max(1, max(i.harmonics for i in s.inputs))
                                 + 1)).T
            for s in segments]
    return np.vstack(rows)


def input_reversals(segments: Sequence[Segment]) -> tuple[int, ...]:
    """Per input, the sign changes of ``u_i`` along the plan.

    ``u_i`` is sampled :data:`REVERSAL_SAMPLES` times per segment and harmonic (and at
    both ends of every segment); values with ``|u_i|`` below
    :data:`REVERSAL_FRACTION` of the input's largest one are ignored.
    """
    if not segments:
        return ()
    values = _sampled_inputs(segments)
    out = []
    for col in values.T:
        big = np.max(np.abs(col))
        signs = np.sign(col[np.abs(col) > REVERSAL_FRACTION * big]) if big > 0 else np.zeros(0)
        out.append(int(np.count_nonzero(signs[1:] != signs[:-1])))
    return tuple(out)


def drive_reversals(system: ControlSystem, segments: Sequence[Segment]) -> int | None:
    """The reversals of a vehicle model's drive input (:data:`DRIVE_INPUTS`), or ``None``
    for a model without one.  A vehicle model is a built-in one of those names (any
    parameters), or a model file with its fields: a file that only borrows the name
    (``name = "unicycle"`` over other fields) has no drive input."""
    index = DRIVE_INPUTS.get(system.name.partition(":")[0])
    if index is None or index >= system.m or not is_builtin(system):
        return None
    return input_reversals(segments)[index] if segments else 0


def motion_fields(system: ControlSystem, segments: Sequence[Segment],
                  timed: TimedTrajectory | None, reasons: dict[str, str]) -> dict[str, Any]:
    """The plan JSON's ``input_reversals``, ``reversals`` and (when re-timed)
    ``trajectory``; the reason of a ``null`` ``reversals`` is added to ``reasons``."""
    out: dict[str, Any] = {"input_reversals": list(input_reversals(segments)),
                           "reversals": drive_reversals(system, segments)}
    if out["reversals"] is None:
        reasons["reversals"] = (f"model {system.name} has no drive input (vehicle models: "
                                "car, unicycle, car-trailers)")
    if timed is not None:
        out["trajectory"] = timed.to_json()
    return out
