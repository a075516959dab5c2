"""nilpotent: privileged coordinates, nilpotent approximation, simulation and steering
of driftless control systems.

The public API is re-exported here (the modules ``nilpotent.simulate`` and
``nilpotent.sweep`` keep their own names: call ``nilpotent.simulate.simulate``
and ``nilpotent.sweep.sweep``).  The names are resolved lazily (PEP 562),
so ``import nilpotent`` stays light and ``nilpotent.core`` never pulls in the
numeric stack (scipy, numba, matplotlib)::

    import nilpotent as nil
    snake = nil.get_model("trident-snake")
    nil.analyze(snake).growth_vector            # (3, 6)
    approx = nil.approximate(snake)             # privileged coordinates + X̂_i
    cmp = nil.compare_bracket_motion(snake, (1, 2), 0.1)
"""

from __future__ import annotations

import importlib
from typing import Any

from nilpotent.core.system import ControlSystem as ControlSystem
from nilpotent.errors import NilpotentError as NilpotentError

__version__ = "0.1.0"

_LAZY: dict[str, str] = {
    # symbolic core
    "parse_expression": "nilpotent.core.expressions",
    "format_expression": "nilpotent.core.expressions",
    "load_model_file": "nilpotent.core.modelfile",
    "system_from_dict": "nilpotent.core.modelfile",
    "parse_point": "nilpotent.core.points",
    "bracket": "nilpotent.core.brackets",
    "word_field": "nilpotent.core.brackets",
    "hall_basis": "nilpotent.core.brackets",
    "format_word": "nilpotent.core.brackets",
    "Filtration": "nilpotent.core.filtration",
    "analyze": "nilpotent.core.filtration",
    "singular_locus": "nilpotent.core.filtration",
    "function_order": "nilpotent.core.orders",
    "PrivilegedCoordinates": "nilpotent.core.privileged",
    "privileged_coordinates": "nilpotent.core.privileged",
    "NilpotentApproximation": "nilpotent.core.approximation",
    "Certificate": "nilpotent.core.approximation",
    "approximate": "nilpotent.core.approximation",
    # models
    "get_model": "nilpotent.models",
    "load_system": "nilpotent.models",
    "list_models": "nilpotent.models",
    "TridentGeometry": "nilpotent.models",
    "wheel_slip": "nilpotent.models",
    # numbers and simulation
    "compile_fields": "nilpotent.numeric",
    "compile_system": "nilpotent.numeric",
    "integrate": "nilpotent.numeric",
    "Signal": "nilpotent.simulate",
    "bracket_signal": "nilpotent.simulate",
    "compare_bracket_motion": "nilpotent.simulate",
    "scaling_study": "nilpotent.simulate",
    "SweepResult": "nilpotent.sweep",
    "amplitude_range": "nilpotent.sweep",
    # steering, pictures, the paper
    "plan": "nilpotent.planning",
    "plan_global": "nilpotent.planning.global_planner",
    "GlobalPlan": "nilpotent.planning.global_planner",
    "World": "nilpotent.planning.world",
    "load_world": "nilpotent.planning.world",
    "execute_plan": "nilpotent.planning.execute",
    "Limits": "nilpotent.core.outline",
    "Outline": "nilpotent.core.outline",
    "Plan": "nilpotent.planning",
    "steer_nilpotent": "nilpotent.planning",
    "reproduce": "nilpotent.report",
    "run_audit": "nilpotent.report",
}

__all__ = ["ControlSystem", "NilpotentError", "__version__", *sorted(_LAZY)]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'nilpotent' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
