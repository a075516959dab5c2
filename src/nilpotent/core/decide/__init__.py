"""The one zero and rank engine: exact and certified values of constants, certified spans."""

from nilpotent.core.decide.evaluation import ball as ball
from nilpotent.core.decide.evaluation import exact_value as exact_value
from nilpotent.core.decide.evaluation import to_double as to_double
from nilpotent.core.decide.spans import Decision as Decision
from nilpotent.core.decide.spans import MeasuredSpan as MeasuredSpan
from nilpotent.core.decide.spans import Span as Span
from nilpotent.core.decide.spans import is_zero as is_zero
from nilpotent.core.decide.spans import numeric_rank as numeric_rank
from nilpotent.core.decide.spans import rank as rank

__all__ = [
    "Decision", "MeasuredSpan", "Span", "ball", "exact_value", "is_zero", "numeric_rank",
    "rank", "to_double",
]
