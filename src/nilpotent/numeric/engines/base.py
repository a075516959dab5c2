"""The engines' contract in code: the base class, its status codes and shared checks.

What every engine module imports (:class:`Engine`, :class:`Status`,
:data:`EngineOutput`, :func:`check_times`, :func:`state_status`); the registry
and the choice of an engine are in :mod:`nilpotent.numeric.engines`, whose
docstring is the written contract.
"""

from __future__ import annotations

import abc
import weakref
from enum import IntEnum
from typing import Any, ClassVar

import numpy as np

from nilpotent.errors import MissingExtraError, OptionError

__all__ = ["Engine", "EngineOutput", "Status", "check_times", "compiled_memo", "state_status"]

#: ``(final (B, n), samples (B, T, n), info (B, 4))``: what :meth:`Engine.solve` returns.
EngineOutput = tuple[np.ndarray, np.ndarray, np.ndarray]


class _Memo(dict):
    """The engines' cache of one system (a ``dict`` that weak references can point to)."""


# one memo per key: systems with the same fields (a renamed model, the same fields
# built twice) share their compiled integrators; it lives as long as one of them
_SHARED: weakref.WeakValueDictionary[str, _Memo] = weakref.WeakValueDictionary()
_OF: weakref.WeakKeyDictionary[Any, _Memo] = weakref.WeakKeyDictionary()


def compiled_memo(system: Any) -> dict:
    """The engines' per-process cache for a compiled system (owned here, not by the system).

    What the engines build for ``system`` (a
    :class:`~nilpotent.numeric.compile.CompiledSystem`) and keep: heyoka's compiled
    integrators, whether numba's kernels were called.  Systems with the same
    ``key`` (the same fields) share it; it is freed with the last of them.
    """
    memo = _OF.get(system)
    if memo is None:
        memo = _SHARED.get(system.key)
        if memo is None:
            memo = _SHARED.setdefault(system.key, _Memo())
        _OF[system] = memo
    return memo


class Status(IntEnum):
    """Outcome of one trajectory (the members' :attr:`message` is what users read)."""

    SUCCESS = 0
    MAX_STEPS = 1
    STEP_TOO_SMALL = 2
    BLOW_UP = 3
    NON_FINITE = 4

    @property
    def message(self) -> str:
        return {
            0: "integrated to the end",
            1: "stopped: too many steps (max_steps)",
            2: "stopped: step size below min_step",
            3: "stopped: the state left the bound |x_k| <= bound (blow-up)",
            4: "stopped: the state is not finite",
        }[int(self)]


class Engine(abc.ABC):
    """Base class of the integration engines (the contract is the module docstring)."""

    name: ClassVar[str]
    methods: ClassVar[tuple[str, ...]]
    summary: ClassVar[str]
    install: ClassVar[str] = ""

    def available(self) -> bool:
        """Whether the engine's dependencies can be imported."""
        return True

    def cached(self, system: Any) -> bool:
        """Whether running ``system`` needs no compilation first (``"auto"`` prefers such)."""
        del system
        return True

    def handles(self, system: Any) -> bool:
        """Whether the engine can integrate ``system``'s fields (else ``"auto"`` skips it)."""
        del system
        return True

    def require(self) -> None:
        """Raise :class:`MissingExtraError` (naming the install) if not :meth:`available`."""
        if not self.available():
            raise MissingExtraError(f"the {self.name} engine needs {self.install}")

    @abc.abstractmethod
    def solve(
        self,
        system: Any,
        xs: np.ndarray,
        signal: Any,
        times: np.ndarray,
        *,
        adaptive: bool,
        steps: int,
        rtol: float,
        atol: float,
        max_steps: int,
        min_step: float,
        bound: float,
        threads: int | None,
    ) -> EngineOutput:
        """Integrate the batch (module docstring: inputs, outputs, obligations)."""

    def __repr__(self) -> str:
        return f"<engine {self.name}: {self.summary}>"


def check_times(times: Any, total: np.ndarray) -> np.ndarray:
    """``times`` as a sorted ``(T,)`` float array within ``[0, min(total)]``; ``None``: none.

    ``total`` ``(B,)`` the trajectories' durations; with ``B = 0`` only ``>= 0`` is checked.
    A time past ``min(total)`` by at most a relative 1e-12 (rounding in the
    caller's sum of durations) is read as ``min(total)``, on every engine.
    """
    if times is None:
        return np.zeros(0)
    ts = np.ascontiguousarray(np.asarray(times, dtype=np.float64).ravel())
    if ts.size and (not np.all(np.isfinite(ts)) or np.any(np.diff(ts) < 0)):
        raise OptionError("sample times must be finite and sorted")
    if ts.size and ts[0] < 0:
        raise OptionError("sample times must be >= 0")
    if ts.size and total.size and ts[-1] > float(np.min(total)) * (1 + 1e-12):
        raise OptionError(
            f"sample times must lie in [0, {float(np.min(total))}] (the input's duration)"
        )
    if ts.size and total.size:  # within the 1e-12 slack past the end: the end itself
        ts = np.minimum(ts, float(np.min(total)))
    return ts


def state_status(x: np.ndarray, bound: float) -> np.ndarray:
    """``(B,)`` status codes of states ``(B, n)``: non-finite, beyond ``bound``, or 0."""
    finite = np.all(np.isfinite(x), axis=1)
    big = np.any(np.abs(np.where(np.isfinite(x), x, 0.0)) > bound, axis=1)
    return np.where(~finite, int(Status.NON_FINITE), np.where(big, int(Status.BLOW_UP), 0))
