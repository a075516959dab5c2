"""Built-in models: a registry of driftless systems chosen by name.

Families are data (one module per family: :mod:`~nilpotent.models.trident`,
:mod:`~nilpotent.models.classic`, :mod:`~nilpotent.models.trailers`,
:mod:`~nilpotent.models.vehicles`, :mod:`~nilpotent.models.groups`) plus this
registry, which the CLI (``nilpotent models``), the docs and the tests all
iterate over.

* :data:`MODELS` maps a name to its :class:`ModelInfo`;
* :func:`get_model` builds a built-in (``"unicycle"``, ``"car-trailers:3"``)
  and applies parameter values;
* :func:`load_system` accepts a built-in name or the path of a ``.toml`` /
  ``.json`` model file (the Model files page).

Examples
--------
>>> get_model("car-trailers:2").coordinate_names
('x', 'y', 'theta0', 'theta1', 'theta2')
>>> get_model("trident-snake", {"l": 2}).parameter_values["l"]
2
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from types import MappingProxyType
from typing import Any

import sympy as sp

from nilpotent.core.model.expressions import format_expression
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ModelError, NilpotentError
from nilpotent.models.classic import cartan, engel, heisenberg, martinet, unicycle
from nilpotent.models.groups import rigid_body, roto_translation
from nilpotent.models.outlines import with_builtin_constraints
from nilpotent.models.trailers import car_trailers
from nilpotent.models.trident import (
    TridentGeometry,
    WheelSlip,
    joint_singularity,
    paper_singularity,
    trident_snake,
    trident_snake_joints,
    trident_snake_paper,
    wheel_slip,
)
from nilpotent.models.vehicles import (
    car,
    kinematic_snake,
    snake_singularity,
    snakeboard,
    space_robot,
)
from nilpotent.strict_json import json_object

__all__ = [
    "MAX_TRAILERS",
    "MODELS",
    "MODELS_SCHEMA",
    "ModelInfo",
    "TridentGeometry",
    "WheelSlip",
    "get_model",
    "is_builtin",
    "joint_singularity",
    "list_models",
    "load_system",
    "models_to_json",
    "paper_singularity",
    "snake_singularity",
    "wheel_slip",
]

#: Largest ``K`` accepted in ``car-trailers:K``: the brackets up to length K + 2 are
#: needed at every point, and each trailer multiplies their cost by 5-8 (``analyze`` at the
#: origin: K = 9 in 5.4 s of CPU and 0.26 GB, K = 10 in 46 s and 0.76 GB, K = 11 past the
#: minutes a command may take; measured 2026-12-01, docs/models.md).
MAX_TRAILERS = 9

_MODEL_FILE_SUFFIXES = (".toml", ".json")


@dataclass(frozen=True)
class ModelInfo:
    """One entry of the model registry.

    The entry is data: nothing is built when the registry is created.  The
    one-line :attr:`description` and the default :attr:`parameters` are read
    from the model itself, built once on first access (so ``import
    nilpotent.models`` builds no system).

    Parameters
    ----------
    name : str
        Registry name (``"trident-snake"``, ``"car-trailers"``).
    build : Callable[..., ControlSystem]
        ``build()`` (or ``build(K)`` when :attr:`argument` is set) returns the
        :class:`~nilpotent.core.model.system.ControlSystem` with its default
        parameter values.
    argument : str or None
        Name of the integer argument written after a colon (``"K"`` for
        ``car-trailers:K``), or ``None``.
    default_argument : int or None
        The argument used by :attr:`example_spec` and for the description.
    parameter_note : str
        Human-readable parameter rule for families (``"d1..dK = 1"``).
    positive_parameters : bool
        Every parameter must be a positive number (lengths); :func:`get_model`
        refuses other values with :class:`ModelError`.
    summary : str
        A family's one-line description (``""``: the built model's own).
    example_at : str
        A point in the ``--at`` syntax (``"alpha1=pi/2,alpha2=pi/2"``) where
        the model is defined and regular, for a model whose fields are
        undefined at the origin (``kinematic-snake``); ``""``: the origin.
        The ``every_model`` tests and :meth:`example_point` use it.
    """

    name: str
    build: Callable[..., ControlSystem] = field(repr=False)
    argument: str | None = None
    default_argument: int | None = None
    parameter_note: str = ""
    positive_parameters: bool = False
    summary: str = ""
    example_at: str = ""

    @cached_property
    def example(self) -> ControlSystem:
        """The model built with its defaults (:attr:`example_spec`); built once, on first use."""
        return self.build(self.default_argument) if self.argument else self.build()

    @property
    def description(self) -> str:
        """One line for ``nilpotent models``: :attr:`summary`, else the model's own."""
        return self.summary or self.example.description

    @property
    def parameters(self) -> Mapping[str, sp.Expr]:
        """Parameter name → default value (exact sympy numbers) of :attr:`example`.

        For a family with an argument these are the defaults of the model
        built with :attr:`default_argument`; :attr:`parameter_note` states the
        general rule.
        """
        return MappingProxyType(dict(self.example.parameters))

    @property
    def usage(self) -> str:
        """How to name the model on the command line (``"car-trailers:K"``)."""
        return f"{self.name}:{self.argument}" if self.argument else self.name

    @property
    def example_spec(self) -> str:
        """A spec that :func:`get_model` accepts (``"car-trailers:1"``)."""
        return f"{self.name}:{self.default_argument}" if self.argument else self.name

    def example_point(self, system: ControlSystem | None = None) -> tuple[sp.Expr, ...]:
        """:attr:`example_at` as a point of ``system`` (default :attr:`example`), exact.

        Parameters
        ----------
        system : ControlSystem or None
            The built model (with any parameters applied); ``None``: :attr:`example`.
        """
        from nilpotent.core.model.points import parse_point

        sys = system if system is not None else self.example
        return parse_point(self.example_at, sys) if self.example_at else sys.origin()

    def parameter_summary(self) -> str:
        """``"r=1, l=1"``, the family rule, or ``""`` when there are none."""
        if self.parameter_note:
            return self.parameter_note
        return ", ".join(f"{k}={v}" for k, v in self.parameters.items())

    def to_json(self) -> dict[str, object]:
        """This entry as one element of the ``nilpotent/models@1`` list (the interface page)."""
        return json_object({
            "name": self.usage,
            "example": self.example_spec,
            "description": self.description,
            "parameters": {k: format_expression(v) for k, v in self.parameters.items()},
            "parameter_rule": self.parameter_summary(),
        })


#: The built-in models, by registry name (``nilpotent models`` lists them in this order).
MODELS: Mapping[str, ModelInfo] = MappingProxyType(
    {
        info.name: info
        for info in (
            ModelInfo("trident-snake", trident_snake, positive_parameters=True),
            ModelInfo("trident-snake-paper", trident_snake_paper),
            ModelInfo("trident-snake-joints", trident_snake_joints, positive_parameters=True),
            ModelInfo("unicycle", unicycle),
            ModelInfo(
                "car-trailers",
                car_trailers,
                argument="K",
                default_argument=1,
                parameter_note="d1..dK=1 (hitch lengths, one per trailer)",
                summary="unicycle car pulling K trailers hitched at the axle centres; "
                "growth (2,3,...,K+3) at the origin",
                positive_parameters=True,
            ),
            ModelInfo("heisenberg", heisenberg),
            ModelInfo("engel", engel),
            ModelInfo("cartan", cartan),
            ModelInfo("martinet", martinet),
            ModelInfo("car", car, positive_parameters=True),
            ModelInfo("snakeboard", snakeboard, positive_parameters=True),
            ModelInfo(
                "kinematic-snake",
                kinematic_snake,
                positive_parameters=True,
                example_at="alpha1=pi/2,alpha2=pi/2",
            ),
            ModelInfo("space-robot", space_robot, positive_parameters=True),
            ModelInfo("rigid-body", rigid_body),
            ModelInfo("roto-translation", roto_translation),
        )
    }
)

#: The schema name of :func:`models_to_json`.
MODELS_SCHEMA = "nilpotent/models@1"


def models_to_json() -> dict[str, object]:
    """The ``nilpotent/models@1`` object: every registry entry's :meth:`ModelInfo.to_json`."""
    return {"schema": MODELS_SCHEMA, "models": [info.to_json() for info in MODELS.values()]}


def list_models() -> tuple[ModelInfo, ...]:
    """The registry entries, in display order.

    Each carries ``name``, ``usage`` (``car-trailers:K``), ``parameters``
    (defaults), ``parameter_summary()`` and the one-line ``description``.
    """
    return tuple(MODELS.values())


def _known() -> str:
    return ", ".join(info.usage for info in MODELS.values())


def _parse_argument(spec: str, info: ModelInfo, text: str) -> int:
    if not re.fullmatch(r"[0-9]+", text.strip()):
        raise ModelError(
            f"model {spec!r}: {info.argument} must be a positive integer "
            f"(e.g. {info.example_spec}), got {text!r}"
        )
    digits = text.strip().lstrip("0")
    value = int(digits or "0") if len(digits) <= 6 else MAX_TRAILERS + 1  # no 4300-digit limit
    if value < 1 or value > MAX_TRAILERS:
        shown = text.strip() if len(text.strip()) <= 20 else f"{text.strip()[:20]}..."
        raise ModelError(
            f"model {spec[:60]!r}: {info.argument} must be between 1 and {MAX_TRAILERS}, got "
            f"{shown} (each trailer multiplies the symbolic work by 5-8: "
            f"K = {MAX_TRAILERS} takes seconds, K = {MAX_TRAILERS + 1} about a minute)"
        )
    return value


def get_model(spec: str, params: Mapping[str, object] | None = None) -> ControlSystem:
    """Build a built-in model by name and apply parameter values.

    Parameters
    ----------
    spec:
        A registry name (``"unicycle"``) or ``"NAME:K"`` for a family with an
        integer argument (``"car-trailers:3"``, ``1 ≤ K ≤ MAX_TRAILERS``).
    params:
        Parameter values (sympy numbers) replacing the defaults.

    Raises
    ------
    ModelError
        Unknown name (the message lists the known ones), a bad or missing
        argument, an unknown parameter name, or a length parameter that is
        not a positive number (``trident-snake``: ``r``, ``l``;
        ``car-trailers``: ``d1..dK``; ``car``: ``L``, ``rmin``;
        ``snakeboard``: ``l``; ``kinematic-snake``: ``R``; ``space-robot``: all).
    """
    name, sep, arg = spec.partition(":")
    info = MODELS.get(name.strip())
    if info is None:
        raise ModelError(f"unknown model {spec!r}; known models: {_known()}")
    if info.argument is None:
        if sep:
            raise ModelError(f"model {spec!r}: {info.name} takes no ':' argument")
        system = info.build()
    else:
        if not sep:
            raise ModelError(
                f"model {spec!r} needs its argument: {info.usage} (e.g. {info.example_spec})"
            )
        system = info.build(_parse_argument(spec, info, arg))
    if params:
        system = system.with_parameters(dict(params))
    if info.positive_parameters:
        for key, value in system.parameters:
            if not (value.is_number and value.is_extended_real and value.is_positive):
                raise ModelError(
                    f"model {spec!r}: parameter {key} must be a positive number, got {value}"
                )
    return with_builtin_constraints(system)  # outline and default limits (planning)


def _shown(text: str, limit: int = 200) -> str:
    clean = "".join(ch if ch.isprintable() else ascii(ch)[1:-1] for ch in text)
    if len(clean) <= limit:
        return clean
    return clean[:limit] + f"... ({len(clean) - limit} more characters)"


def _file_problem(path: Path) -> str | None:
    """Why ``path`` cannot be opened as a file, in words (None: it can be looked at)."""
    import errno
    import os

    try:
        os.stat(path)
    except FileNotFoundError:
        if os.path.islink(path):
            return f"is a broken symbolic link (its target {_shown(os.readlink(path))!r} " \
                   "does not exist)"
        return "not found"
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "is a symbolic link loop (it never reaches a file)"
        if exc.errno == errno.ENAMETOOLONG:
            return "has a name too long for the file system"
        return f"cannot be read ({exc.strerror or type(exc).__name__})"
    return None


def load_system(spec: str, params: Mapping[str, object] | None = None) -> ControlSystem:
    """A built-in model by name, else a ``.toml`` / ``.json`` model file; then parameters.

    Parameters
    ----------
    spec:
        A built-in spec (see :func:`get_model`) or a path to a model file in
        the format of the Model files page, read by
        :func:`nilpotent.core.model.modelfile.load_model_file`.
    params:
        Parameter values applied with
        :meth:`~nilpotent.core.model.system.ControlSystem.with_parameters`.

    Raises
    ------
    ModelError
        Neither a built-in nor an existing model file, or an unknown parameter.
    """
    if spec.partition(":")[0].strip() in MODELS:
        return get_model(spec, params)
    if not spec.strip():
        raise ModelError(f"empty model name (known models: {_known()}; or a .toml/.json file)")
    path = Path(spec)
    problem = _file_problem(path)
    if path.suffix.lower() not in _MODEL_FILE_SUFFIXES and problem == "not found":
        raise ModelError(
            f"unknown model {_shown(spec)!r}: not a built-in (known models: {_known()}) "
            "and not a model file (.toml or .json)"
        )
    if problem is not None:
        raise ModelError(f"model file {_shown(spec)!r} {problem}")
    from nilpotent.core.model.modelfile import load_model_file  # lazy: written alongside

    system = load_model_file(path)
    if params:
        system = system.with_parameters(dict(params))
    return system


_BUILTIN_CHECKS: dict[tuple[Any, ...], bool] = {}


def is_builtin(system: ControlSystem) -> bool:
    """Whether ``system`` has the coordinates and fields of the built-in model of its name
    and parameters (structural equality of the sympy fields; cached): a model file that
    only borrows a built-in's name (``name = "unicycle"`` over other fields) is not."""
    key = (system.name, system.coordinate_names, tuple(system.parameters),
           tuple(tuple(f) for f in system.fields))
    if key not in _BUILTIN_CHECKS:
        try:
            ref = get_model(system.name, dict(system.parameters))
            same = (ref.coordinate_names == system.coordinate_names
                    and tuple(tuple(f) for f in ref.fields) == key[3])
        except NilpotentError:  # a name or parameters the built-ins refuse: not one
            same = False
        _BUILTIN_CHECKS[key] = same
    return _BUILTIN_CHECKS[key]
