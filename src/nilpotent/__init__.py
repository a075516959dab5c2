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

The functions are named like the commands (README "Command line and Python"):
``analyze``, ``approximate``, ``simulate`` (a bracket motion of the system and of
its approximation, as ``nilpotent simulate``), ``scaling``, ``sweep``, ``plan``
(the global plan, as ``nilpotent plan``), ``steer`` (the local steering of the
true system, without a world), ``execute`` and ``reproduce``; the older names
(``compare_bracket_motion``, ``scaling_study``, ``plan_global``, ``execute_plan``)
remain.  Every ``to_json()`` is strict JSON (no NaN or infinity).

The ``if TYPE_CHECKING:`` block is the one list: type checkers and editors read
it as ordinary imports, and :func:`__getattr__` reads the same statements (once,
from this file's syntax tree) to know where each name lives.
"""

from __future__ import annotations

import importlib
from functools import cache
from typing import TYPE_CHECKING, Any

from nilpotent.errors import NilpotentError as NilpotentError
from nilpotent.version import __version__ as __version__

if TYPE_CHECKING:
    from nilpotent.core.analysis.filtration import Filtration as Filtration
    from nilpotent.core.analysis.filtration import analyze as analyze
    from nilpotent.core.analysis.filtration import singular_locus as singular_locus
    from nilpotent.core.coordinates.approximation import Certificate as Certificate
    from nilpotent.core.coordinates.approximation import (
        NilpotentApproximation as NilpotentApproximation,
    )
    from nilpotent.core.coordinates.approximation import approximate as approximate
    from nilpotent.core.coordinates.orders import function_order as function_order
    from nilpotent.core.coordinates.privileged import PrivilegedCoordinates as PrivilegedCoordinates
    from nilpotent.core.coordinates.privileged import (
        privileged_coordinates as privileged_coordinates,
    )
    from nilpotent.core.lie.brackets import bracket as bracket
    from nilpotent.core.lie.brackets import format_word as format_word
    from nilpotent.core.lie.brackets import hall_basis as hall_basis
    from nilpotent.core.lie.brackets import word_field as word_field
    from nilpotent.core.model.expressions import format_expression as format_expression
    from nilpotent.core.model.expressions import parse_expression as parse_expression
    from nilpotent.core.model.modelfile import load_model_file as load_model_file
    from nilpotent.core.model.modelfile import system_from_dict as system_from_dict
    from nilpotent.core.model.outline import Limits as Limits
    from nilpotent.core.model.outline import Outline as Outline
    from nilpotent.core.model.points import parse_point as parse_point
    from nilpotent.core.model.system import ControlSystem as ControlSystem
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
    from nilpotent.numeric.settings import IntegrationSettings as IntegrationSettings
    from nilpotent.numeric.signals import Signal as Signal
    from nilpotent.numeric.signals import bracket_signal as bracket_signal
    from nilpotent.planning import Plan as Plan
    from nilpotent.planning import steer_nilpotent as steer_nilpotent
    from nilpotent.planning.execute import execute_plan as execute
    from nilpotent.planning.execute import execute_plan as execute_plan
    from nilpotent.planning.global_planner import GlobalPlan as GlobalPlan
    from nilpotent.planning.global_planner import plan_global as plan
    from nilpotent.planning.global_planner import plan_global as plan_global
    from nilpotent.planning.iterative import plan as steer
    from nilpotent.planning.world import World as World
    from nilpotent.planning.world import load_world as load_world
    from nilpotent.report import Audit as Audit
    from nilpotent.report import Reproduction as Reproduction
    from nilpotent.report import reproduce as reproduce
    from nilpotent.report import run_audit as run_audit
    from nilpotent.simulation import Comparison as Comparison
    from nilpotent.simulation import ScalingStudy as ScalingStudy
    from nilpotent.simulation import SweepResult as SweepResult
    from nilpotent.simulation import Trajectory as Trajectory
    from nilpotent.simulation import amplitude_range as amplitude_range
    from nilpotent.simulation import compare_bracket_motion as compare_bracket_motion
    from nilpotent.simulation import compare_bracket_motion as simulate
    from nilpotent.simulation import scaling_study as scaling
    from nilpotent.simulation import scaling_study as scaling_study
    from nilpotent.simulation import sweep as sweep

__all__ = [
    "MODELS",
    "Audit",
    "Certificate",
    "Comparison",
    "ControlSystem",
    "Filtration",
    "GlobalPlan",
    "IntegrationSettings",
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
    "execute",
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
    "scaling",
    "scaling_study",
    "simulate",
    "singular_locus",
    "steer",
    "steer_nilpotent",
    "sweep",
    "system_from_dict",
    "wheel_slip",
    "word_field",
]


@cache
def _lazy_imports() -> dict[str, tuple[str, str]]:
    """Public name -> (defining module, name there), read from the ``if TYPE_CHECKING:``
    block above (``from m import f as g`` makes ``g`` the name ``f`` of ``m``)."""
    import ast  # here, not at the top: ``import nilpotent`` stays as light as can be
    from pathlib import Path

    tree = ast.parse(Path(__file__).read_text(encoding="utf-8"))
    found: dict[str, tuple[str, str]] = {}
    for node in tree.body:
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for stmt in node.body:
                if isinstance(stmt, ast.ImportFrom) and stmt.module:
                    for alias in stmt.names:
                        found[alias.asname or alias.name] = (stmt.module, alias.name)
    return found


def __getattr__(name: str) -> Any:
    # a submodule (``from nilpotent import progress``) asks here first: answered at once
    where = _lazy_imports().get(name) if name in __all__ else None
    if where is None:
        raise AttributeError(f"module 'nilpotent' has no attribute {name!r}")
    module, attribute = where
    value = getattr(importlib.import_module(module), attribute)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
