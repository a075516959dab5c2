r"""The original system and its nilpotent approximation, compiled side by side.

A :class:`CompiledPair` is the one engine that compares a system with its
nilpotent approximation at $p$: comparisons, scaling studies and sweeps all run
through :meth:`CompiledPair.run`.  For a batch of start points $q_0$ (model
coordinates) and controls it integrates

* the original system from $q_0$, and
* the approximation $\hat X_i$ in the privileged coordinates $y$ of $p$ from
  $\hat y_0 = y(q_0)$ (or a given $\hat y_0$),

under the same controls, and returns both (:class:`PairRun`) with the maps
$y(x)$ and $x(y)$ applied on demand.  Errors are measured in $y$ per weight
group $w$: $\max_{w_j = w}|y_j - \hat y_j|$.

A pair is plain data over compiled systems (:class:`~nilpotent.numeric.compile.CompiledSystem`
and :class:`~nilpotent.numeric.compile.CompiledMap` pickle as their fields):
it can be shipped to Dask workers, which reload the generated code from the
cache.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from nilpotent.core.model.system import ControlSystem
from nilpotent.numeric.compile import (
    CompiledMap,
    CompiledSystem,
    compile_fields,
    compile_map,
    compile_system,
)
from nilpotent.numeric.integrate import Status, integrate
from nilpotent.numeric.signals import Signal
from nilpotent.numeric.types import PerTrajectory, Samples, States, Times

__all__ = ["CompiledPair", "PairRun", "weight_groups"]


def weight_groups(weights: tuple[int, ...]) -> tuple[tuple[int, tuple[int, ...]], ...]:
    """``((w, (j, ...)), ...)``: the coordinate indices of each weight, weights increasing."""
    groups: dict[int, list[int]] = {}
    for j, w in enumerate(weights):
        groups.setdefault(int(w), []).append(j)
    return tuple((w, tuple(idx)) for w, idx in sorted(groups.items()))


@dataclass(frozen=True, eq=False)
class CompiledPair:
    r"""A system and its nilpotent approximation at $p$, compiled (picklable).

    Attributes
    ----------
    original:
        The system's fields (model coordinates $x$).
    approximation:
        The fields $\hat X_i$ (privileged coordinates $y$).
    forward:
        $x \mapsto y(x)$.
    inverse:
        $y \mapsto x(y)$.
    weights:
        $w_1 \le \dots \le w_n$ of the coordinates $y_j$.
    """

    original: CompiledSystem
    approximation: CompiledSystem
    forward: CompiledMap
    inverse: CompiledMap
    weights: tuple[int, ...]

    @classmethod
    def build(cls, system: ControlSystem, approximation: Any) -> CompiledPair:
        """Compile ``system`` (parameters substituted) and ``approximation``
        (a :class:`~nilpotent.core.coordinates.approximation.NilpotentApproximation` of it)."""
        sysp = system.specialized()
        coords = approximation.coordinates
        return cls(
            original=compile_system(sysp),
            approximation=compile_fields(coords.names, approximation.fields,
                                         name=f"{sysp.name}-nilpotent"),
            forward=compile_map(sysp.coordinates, coords.forward, name=f"{sysp.name}-forward"),
            inverse=compile_map(coords.names, coords.inverse, name=f"{sysp.name}-inverse"),
            weights=tuple(int(w) for w in approximation.filtration.weights),
        )

    @property
    def groups(self) -> tuple[tuple[int, tuple[int, ...]], ...]:
        """The coordinate indices of each weight (:func:`weight_groups`)."""
        return weight_groups(self.weights)

    def run(
        self,
        starts: States,
        inputs: Signal,
        times: Times,
        *,
        y0: States | None = None,
        **settings: Any,
    ) -> PairRun:
        """Integrate both systems from ``starts`` (``(B, n)``, model coordinates).

        ``inputs`` is a batch of ``B`` controls (or one shared); ``times`` the
        sample times; ``y0`` the approximation's start (default ``y(starts)``);
        ``settings`` go to :func:`~nilpotent.numeric.integrate.integrate`
        (``settings=`` an :class:`~nilpotent.numeric.settings.IntegrationSettings`,
        ``threads``, or the loose ``method``, ``engine``, ``rtol``, ...).
        """
        xs = np.ascontiguousarray(np.asarray(starts, dtype=float))
        ys = self.forward(xs) if y0 is None else np.asarray(y0, dtype=float)
        sol_x = integrate(self.original, xs, inputs, times=times, **settings)
        sol_y = integrate(self.approximation, ys, inputs, times=times, **settings)
        return PairRun(
            pair=self,
            times=np.asarray(sol_x.times),
            x=np.asarray(sol_x.samples),
            y_hat=np.asarray(sol_y.samples),
            final_x=np.asarray(sol_x.final),
            final_y_hat=np.asarray(sol_y.final),
            status_original=np.asarray(sol_x.status),
            status_approximation=np.asarray(sol_y.status),
            tolerance=max(sol_x.tolerance, sol_y.tolerance),
            engines=(sol_x.engine, sol_y.engine),
        )


@dataclass(frozen=True, eq=False)
class PairRun:
    """Both trajectories of a batch (what :meth:`CompiledPair.run` returns).

    Attributes
    ----------
    pair:
        The :class:`CompiledPair` that ran.
    times:
        ``(T,)`` sample times.
    x:
        ``(B, T, n)`` the original system (model coordinates; NaN past an early stop).
    y_hat:
        ``(B, T, n)`` the approximation (privileged coordinates).
    final_x, final_y_hat:
        ``(B, n)`` the end points (the last state reached where stopped early).
    status_original, status_approximation:
        ``(B,)`` :class:`~nilpotent.numeric.integrate.Status` codes.
    tolerance:
        Accuracy of the integrations (the larger of the two).
    engines:
        The engines that integrated the original and the approximation.
    """

    pair: CompiledPair
    times: Times
    x: Samples
    y_hat: Samples
    final_x: States
    final_y_hat: States
    status_original: PerTrajectory
    status_approximation: PerTrajectory
    tolerance: float
    engines: tuple[str, str]

    @property
    def ok(self) -> np.ndarray:
        """``(B,)`` True where both trajectories reached the end."""
        return (self.status_original == Status.SUCCESS) & (
            self.status_approximation == Status.SUCCESS
        )

    def y(self) -> Samples:
        """``(B, T, n)`` the original trajectory in privileged coordinates, ``y(x(t))``."""
        with np.errstate(all="ignore"):
            return self.pair.forward(self.x)

    def x_hat(self) -> Samples:
        """``(B, T, n)`` the approximation in model coordinates, ``x(ŷ(t))``."""
        with np.errstate(all="ignore"):
            return self.pair.inverse(self.y_hat)

    def final_x_hat(self) -> States:
        """``(B, n)`` the approximation's end point in model coordinates."""
        with np.errstate(all="ignore"):
            return self.pair.inverse(self.final_y_hat)

    def final_y(self) -> States:
        """``(B, n)`` the original end point in privileged coordinates."""
        with np.errstate(all="ignore"):
            return self.pair.forward(self.final_x)

    def by_weight(self, diff: np.ndarray, axes: tuple[int, ...]) -> dict[int, np.ndarray]:
        """For each weight ``w``: the maximum of ``diff[..., j]`` over ``w_j = w`` and ``axes``.

        ``diff`` has the coordinates last; ``axes`` are the other axes to
        reduce besides the coordinate axis (``()`` keeps them).
        """
        return {
            w: diff[..., list(idx)].max(axis=(*axes, diff.ndim - 1))
            for w, idx in self.pair.groups
        }
