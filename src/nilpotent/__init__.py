"""nilpotent: privileged coordinates, nilpotent approximation, simulation and steering
of driftless control systems.

The public API is the list of names below (``__all__``); the modules they come
from are the implementation and may move.  The names are resolved lazily
(PEP 562), so ``import nilpotent`` stays light (the standard library only: the
command line's entry point installs its signal handlers before anything heavy
loads) and ``nilpotent.core`` never pulls in the numeric stack (scipy, numba,
matplotlib)::

    import nilpotent as nil
    snake = nil.get_model("trident-snake")
    nil.analyze(snake).growth_vector            # (3, 6)
    approx = nil.approximate(snake)             # privileged coordinates + X̂_i
    cmp = nil.compare_bracket_motion(snake, (1, 2), 0.1)

The ``if TYPE_CHECKING:`` block is the one list: type checkers and editors read
it as ordinary imports, and :func:`__getattr__` reads the same statements (once,
from this file's syntax tree) to know where each name lives.  The modules
``nilpotent.simulate`` and ``nilpotent.sweep`` keep their own names (call
``nilpotent.simulate.simulate`` and ``nilpotent.sweep.sweep``).
"""

from __future__ import annotations

import importlib
from functools import cache
from typing import TYPE_CHECKING, Any

from nilpotent.errors import NilpotentError as NilpotentError
from nilpotent.version import __version__ as __version__

if TYPE_CHECKING:
    from nilpotent.core.approximation import Certificate as Certificate
    from nilpotent.core.approximation import NilpotentApproximation as NilpotentApproximation
    from nilpotent.core.approximation import approximate as approximate
    from nilpotent.core.brackets import bracket as bracket
    from nilpotent.core.brackets import format_word as format_word
    from nilpotent.core.brackets import hall_basis as hall_basis
    from nilpotent.core.brackets import word_field as word_field
    from nilpotent.core.expressions import format_expression as format_expression
    from nilpotent.core.expressions import parse_expression as parse_expression
    from nilpotent.core.filtration import Filtration as Filtration
    from nilpotent.core.filtration import analyze as analyze
    from nilpotent.core.filtration import singular_locus as singular_locus
    from nilpotent.core.modelfile import load_model_file as load_model_file
    from nilpotent.core.modelfile import system_from_dict as system_from_dict
    from nilpotent.core.orders import function_order as function_order
    from nilpotent.core.outline import Limits as Limits
    from nilpotent.core.outline import Outline as Outline
    from nilpotent.core.points import parse_point as parse_point
    from nilpotent.core.privileged import PrivilegedCoordinates as PrivilegedCoordinates
    from nilpotent.core.privileged import privileged_coordinates as privileged_coordinates
    from nilpotent.core.system import ControlSystem as ControlSystem
    from nilpotent.models import MODELS as MODELS
    from nilpotent.models import ModelInfo as ModelInfo
    from nilpotent.models import TridentGeometry as TridentGeometry
    from nilpotent.models import get_model as get_model
    from nilpotent.models import list_models as list_models
    from nilpotent.models import load_system as load_system
    from nilpotent.models import wheel_slip as wheel_slip
    from nilpotent.numeric import compile_fields as compile_fields
    from nilpotent.numeric import compile_system as compile_system
    from nilpotent.numeric import integrate as integrate
    from nilpotent.planning import Plan as Plan
    from nilpotent.planning import plan as plan
    from nilpotent.planning import steer_nilpotent as steer_nilpotent
    from nilpotent.planning.execute import execute_plan as execute_plan
    from nilpotent.planning.global_planner import GlobalPlan as GlobalPlan
    from nilpotent.planning.global_planner import plan_global as plan_global
    from nilpotent.planning.world import World as World
    from nilpotent.planning.world import load_world as load_world
    from nilpotent.report import Audit as Audit
    from nilpotent.report import Reproduction as Reproduction
    from nilpotent.report import reproduce as reproduce
    from nilpotent.report import run_audit as run_audit
    from nilpotent.simulate import Comparison as Comparison
    from nilpotent.simulate import ScalingStudy as ScalingStudy
    from nilpotent.simulate import Signal as Signal
    from nilpotent.simulate import Trajectory as Trajectory
    from nilpotent.simulate import bracket_signal as bracket_signal
    from nilpotent.simulate import compare_bracket_motion as compare_bracket_motion
    from nilpotent.simulate import scaling_study as scaling_study
    from nilpotent.sweep import SweepResult as SweepResult
    from nilpotent.sweep import amplitude_range as amplitude_range

__all__ = [
    "MODELS",
    "Audit",
    "Certificate",
    "Comparison",
    "ControlSystem",
    "Filtration",
    "GlobalPlan",
    "Limits",
    "ModelInfo",
    "NilpotentApproximation",
    "NilpotentError",
    "Outline",
    "Plan",
    "PrivilegedCoordinates",
    "Reproduction",
    "ScalingStudy",
    "Signal",
    "SweepResult",
    "Trajectory",
    "TridentGeometry",
    "World",
    "__version__",
    "amplitude_range",
    "analyze",
    "approximate",
    "bracket",
    "bracket_signal",
    "compare_bracket_motion",
    "compile_fields",
    "compile_system",
    "execute_plan",
    "format_expression",
    "format_word",
    "function_order",
    "get_model",
    "hall_basis",
    "integrate",
    "list_models",
    "load_model_file",
    "load_system",
    "load_world",
    "parse_expression",
    "parse_point",
    "plan",
    "plan_global",
    "privileged_coordinates",
    "reproduce",
    "run_audit",
    "scaling_study",
    "singular_locus",
    "steer_nilpotent",
    "system_from_dict",
    "wheel_slip",
    "word_field",
]


@cache
def _lazy_imports() -> dict[str, str]:
    """Public name -> defining module, read from the ``if TYPE_CHECKING:`` block above."""
    import ast  # here, not at the top: ``import nilpotent`` stays as light as can be
    from pathlib import Path

    tree = ast.parse(Path(__file__).read_text(encoding="utf-8"))
    found: dict[str, str] = {}
    for node in tree.body:
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for stmt in node.body:
                if isinstance(stmt, ast.ImportFrom) and stmt.module:
                    for alias in stmt.names:
                        found[alias.asname or alias.name] = stmt.module
    return found


def __getattr__(name: str) -> Any:
    # a submodule (``from nilpotent import progress``) asks here first: answered at once
    module = _lazy_imports().get(name) if name in __all__ else None
    if module is None:
        raise AttributeError(f"module 'nilpotent' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
