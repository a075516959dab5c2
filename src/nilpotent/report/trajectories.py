r"""Sampled bracket motions and the amplitude study used by the paper reproduction.

Numbers come from the project's numeric layer (:mod:`nilpotent.numeric`:
compiled fields, adaptive DOP853 through ``solve_ivp`` with rtol ``1e-10``):

* :func:`bracket_motion` — one period of the periodic input
  $u_i = -A\omega\sin\omega t$, $u_j = A\omega\cos\omega t$ ($\omega = 1$) from
  the base point, sampled, for the original system and for its nilpotent
  approximation pushed to the model coordinates; plus the first-order prediction
  $p + \pi A^2 [X_i, X_j](p)$;
* :func:`amplitude_study` — for a range of amplitudes, the end-point error of
  the approximation measured in its privileged coordinates, grouped by weight:
  $e_w(A) = \max_{j: w_j = w} |y_j(x(T)) - \hat y_j(T)|$, with $x$ the original
  trajectory mapped by the coordinate change and $\hat y$ the approximation
  integrated in $y$.  ``MATH.md`` §6 predicts $e_w = O(A^{w+1})$; the slopes are
  *measured* (least squares on log–log), never assumed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp

from nilpotent.core.approximation import NilpotentApproximation
from nilpotent.core.brackets import bracket
from nilpotent.core.system import ControlSystem
from nilpotent.errors import IntegrationError

__all__ = ["ROUND_OFF", "AmplitudeStudy", "BracketMotion", "amplitude_study", "bracket_motion"]

_RTOL = 1e-10
#: Errors below this are round-off of the integration, not approximation errors.
ROUND_OFF = 1e-11
_ATOL = 1e-13


@dataclass(frozen=True)
class BracketMotion:
    """One period of the ``(i, j)`` periodic input, original and approximation.

    Attributes
    ----------
    pair:
        ``(i, j)``, 1-based field numbers: ``u_i = −A sin t``, ``u_j = A cos t``.
    amplitude:
        ``A``.
    times:
        ``(T,)`` sample times in ``[0, 2π]``.
    original, approximation:
        ``(T, n)`` states in the model coordinates.
    prediction:
        ``(n,)``: ``p + πA²[X_i, X_j](p)``.
    bracket_at_point:
        ``[X_i, X_j](p)`` (exact values).
    """

    pair: tuple[int, int]
    amplitude: float
    times: np.ndarray
    original: np.ndarray
    approximation: np.ndarray
    prediction: np.ndarray
    bracket_at_point: tuple[sp.Expr, ...]

    @property
    def endpoint_error(self) -> float:
        """Euclidean distance between the two end states."""
        return float(np.linalg.norm(self.original[-1] - self.approximation[-1]))


@dataclass(frozen=True)
class AmplitudeStudy:
    """End-point errors of the approximation against the amplitude, by weight.

    ``errors[w]`` is ``(K,)``: the largest error among the privileged
    coordinates of weight ``w``; ``endpoint`` the Euclidean end-point error in
    the model coordinates; ``slopes`` the fitted log–log slopes (keys
    ``"weight w"`` and ``"endpoint"``), ``None`` for a group whose errors all
    stay below :data:`ROUND_OFF` (the approximation is exact there up to
    round-off: there is no slope to fit).
    """

    pair: tuple[int, int]
    amplitudes: np.ndarray
    errors: dict[int, np.ndarray]
    endpoint: np.ndarray
    slopes: dict[str, float | None]


def _integrate(
    system: ControlSystem,
    x0: np.ndarray,
    pair: tuple[int, int],
    amplitudes: np.ndarray,
    times: np.ndarray | None = None,
):
    from nilpotent.numeric import Status, bracket_inputs, compile_system, integrate

    compiled = compile_system(system, backend="numpy")
    batch = np.repeat(np.atleast_2d(x0), len(amplitudes), axis=0)
    sol = integrate(
        compiled,
        batch,
        bracket_inputs(system.m, pair[0], pair[1], amplitudes),
        times=times,
        engine="scipy",
        rtol=_RTOL,
        atol=_ATOL,
    )
    if not np.all(sol.status == Status.SUCCESS):
        raise IntegrationError(f"{system.name}: the bracket motion {pair} did not integrate")
    return sol


def _bracket_value(
    system: ControlSystem, pair: tuple[int, int], point: Sequence[sp.Expr]
) -> tuple[sp.Expr, ...]:
    f = system.specialized_fields
    b = bracket(f[pair[0] - 1], f[pair[1] - 1], system.coordinates)
    subs = dict(zip(system.coordinates, point, strict=True))
    return tuple(sp.nsimplify(sp.simplify(sp.S(v).subs(subs))) for v in b)


def bracket_motion(
    approx: NilpotentApproximation,
    pair: tuple[int, int],
    amplitude: float,
    *,
    samples: int = 121,
) -> BracketMotion:
    """Sample one period of the ``pair`` bracket motion for ``approx.system`` and ``approx``.

    The approximation is integrated in the model coordinates
    (``approx.as_system("x")``), from the same point, with the same inputs.
    """
    system = approx.system
    x0 = np.array([float(v) for v in approx.point])
    times = np.linspace(0.0, 2 * math.pi, samples)
    amps = np.array([float(amplitude)])
    orig = _integrate(system, x0, pair, amps, times).samples[0]
    hat = _integrate(approx.as_system("x"), x0, pair, amps, times).samples[0]
    value = _bracket_value(system, pair, approx.point)
    prediction = x0 + math.pi * amplitude**2 * np.array([float(v) for v in value])
    return BracketMotion(pair, float(amplitude), times, orig, hat, prediction, value)


def amplitude_study(
    approx: NilpotentApproximation, pair: tuple[int, int], amplitudes: Sequence[float]
) -> AmplitudeStudy:
    """Errors after one period of the ``pair`` input, for each amplitude, by weight."""
    from nilpotent.viz.scaling import fit_slope

    amps = np.asarray(amplitudes, dtype=float)
    system = approx.system
    x0 = np.array([float(v) for v in approx.point])
    x_end = _integrate(system, x0, pair, amps).final
    hat_x_end = _integrate(approx.as_system("x"), x0, pair, amps).final
    y_hat = _integrate(approx.as_system("y"), np.zeros(system.n), pair, amps).final
    forward = sp.lambdify(system.coordinates, list(approx.coordinates.forward), "numpy")
    y_true = np.array(
        [np.broadcast_to(np.asarray(v, float), (len(amps),)) for v in forward(*x_end.T)]
    ).T
    weights = approx.weights
    errors: dict[int, np.ndarray] = {}
    for w in sorted(set(weights)):
        cols = [j for j, wj in enumerate(weights) if wj == w]
        errors[w] = np.max(np.abs(y_true[:, cols] - y_hat[:, cols]), axis=1)
    endpoint = np.linalg.norm(x_end - hat_x_end, axis=1)
    slopes: dict[str, float | None] = {}
    for label, e in [*((f"weight {w}", e) for w, e in errors.items()), ("endpoint", endpoint)]:
        slopes[label] = fit_slope(amps, e)[0] if float(np.max(e)) > ROUND_OFF else None
    return AmplitudeStudy(tuple(pair), amps, errors, endpoint, slopes)
