"""The ``numba`` engine: DOP853 kernels compiled into each system's cached module.

The kernels (:mod:`nilpotent.numeric.kernels`) are generated for the system's
fields, compiled by numba on first use (about 10 s) and kept in numba's on-disk
cache next to the generated module (:mod:`nilpotent.numeric.cache`); the batch
runs in parallel (``prange``).  Adaptive (scipy's step-size rules) and fixed-step.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any, ClassVar

import numpy as np

from nilpotent.numeric.compile import CompiledSystem, numba_available
from nilpotent.numeric.engines.base import Engine, EngineOutput, compiled_memo

__all__ = ["NumbaEngine", "kernels_cached"]


@contextlib.contextmanager
def _numba_threads(threads: int | None) -> Iterator[None]:
    """Run with ``threads`` numba threads, restoring the previous setting afterwards."""
    if threads is None:
        yield
        return
    import numba
    from numba.core import config as numba_config

    # NUMBA_NUM_THREADS is set on numba.core.config at import (invisible to type checkers)
    limit = int(numba_config.NUMBA_NUM_THREADS)  # pyright: ignore[reportAttributeAccessIssue]
    previous = numba.get_num_threads()
    numba.set_num_threads(max(1, min(int(threads), limit)))
    try:
        yield
    finally:
        numba.set_num_threads(previous)


def kernels_cached(system: CompiledSystem) -> bool:
    """Whether the numba integrator of ``system`` is in numba's on-disk cache."""
    from nilpotent.numeric.cache import cache_dir
    from nilpotent.numeric.kernels import KERNEL_VERSION

    folder = cache_dir() / "__pycache__"
    stem = f"nb_{system.key}_{KERNEL_VERSION}"
    return any(folder.glob(f"{stem}.integrate_batch-*.nbi"))


class NumbaEngine(Engine):
    """Compiled DOP853 (adaptive or fixed), parallel over the batch; ``threads`` numba threads."""

    name: ClassVar[str] = "numba"
    methods: ClassVar[tuple[str, ...]] = ("adaptive", "fixed")
    summary: ClassVar[str] = "compiled DOP853 kernels, parallel over the batch"
    install: ClassVar[str] = "numba: pip install numba"

    def available(self) -> bool:
        return numba_available()

    def cached(self, system: CompiledSystem) -> bool:
        """Whether ``system``'s kernels are compiled already (no compilation to wait for)."""
        return kernels_cached(system)

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
        mod = system.kernels
        batch = xs.shape[0]
        final = np.empty_like(xs)
        samples = np.full((batch, times.size, system.n), np.nan)
        info = np.zeros((batch, 4))
        from nilpotent.progress import COMPILING, progress

        first = "numba-called" not in compiled_memo(system) and not kernels_cached(system)
        stage = progress(COMPILING) if first else contextlib.nullcontext()
        with stage, _numba_threads(threads):
            mod.integrate_batch(
                xs, signal.durations, signal.omegas, signal.constant, signal.cos, signal.sin,
                times, adaptive, steps, rtol, atol, max_steps, min_step, bound, final, samples,
                info,
            )
        compiled_memo(system)["numba-called"] = True
        return final, samples, info
