"""How to integrate: one value, :class:`IntegrationSettings`, with one default.

Every numeric entry point (:func:`nilpotent.numeric.integrate`,
:func:`nilpotent.simulate`, :func:`nilpotent.sweep`,
:func:`nilpotent.simulation.compare_bracket_motion`, :func:`nilpotent.scaling`,
the planners) takes ``settings=IntegrationSettings(...)``.  The value checks
itself when it is made (:meth:`IntegrationSettings.__post_init__`), so a bad
tolerance is the same :class:`~nilpotent.errors.OptionError` (kind ``option``)
whether it comes from Python or from the command line.

The one default is :data:`DEFAULT_SETTINGS` (``IntegrationSettings()``).  A
computation that needs something else says so with a named value derived from
it (documented where it is used): :data:`nilpotent.simulation.comparison.BRACKET_SETTINGS`
(tighter tolerances: a bracket motion is compared at the noise floor),
:data:`nilpotent.simulation.sweep.SWEEP_SETTINGS` (a lower blow-up bound) and
:data:`nilpotent.planning.simulation.PLANNING_SETTINGS` (tighter tolerances).

Examples
--------
>>> s = IntegrationSettings(rtol=1e-8)
>>> s.rtol, s.atol, s.engine
(1e-08, 1e-12, 'auto')
>>> IntegrationSettings(rtol=-1)
Traceback (most recent call last):
...
nilpotent.errors.OptionError: rtol must be a finite number > 0, got -1
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass
from typing import Any

from nilpotent.errors import OptionError
from nilpotent.strict_json import json_object

__all__ = ["DEFAULT_SETTINGS", "METHODS", "IntegrationSettings", "resolve_settings"]

METHODS: dict[str, str] = {
    "adaptive": "DOP853 with embedded error control (scipy's step-size rules)",
    "fixed": "DOP853 with equal steps per segment; error estimated by step halving",
}


def _number(value: Any, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise OptionError(f"{name} must be a number, got {value!r}")
    return float(value)


def _integer(value: Any, name: str, low: int) -> int:
    whole = isinstance(value, numbers.Integral) or (
        isinstance(value, float) and value.is_integer())
    if isinstance(value, bool) or not whole or value < low:
        raise OptionError(f"{name} must be an integer >= {low}, got {value!r}")
    return int(value)


@dataclass(frozen=True)
class IntegrationSettings:
    """How trajectories are integrated (one value; :data:`DEFAULT_SETTINGS` is the default).

    Parameters
    ----------
    method : str
        ``"adaptive"`` (DOP853 with error control) or ``"fixed"`` (equal steps),
        :data:`METHODS`.
    engine : str
        One of :data:`nilpotent.numeric.ENGINES` or ``"auto"``.
    rtol : float
        Relative tolerance of the adaptive method (finite, > 0).
    atol : float
        Absolute tolerance of the adaptive method (finite, >= 0).
    steps : int
        Steps per segment of the fixed method (>= 2; even when its error is
        estimated by step halving).
    max_steps : int
        Most steps (accepted + rejected) per trajectory (>= 1).
    bound : float
        A trajectory with some ``|x_k| > bound`` is stopped as a blow-up (finite, > 0).

    Raises
    ------
    OptionError
        An unknown method or engine, or a value out of its range (the message
        names the field).
    """

    method: str = "adaptive"
    engine: str = "auto"
    rtol: float = 1e-10
    atol: float = 1e-12
    steps: int = 64
    max_steps: int = 100_000
    bound: float = 1e8

    def __post_init__(self) -> None:
        from nilpotent.numeric.engines import engine_names

        if self.method not in METHODS:
            raise OptionError(f"unknown method {self.method!r} (choose from {', '.join(METHODS)})")
        if self.engine not in engine_names():
            raise OptionError(
                f"unknown engine {self.engine!r} (choose from {', '.join(engine_names())})"
            )
        rtol = _number(self.rtol, "rtol")
        if not (math.isfinite(rtol) and rtol > 0):
            raise OptionError(f"rtol must be a finite number > 0, got {self.rtol!r}")
        atol = _number(self.atol, "atol")
        if not (math.isfinite(atol) and atol >= 0):
            raise OptionError(f"atol must be a finite number >= 0, got {self.atol!r}")
        bound = _number(self.bound, "bound")
        if not (math.isfinite(bound) and bound > 0):
            raise OptionError(f"bound must be a finite number > 0, got {self.bound!r}")
        object.__setattr__(self, "rtol", rtol)
        object.__setattr__(self, "atol", atol)
        object.__setattr__(self, "bound", bound)
        object.__setattr__(self, "steps", _integer(self.steps, "steps", 2))
        object.__setattr__(self, "max_steps", _integer(self.max_steps, "max_steps", 1))

    def replace(self, **changes: Any) -> IntegrationSettings:
        """A copy with some fields changed (``None`` values are ignored), checked again."""
        given = {k: v for k, v in changes.items() if v is not None}
        return dataclasses.replace(self, **given) if given else self

    def to_json(self) -> dict[str, Any]:
        """The fields as a JSON object."""
        return json_object(dataclasses.asdict(self))


#: The one default: adaptive DOP853, ``rtol = 1e-10``, ``atol = 1e-12``, bound ``1e8``.
DEFAULT_SETTINGS = IntegrationSettings()


def resolve_settings(
    settings: IntegrationSettings | None, default: IntegrationSettings, **loose: Any
) -> IntegrationSettings:
    """The settings an entry point uses: ``settings`` (or its ``default``) with loose overrides.

    Parameters
    ----------
    settings : IntegrationSettings or None
        What the caller gave (``None``: the entry point's ``default``).
    default : IntegrationSettings
        :data:`DEFAULT_SETTINGS` or a documented override of it.
    **loose : Any
        The loose keywords of the entry point (``rtol=``, ``engine=``, ...;
        ``None`` when not given): they override the fields of the same name.
        Kept for one release; pass ``settings=`` instead.

    Raises
    ------
    OptionError
        ``settings`` that is not an :class:`IntegrationSettings`, or a bad value.
    """
    base = default if settings is None else settings
    if not isinstance(base, IntegrationSettings):
        raise OptionError(f"settings must be an IntegrationSettings, got {type(base).__name__}")
    return base.replace(**loose)
