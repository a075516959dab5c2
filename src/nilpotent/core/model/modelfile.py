"""Model files: a user's own driftless system as TOML or JSON.

The format (see ``docs/model-files.md``)::

    name = "unicycle"                 # optional; default: the file's stem
    description = "optional, one line"
    coordinates = ["x", "y", "theta"]

    [parameters]                      # optional: named constants
    l = 1.0                           # a number, or a constant expression "sqrt(2)/2"

    [[fields]]                        # one table per control field X_i, in order
    x = "cos(theta)"                  # component along each coordinate; missing = 0
    y = "sin(theta)"

    [[fields]]
    theta = "1"

JSON files hold the same structure (``{"coordinates": [...], "fields": [{...}]}``).

Components are parsed by :func:`nilpotent.core.model.expressions.parse_expression`
with the coordinate and parameter names; user text never reaches ``eval``.
Coordinates become plain :class:`sympy.Symbol` objects; parameters appear in
the fields as ``sympy.Symbol(name)`` and their values are stored in
:attr:`ControlSystem.parameters`.

Every mistake raises :class:`~nilpotent.errors.ModelError` (or
:class:`~nilpotent.errors.ExpressionError` for a component outside the grammar)
with a message naming the file, the field (``fields[1].theta (X2)``; list
positions are 0-based, field numbers ``X1, X2, ...`` 1-based) and the text.
"""

from __future__ import annotations

import keyword
import math
import unicodedata
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import sympy as sp

from nilpotent.core.model.datafile import (  # noqa: F401  (re-exported: the limits of a file)
    MAX_FILE_BYTES,
    MAX_INT_DIGITS,
    SUFFIXES,
    file_suffix,
    read_data_file,
)
from nilpotent.core.model.expressions import (
    MAX_BITS,
    RESERVED_NAMES,
    format_expression,
    parse_expression,
    real_value,
)
from nilpotent.core.model.outline import Limits, Outline
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ComputationLimitError, ExpressionError, ModelError
from nilpotent.strict_json import json_text

__all__ = [
    "ALLOWED_KEYS",
    "SUFFIXES",
    "dump_model_file",
    "limits_from_dict",
    "load_model_file",
    "outline_from_dict",
    "relative_limits_from_dict",
    "system_from_dict",
    "system_to_dict",
]

#: Top-level keys of a model file.
ALLOWED_KEYS: tuple[str, ...] = (
    "name", "description", "coordinates", "parameters", "fields", "limits", "geometry",
    "relative_limits",
)
#: Most coordinates of a model file.
MAX_COORDINATES = 40
#: Most control fields of a model file.
MAX_FIELDS = 40
#: Most parameters of a model file.
MAX_PARAMETERS = 100
#: Longest coordinate or parameter name, in characters.
MAX_NAME_LENGTH = 64
#: Longest model name and description, in characters.
MAX_TITLE_LENGTH = 200
MAX_DESCRIPTION_LENGTH = 2000


def _limit(source: str, what: str, count: int, limit: int, name: str) -> None:
    if count > limit:
        raise ComputationLimitError(
            f"{source}: {count:,} {what}, above the limit {limit:,} of a model file "
            f"(nilpotent.core.model.modelfile.{name})"
        )


def name_skeleton(name: str) -> str:
    """The look-alike skeleton of a name (after Unicode TR39): compatibility forms and
    accents removed, each character replaced by the ASCII character it looks like
    (Cyrillic ``х`` → ``x``), so that two names with the same skeleton read the same."""
    from confusable_homoglyphs import confusables

    decomposed = unicodedata.normalize("NFKD", name)
    out = []
    for ch in decomposed:
        if unicodedata.combining(ch):
            continue
        if ch.isascii():
            out.append(ch)
            continue
        found = confusables.is_confusable(ch, greedy=True, preferred_aliases=["latin"]) or []
        ascii_like = [g["c"] for item in found for g in item["homoglyphs"]
                      if g["c"].isascii() and g["c"].isalnum()]
        out.append(ascii_like[0] if ascii_like else ch)
    return "".join(out)


def _check_lookalikes(names: list[str], source: str) -> None:
    """Refuse two names that differ only by look-alike characters (``x`` and Cyrillic ``х``)."""
    seen: dict[str, str] = {}
    for name in names:
        key = name_skeleton(name)
        other = seen.get(key)
        if other is not None and other != name:
            raise ModelError(
                f"{source}: the names {other!r} and {name!r} look alike (they differ only by "
                f"look-alike characters: {other!a} vs {name!a}); rename one"
            )
        seen[key] = name


def _show(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _check_name(name: object, what: str, source: str) -> str:
    """Validate a coordinate or parameter name; return it."""
    if not isinstance(name, str):
        raise ModelError(f"{source}: {what} must be a string, got {_show(name)}")
    if not name:
        raise ModelError(f"{source}: {what} is empty")
    if len(name) > MAX_NAME_LENGTH:
        raise ComputationLimitError(
            f"{source}: {what} {_show(name)} has {len(name):,} characters, above the limit "
            f"{MAX_NAME_LENGTH} of a name (nilpotent.core.model.modelfile.MAX_NAME_LENGTH)"
        )
    if not name.isidentifier() or unicodedata.normalize("NFKC", name) != name:
        raise ModelError(
            f"{source}: {what} {name!r} is not a valid name (letters, digits and '_', "
            "not starting with a digit)"
        )
    if keyword.iskeyword(name):
        raise ModelError(f"{source}: {what} {name!r} is a reserved word of the grammar")
    if name.startswith("__") and name.endswith("__"):
        raise ModelError(f"{source}: {what} {name!r} is not allowed (double underscores)")
    if name in RESERVED_NAMES:
        raise ModelError(
            f"{source}: {what} {name!r} clashes with a function or constant of the grammar "
            f"({', '.join(sorted(RESERVED_NAMES))})"
        )
    return name


def _integer(value: int, where: str) -> sp.Expr:
    if value.bit_length() > MAX_BITS:
        raise ModelError(
            f"{where}: integer of {value.bit_length():,} bits, too large (at most {MAX_BITS} "
            "bits)")
    return sp.Integer(value)


def _parameter_value(value: object, where: str) -> sp.Expr:
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise ModelError(
            f"{where}: a parameter value must be a number or a constant expression, "
            f"got {_show(value)}"
        )
    if isinstance(value, int):
        return _integer(value, where)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ModelError(f"{where}: parameter value must be finite, got {value!r}")
        return sp.Float(value)
    expr = parse_expression(value, {}, where=where)
    try:
        real_value(expr, where=where)
    except ExpressionError as exc:
        raise ModelError(f"{exc} (text {_show(value)})") from None
    return expr


def _component(value: object, names: Mapping[str, sp.Symbol], where: str) -> sp.Expr:
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise ModelError(
            f"{where}: a component must be an expression (text) or a number, got {_show(value)}"
        )
    if isinstance(value, int):
        return _integer(value, where)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ModelError(f"{where}: component must be finite, got {value!r}")
        return sp.Float(value)
    return parse_expression(value, names, where=where)


def system_from_dict(
    data: Mapping[str, Any], source: str = "<dict>", *, default_name: str | None = None
) -> ControlSystem:
    """Build a :class:`ControlSystem` from the model-file structure.

    Parameters
    ----------
    data:
        The decoded TOML/JSON document (see the module docstring).
    source:
        Where it comes from (a file path), put at the start of error messages.
    default_name:
        The model's name when ``data`` has no ``name``; default: the stem of
        ``source`` when it looks like a path, else ``"model"``.

    Raises
    ------
    ModelError
        A missing, unknown or malformed key, a bad name, an unknown coordinate
        in a field, a zero field, a non-constant parameter.
    ExpressionError
        A component outside the expression grammar.

    Examples
    --------
    >>> s = system_from_dict({"coordinates": ["x", "y", "theta"],
    ...                       "fields": [{"x": "cos(theta)", "y": "sin(theta)"}, {"theta": 1}]},
    ...                      default_name="unicycle")
    >>> s.name, s.n, s.m
    ('unicycle', 3, 2)
    """
    if not isinstance(data, Mapping):
        raise ModelError(
            f"{source}: a model must be a table/object with keys {', '.join(ALLOWED_KEYS)}, "
            f"got {type(data).__name__}"
        )
    unknown = [k for k in data if k not in ALLOWED_KEYS]
    if unknown:
        raise ModelError(
            f"{source}: unknown key {_show(unknown[0])} (allowed keys: {', '.join(ALLOWED_KEYS)})"
        )

    if default_name is None:
        default_name = Path(source).stem if source and not source.startswith("<") else "model"
    name = data.get("name", default_name)
    if not isinstance(name, str) or not name.strip():
        raise ModelError(f"{source}: name must be a non-empty string, got {_show(name)}")
    _limit(source, "characters in the name", len(name), MAX_TITLE_LENGTH, "MAX_TITLE_LENGTH")
    description = data.get("description", "")
    if not isinstance(description, str):
        raise ModelError(f"{source}: description must be a string, got {_show(description)}")
    _limit(source, "characters in the description", len(description), MAX_DESCRIPTION_LENGTH,
           "MAX_DESCRIPTION_LENGTH")

    # coordinates
    if "coordinates" not in data:
        raise ModelError(f"{source}: missing 'coordinates' (a list of names, e.g. [\"x\", \"y\"])")
    raw_coords = data["coordinates"]
    if not isinstance(raw_coords, list) or not raw_coords:
        raise ModelError(
            f"{source}: coordinates must be a non-empty list of names, got {_show(raw_coords)}"
        )
    _limit(source, "coordinates", len(raw_coords), MAX_COORDINATES, "MAX_COORDINATES")
    coord_names = [
        _check_name(c, f"coordinates[{i}]", source) for i, c in enumerate(raw_coords)
    ]
    seen: set[str] = set()
    for c in coord_names:
        if c in seen:
            raise ModelError(f"{source}: duplicate coordinate {c!r} in coordinates")
        seen.add(c)
    coords = tuple(sp.Symbol(c) for c in coord_names)

    # parameters
    raw_params = data.get("parameters", {})
    if not isinstance(raw_params, Mapping):
        raise ModelError(
            f"{source}: parameters must be a table of NAME = value, got {_show(raw_params)}"
        )
    _limit(source, "parameters", len(raw_params), MAX_PARAMETERS, "MAX_PARAMETERS")
    _check_lookalikes([*coord_names, *(k for k in raw_params if isinstance(k, str))], source)
    params: dict[str, sp.Expr] = {}
    for key, value in raw_params.items():
        pname = _check_name(key, "parameter name", source)
        if pname in seen:
            raise ModelError(f"{source}: parameters.{pname}: {pname!r} is also a coordinate")
        params[pname] = _parameter_value(value, f"{source}: parameters.{pname}")

    # fields
    if "fields" not in data:
        raise ModelError(f"{source}: missing 'fields' (one [[fields]] table per control field)")
    raw_fields = data["fields"]
    if not isinstance(raw_fields, list) or not raw_fields:
        raise ModelError(
            f"{source}: fields must be a non-empty list of tables, got {_show(raw_fields)}"
        )
    _limit(source, "fields", len(raw_fields), MAX_FIELDS, "MAX_FIELDS")
    names: dict[str, sp.Symbol] = {c: s for c, s in zip(coord_names, coords, strict=True)}
    names.update({p: sp.Symbol(p) for p in params})
    fields = []
    for i, raw in enumerate(raw_fields):
        label = f"fields[{i}] (X{i + 1})"
        if not isinstance(raw, Mapping):
            raise ModelError(
                f"{source}: {label} must be a table of COORDINATE = expression, got {_show(raw)}"
            )
        components: dict[str, sp.Expr] = dict.fromkeys(coord_names, sp.Integer(0))
        for key, value in raw.items():
            if key not in seen:
                raise ModelError(
                    f"{source}: {label}: unknown coordinate {_show(key)} "
                    f"(coordinates: {', '.join(coord_names)})"
                )
            where = f"{source}: fields[{i}].{key} (X{i + 1})"
            components[key] = _component(value, names, where)
        if all(e.is_Number and e.is_zero for e in components.values()):
            raise ModelError(
                f"{source}: {label} is zero (give at least one nonzero component, "
                f"e.g. {coord_names[0]} = \"1\")"
            )
        fields.append(tuple(components[c] for c in coord_names))
    limits = limits_from_dict(data.get("limits", {}), coord_names, source)
    if "relative_limits" in data:
        relative = relative_limits_from_dict(data["relative_limits"],
                                             {c: names[c] for c in coord_names}, source)
        try:
            limits = Limits(limits.bounds, relative)  # linear ones normalised (Limits)
        except ModelError as exc:
            raise ModelError(f"{source}: relative_limits: {exc}") from None
    geometry = outline_from_dict(data["geometry"], names, source) if "geometry" in data else None
    try:
        return ControlSystem(
            name, coords, tuple(fields), tuple(params.items()), description, limits, geometry
        )
    except ModelError as exc:
        raise ModelError(f"{source}: {exc}") from None


def limits_from_dict(raw: object, coord_names: list[str], source: str) -> Limits:
    """The ``[limits]`` table: ``NAME = [lo, hi]`` (numbers or constant expressions).

    Raises
    ------
    ModelError
        Not a table, an unknown coordinate, not a pair, ``lo > hi``, not finite.
    """
    if not isinstance(raw, Mapping):
        raise ModelError(f"{source}: limits must be a table of NAME = [lo, hi], got {_show(raw)}")
    bounds = []
    for key, pair in raw.items():
        where = f"{source}: limits.{key}"
        if key not in coord_names:
            raise ModelError(
                f"{where}: {key!r} is not a coordinate (coordinates: {', '.join(coord_names)})"
            )
        if not isinstance(pair, list) or len(pair) != 2:
            raise ModelError(f"{where}: a limit is a pair [lo, hi], got {_show(pair)}")
        lo, hi = (real_value(_parameter_value(v, where), where=where) for v in pair)
        if lo > hi:
            raise ModelError(f"{where}: lower bound {lo} is above the upper bound {hi}")
        bounds.append((key, lo, hi))
    return Limits(tuple(bounds))


def relative_limits_from_dict(
    raw: object, coords: Mapping[str, sp.Symbol], source: str
) -> tuple[tuple[str, sp.Expr, float, float], ...]:
    """The ``[relative_limits]`` table: ``"EXPRESSION" = [lo, hi]``, e.g.
    ``"theta0 - theta1" = [-1.4, 1.4]`` (a hitch angle).

    The key is an expression of the safe grammar in the coordinates only (not the
    parameters: a limit stays the same when ``--param`` changes them); the bounds are
    numbers or constant expressions.  The limits are returned as given; :class:`Limits`
    normalises the linear ones (``"2*theta0 - 2*theta1" = [-1.4, 1.4]`` is
    ``theta0 - theta1`` in ``[-0.7, 0.7]``) and refuses two of the same quantity.

    Raises
    ------
    ModelError
        Not a table, an empty key, a key that names no coordinate, not a pair, ``lo > hi``,
        a bound that is not finite, the same expression twice.
    ExpressionError
        A key outside the grammar or naming something that is not a coordinate.
    """
    if not isinstance(raw, Mapping):
        raise ModelError(f"{source}: relative_limits must be a table of \"EXPRESSION\" = "
                         f"[lo, hi] (e.g. \"theta0 - theta1\" = [-1.4, 1.4]), got {_show(raw)}")
    out = []
    seen: dict[sp.Expr, str] = {}
    for key, pair in raw.items():
        where = f"{source}: relative_limits.{_show(key)}"
        if not isinstance(key, str) or not key.strip():
            raise ModelError(f"{where}: the key must be an expression of the coordinates")
        expr = parse_expression(key, coords, where=where)
        if not expr.free_symbols:
            raise ModelError(f"{where}: {key!r} is a constant; a relative limit is an "
                             f"expression of the coordinates ({', '.join(coords)})")
        if expr in seen:
            raise ModelError(f"{where}: the same expression as relative_limits."
                             f"{_show(seen[expr])}")
        seen[expr] = key
        if not isinstance(pair, list) or len(pair) != 2:
            raise ModelError(f"{where}: a limit is a pair [lo, hi], got {_show(pair)}")
        lo, hi = (real_value(_parameter_value(v, where), where=where) for v in pair)
        if lo > hi:
            raise ModelError(f"{where}: lower bound {lo} is above the upper bound {hi}")
        out.append((key, expr, lo, hi))
    return tuple(out)


def _body_name(value: object, where: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise ModelError(f"{where}: a body name is a non-empty string, got {_show(value)}")
    if len(value) > MAX_NAME_LENGTH:
        raise ModelError(f"{where}: body name of {len(value):,} characters, above the limit "
                         f"{MAX_NAME_LENGTH}")
    return value


def _self_collision(raw: object, bodies: list[str | None], source: str) -> tuple:
    where = f"{source}: geometry.self_collision"
    known = list(dict.fromkeys(b for b in bodies if b is not None))
    if raw == "all":
        return tuple((a, b) for i, a in enumerate(known) for b in known[i + 1:])
    if not isinstance(raw, list):
        raise ModelError(f"{where}: a list of body pairs [[\"A\", \"B\"], ...] or \"all\" "
                         f"(every pair of distinct bodies), got {_show(raw)}")
    out = []
    for i, pair in enumerate(raw):
        if not isinstance(pair, list) or len(pair) != 2:
            raise ModelError(f"{where}[{i}]: a pair of body names [\"A\", \"B\"], "
                             f"got {_show(pair)}")
        out.append(tuple(_body_name(b, f"{where}[{i}]") for b in pair))
    return tuple(out)


def _outline_point(raw: object, names: Mapping[str, sp.Symbol], where: str) -> tuple:
    if not isinstance(raw, list) or len(raw) != 2:
        raise ModelError(f"{where}: a point is a pair [X, Y] of expressions, got {_show(raw)}")
    return (_component(raw[0], names, f"{where}[0]"), _component(raw[1], names, f"{where}[1]"))


def outline_from_dict(raw: object, names: Mapping[str, sp.Symbol], source: str) -> Outline:
    """The ``[geometry]`` table: ``polygons``, ``segments``, ``discs`` (the Model files page).

    Every number is an expression of the coordinates and parameters (the safe
    grammar of :mod:`nilpotent.core.model.expressions`).

    Raises
    ------
    ModelError
        Unknown keys, malformed entries, a polygon with fewer than 3 points.
    ExpressionError
        An expression outside the grammar or naming an unknown symbol.
    """
    kinds = ("polygons", "segments", "discs")
    if not isinstance(raw, Mapping):
        raise ModelError(f"{source}: geometry must be a table with {', '.join(kinds)}")
    for key in raw:
        if key not in (*kinds, "self_collision"):
            raise ModelError(
                f"{source}: geometry: unknown key {_show(key)} (allowed: {', '.join(kinds)}, "
                "self_collision)"
            )
    parts: dict[str, list] = {k: [] for k in kinds}
    bodies: list[str | None] = []
    for kind in kinds:
        items = raw.get(kind, [])
        if not isinstance(items, list):
            raise ModelError(f"{source}: geometry.{kind} must be a list of tables")
        for i, item in enumerate(items):
            where = f"{source}: geometry.{kind}[{i}]"
            want = {"polygons": ("points",), "segments": ("from", "to"),
                    "discs": ("center", "radius")}[kind]
            if not isinstance(item, Mapping) or set(item) - {"body"} != set(want):
                raise ModelError(f"{where}: needs exactly the keys {', '.join(want)} "
                                 "(and optionally body)")
            bodies.append(_body_name(item["body"], f"{where}.body") if "body" in item else None)
            if kind == "polygons":
                pts = item["points"]
                if not isinstance(pts, list) or len(pts) < 3:
                    raise ModelError(f"{where}.points: a polygon needs at least 3 points")
                parts[kind].append(tuple(
                    _outline_point(p, names, f"{where}.points[{j}]") for j, p in enumerate(pts)
                ))
            elif kind == "segments":
                parts[kind].append((_outline_point(item["from"], names, f"{where}.from"),
                                    _outline_point(item["to"], names, f"{where}.to")))
            else:
                parts[kind].append((_outline_point(item["center"], names, f"{where}.center"),
                                    _component(item["radius"], names, f"{where}.radius")))
    pairs = _self_collision(raw["self_collision"], bodies, source) if "self_collision" in raw \
        else ()
    try:
        return Outline(tuple(parts["polygons"]), tuple(parts["segments"]), tuple(parts["discs"]),
                       tuple(bodies) if any(b is not None for b in bodies) else (), pairs)
    except ModelError as exc:
        raise ModelError(f"{source}: {exc}") from None


def _outline_to_dict(outline: Outline) -> dict[str, Any]:
    def pt(p: tuple) -> list[str]:
        return [format_expression(p[0]), format_expression(p[1])]

    out: dict[str, Any] = {}
    if outline.self_collision:
        out["self_collision"] = [list(p) for p in outline.self_collision]
    items: dict[str, list[dict[str, Any]]] = {
        "polygons": [{"points": [pt(p) for p in poly]} for poly in outline.polygons],
        "segments": [{"from": pt(a), "to": pt(b)} for a, b in outline.segments],
        "discs": [{"center": pt(c), "radius": format_expression(r)} for c, r in outline.discs],
    }
    k = 0
    for kind in ("polygons", "segments", "discs"):
        for item in items[kind]:
            body = outline.bodies[k] if outline.bodies else None
            if body is not None:
                item["body"] = body
            k += 1
        if items[kind]:
            out[kind] = items[kind]
    return out


def system_to_dict(sys: ControlSystem) -> dict[str, Any]:
    """The model-file structure of a system (inverse of :func:`system_from_dict`).

    Components are written with :func:`format_expression` and zero components
    are left out; integer and float parameter values stay numbers, other exact
    values become expressions (``"sqrt(2)"``).

    Raises
    ------
    ExpressionError
        A component the grammar cannot write (e.g. a function outside it).
    """
    out: dict[str, Any] = {"name": sys.name}
    if sys.description:
        out["description"] = sys.description
    out["coordinates"] = list(sys.coordinate_names)
    if sys.parameters:
        params: dict[str, Any] = {}
        for k, v in sys.parameters:
            if isinstance(v, sp.Integer):
                params[k] = int(v)
            elif isinstance(v, sp.Float) and math.isfinite(float(v)):
                params[k] = float(v)
            else:
                params[k] = format_expression(v)
        out["parameters"] = params
    out["fields"] = [
        {
            c: format_expression(e)
            for c, e in zip(sys.coordinate_names, f, strict=True)
            if not (e.is_Number and e.is_zero)
        }
        for f in sys.fields
    ]
    if sys.limits.bounds:
        out["limits"] = {k: [lo, hi] for k, (lo, hi) in sys.limits.as_dict().items()}
    if sys.limits.relative:
        out["relative_limits"] = {k: [lo, hi]
                                  for k, (lo, hi) in sys.limits.relative_dict().items()}
    if sys.geometry is not None:
        out["geometry"] = _outline_to_dict(sys.geometry)
    return out


def load_model_file(path: str | Path) -> ControlSystem:
    """Read a model file (``.toml`` or ``.json``) into a :class:`ControlSystem`.

    The model's name defaults to the file's stem.

    Parameters
    ----------
    path : str or Path
        The model file (format: the Model files page).

    Raises
    ------
    ModelError
        Unknown suffix, unreadable or non-regular file, syntax error (with its line),
        a duplicate JSON key (:func:`nilpotent.core.model.datafile.read_data_file`), or any
        problem :func:`system_from_dict` reports.
    ComputationLimitError
        A file larger than :data:`nilpotent.core.model.datafile.MAX_FILE_BYTES`.
    ExpressionError
        A component outside the expression grammar.
    """
    path = Path(path)
    data = read_data_file(path, "model file", ModelError)
    return system_from_dict(data, str(path), default_name=path.stem)


# --- writing -------------------------------------------------------------------------

_TOML_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f",
                 "\r": "\\r"}


def _toml_string(text: str) -> str:
    out = []
    for ch in text:
        if ch in _TOML_ESCAPES:
            out.append(_TOML_ESCAPES[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _toml_key(key: str) -> str:
    bare = key and all(ch.isascii() and (ch.isalnum() or ch in "_-") for ch in key)
    return key if bare else _toml_string(key)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(type(value).__name__)  # pragma: no cover - system_to_dict emits no others


def _to_toml(data: Mapping[str, Any]) -> str:
    lines = []
    for key in ("name", "description", "coordinates"):
        if key in data:
            lines.append(f"{key} = {_toml_value(data[key])}")
    if data.get("parameters"):
        lines += ["", "[parameters]"]
        lines += [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in data["parameters"].items()]
    for f in data["fields"]:
        lines += ["", "[[fields]]"]
        lines += [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in f.items()]
    if data.get("limits"):
        lines += ["", "[limits]"]
        lines += [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in data["limits"].items()]
    if data.get("relative_limits"):
        lines += ["", "[relative_limits]"]
        lines += [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in data["relative_limits"].items()]
    geometry = dict(data.get("geometry", {}))
    if "self_collision" in geometry:
        pairs = _toml_value(geometry.pop("self_collision"))
        lines += ["", "[geometry]", f"self_collision = {pairs}"]
    for kind, items in geometry.items():
        for item in items:
            lines += ["", f"[[geometry.{kind}]]"]
            lines += [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in item.items()]
    return "\n".join(lines) + "\n"


def dump_model_file(sys: ControlSystem, path: str | Path) -> None:
    """Write a system as a model file, TOML or JSON by the suffix of ``path``.

    :func:`load_model_file` reads the file back to an equal system (for systems
    whose fields are written in the grammar and have a nonzero component).

    Raises
    ------
    ModelError
        Unknown suffix, or the file cannot be written.
    ExpressionError
        A component the grammar cannot write.
    """
    path = Path(path)
    suffix = file_suffix(path, "model file", ModelError)
    data = system_to_dict(sys)
    text = _to_toml(data) if suffix == ".toml" else json_text(data)
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise ModelError(f"{path}: cannot write the model file ({exc.strerror})") from None
