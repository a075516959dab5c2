"""Numbers from symbols: the numeric compiler and the batched integrators.

* :func:`compile_fields` / :func:`compile_system` → :class:`CompiledSystem`
  (vectorised fields, right-hand side, Jacobians; numpy, numba or JAX);
  :func:`compile_map` → :class:`CompiledMap` (coordinate changes y(x), x(y));
* :class:`Signal` (the one control type: batches of piecewise sums of
  sinusoids, the plan-segment format), :func:`bracket_inputs`;
* :func:`integrate` → :class:`BatchSolution` (adaptive or fixed-step DOP853,
  numba-parallel over the batch, heyoka's Taylor method, ``solve_ivp`` as the
  reference) on the engines of :mod:`nilpotent.numeric.engines` (registry
  :data:`ENGINES` of :class:`Engine` classes, the engine contract written there);
* :mod:`~nilpotent.numeric.fits` (log–log slopes), :mod:`~nilpotent.numeric.types`
  (shape aliases).
"""

from nilpotent.numeric.compile import BACKENDS as BACKENDS
from nilpotent.numeric.compile import CompiledMap as CompiledMap
from nilpotent.numeric.compile import CompiledSystem as CompiledSystem
from nilpotent.numeric.compile import compile_fields as compile_fields
from nilpotent.numeric.compile import compile_map as compile_map
from nilpotent.numeric.compile import compile_system as compile_system
from nilpotent.numeric.engines import ENGINES as ENGINES
from nilpotent.numeric.engines.base import Engine as Engine
from nilpotent.numeric.integrate import METHODS as METHODS
from nilpotent.numeric.integrate import BatchSolution as BatchSolution
from nilpotent.numeric.integrate import Status as Status
from nilpotent.numeric.integrate import integrate as integrate
from nilpotent.numeric.integrate import solve_function_input as solve_function_input
from nilpotent.numeric.settings import DEFAULT_SETTINGS as DEFAULT_SETTINGS
from nilpotent.numeric.settings import IntegrationSettings as IntegrationSettings
from nilpotent.numeric.signals import FunctionSignal as FunctionSignal
from nilpotent.numeric.signals import InputSignal as InputSignal
from nilpotent.numeric.signals import Segment as Segment
from nilpotent.numeric.signals import Signal as Signal
from nilpotent.numeric.signals import bracket_inputs as bracket_inputs
from nilpotent.numeric.tableaux import DOP853 as DOP853
from nilpotent.numeric.tableaux import TABLEAUX as TABLEAUX
from nilpotent.numeric.tableaux import ButcherTableau as ButcherTableau

__all__ = [
    "BACKENDS",
    "DEFAULT_SETTINGS",
    "DOP853",
    "ENGINES",
    "METHODS",
    "TABLEAUX",
    "BatchSolution",
    "ButcherTableau",
    "CompiledMap",
    "CompiledSystem",
    "Engine",
    "FunctionSignal",
    "InputSignal",
    "IntegrationSettings",
    "Segment",
    "Signal",
    "Status",
    "bracket_inputs",
    "compile_fields",
    "compile_map",
    "compile_system",
    "integrate",
    "solve_function_input",
]
