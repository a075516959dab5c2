"""The import path ``nilpotent.simulate`` (kept stable): simulation of single motions.

The implementation lives in :mod:`nilpotent.simulation` (trajectories,
comparisons, scaling studies) and :mod:`nilpotent.numeric.signals` (controls);
this module re-exports the names users call.
"""

from nilpotent.numeric.signals import FunctionSignal as FunctionSignal
from nilpotent.numeric.signals import Signal as Signal
from nilpotent.numeric.signals import bracket_signal as bracket_signal
from nilpotent.numeric.signals import piecewise_constant as piecewise_constant
from nilpotent.numeric.signals import sinusoids as sinusoids
from nilpotent.simulation.comparison import Comparison as Comparison
from nilpotent.simulation.comparison import bracket_value as bracket_value
from nilpotent.simulation.comparison import compare_bracket_motion as compare_bracket_motion
from nilpotent.simulation.scaling import DEFAULT_AMPLITUDES as DEFAULT_AMPLITUDES
from nilpotent.simulation.scaling import ScalingStudy as ScalingStudy
from nilpotent.simulation.scaling import scaling_study as scaling_study
from nilpotent.simulation.trajectory import Trajectory as Trajectory
from nilpotent.simulation.trajectory import simulate as simulate

signal_from_segments = Signal.from_segments

__all__ = [
    "DEFAULT_AMPLITUDES", "Comparison", "FunctionSignal", "ScalingStudy", "Signal", "Trajectory",
    "bracket_signal", "bracket_value", "compare_bracket_motion", "piecewise_constant",
    "scaling_study", "signal_from_segments", "simulate", "sinusoids",
]
