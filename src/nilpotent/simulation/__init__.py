"""Simulation: trajectories, the original system against its nilpotent approximation,
scaling studies and parameter sweeps.

* :func:`simulate` → :class:`Trajectory` (:mod:`~nilpotent.simulation.trajectory`);
* :class:`CompiledPair` — the one engine running a system and its approximation
  side by side (:mod:`~nilpotent.simulation.pair`);
* :func:`compare_bracket_motion` → :class:`Comparison`
  (:mod:`~nilpotent.simulation.comparison`, schema ``nilpotent/simulation@1``);
* :func:`scaling_study` → :class:`ScalingStudy`
  (:mod:`~nilpotent.simulation.scaling`, ``nilpotent/scaling@1``);
* :func:`sweep` → :class:`SweepResult` (:mod:`~nilpotent.simulation.sweep`,
  :mod:`~nilpotent.simulation.sweep_result`, ``nilpotent/sweep@1``), run here
  or on Dask (:mod:`~nilpotent.simulation.executors`).

Controls come from :mod:`nilpotent.numeric.signals`; figures from :mod:`nilpotent.viz`.
"""

from nilpotent.simulation.comparison import Comparison as Comparison
from nilpotent.simulation.comparison import bracket_value as bracket_value
from nilpotent.simulation.comparison import compare_bracket_motion as compare_bracket_motion
from nilpotent.simulation.pair import CompiledPair as CompiledPair
from nilpotent.simulation.pair import PairRun as PairRun
from nilpotent.simulation.scaling import DEFAULT_AMPLITUDES as DEFAULT_AMPLITUDES
from nilpotent.simulation.scaling import ScalingStudy as ScalingStudy
from nilpotent.simulation.scaling import scaling_study as scaling_study
from nilpotent.simulation.sweep import DESIGNS as DESIGNS
from nilpotent.simulation.sweep import amplitude_range as amplitude_range
from nilpotent.simulation.sweep import sweep as sweep
from nilpotent.simulation.sweep_result import SweepParameters as SweepParameters
from nilpotent.simulation.sweep_result import SweepResult as SweepResult
from nilpotent.simulation.trajectory import Trajectory as Trajectory
from nilpotent.simulation.trajectory import simulate as simulate

__all__ = [
    "DEFAULT_AMPLITUDES",
    "DESIGNS",
    "Comparison",
    "CompiledPair",
    "PairRun",
    "ScalingStudy",
    "SweepParameters",
    "SweepResult",
    "Trajectory",
    "amplitude_range",
    "bracket_value",
    "compare_bracket_motion",
    "scaling_study",
    "simulate",
    "sweep",
]
