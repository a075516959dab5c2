"""The import path ``nilpotent.sweep`` (kept stable): parameter sweeps of bracket motions.

The implementation lives in :mod:`nilpotent.simulation.sweep`,
:mod:`nilpotent.simulation.sweep_result` and :mod:`nilpotent.simulation.executors`;
this module re-exports the names users call.
"""

from nilpotent.simulation.executors import MIN_DASK_CHUNK as MIN_DASK_CHUNK
from nilpotent.simulation.sweep import DEFAULT_AMPLITUDES as DEFAULT_AMPLITUDES
from nilpotent.simulation.sweep import DESIGNS as DESIGNS
from nilpotent.simulation.sweep import amplitude_range as amplitude_range
from nilpotent.simulation.sweep import sweep as sweep
from nilpotent.simulation.sweep_result import SweepParameters as SweepParameters
from nilpotent.simulation.sweep_result import SweepResult as SweepResult

__all__ = [
    "DEFAULT_AMPLITUDES", "DESIGNS", "MIN_DASK_CHUNK", "SweepParameters", "SweepResult",
    "amplitude_range", "sweep",
]
