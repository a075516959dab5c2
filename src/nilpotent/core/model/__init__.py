"""What a user writes: expressions, a driftless system, points, limits, outlines, model files."""

from nilpotent.core.model.expressions import format_expression as format_expression
from nilpotent.core.model.expressions import parse_expression as parse_expression
from nilpotent.core.model.modelfile import dump_model_file as dump_model_file
from nilpotent.core.model.modelfile import load_model_file as load_model_file
from nilpotent.core.model.modelfile import system_from_dict as system_from_dict
from nilpotent.core.model.modelfile import system_to_dict as system_to_dict
from nilpotent.core.model.outline import Limits as Limits
from nilpotent.core.model.outline import Outline as Outline
from nilpotent.core.model.points import format_point as format_point
from nilpotent.core.model.points import parse_point as parse_point
from nilpotent.core.model.system import ControlSystem as ControlSystem

__all__ = [
    "ControlSystem", "Limits", "Outline", "dump_model_file", "format_expression",
    "format_point", "load_model_file", "parse_expression", "parse_point", "system_from_dict",
    "system_to_dict",
]
