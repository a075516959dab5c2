"""Model files (TOML/JSON): loading, validation messages, writing, fuzzing."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nilpotent.core.model.modelfile import (
    ALLOWED_KEYS,
    dump_model_file,
    load_model_file,
    system_from_dict,
    system_to_dict,
)
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ExpressionError, ModelError

DATA = Path(__file__).parent / "data"
x, y, th = sp.symbols("x y theta")

UNICYCLE = ControlSystem(
    "unicycle",
    (x, y, th),
    ((sp.cos(th), sp.sin(th), 0), (0, 0, 1)),
    description="unicycle: forward velocity and turning rate",
)


# --- loading -------------------------------------------------------------------

@pytest.mark.parametrize("name", ["unicycle.toml", "unicycle.json"])
def test_unicycle_files_give_the_hand_built_system(name):
    assert load_model_file(DATA / name) == UNICYCLE


def test_parameters_are_symbols_with_exact_values():
    s = load_model_file(DATA / "car_trailer.toml")
    assert s.name == "car_trailer"  # the file stem: the file has no name key
    assert s.coordinate_names == ("x", "y", "phi", "theta0", "theta1")
    assert s.parameter_values == {"l": 1, "d": sp.Rational(1, 2)}
    phi, th0, th1 = sp.symbols("phi theta0 theta1")
    l, d = sp.symbols("l d")
    assert s.fields[0] == (sp.cos(th0), sp.sin(th0), 0, sp.tan(phi) / l, sp.sin(th0 - th1) / d)
    assert s.fields[1] == (0, 0, 1, 0, 0)
    assert s.specialized_fields[0][4] == 2 * sp.sin(th0 - th1)


def test_numbers_as_components_and_name_from_stem():
    s = load_model_file(DATA / "heisenberg.json")
    z = sp.Symbol("z")
    assert s.name == "heisenberg"
    assert s.fields == ((1, 0, -y / 2), (0, 1, x / 2))
    assert s.coordinates == (x, y, z)


def test_floats_stay_floats():
    s = system_from_dict({"coordinates": ["x"], "fields": [{"x": 0.5}],
                          "parameters": {"k": 2.5}})
    assert isinstance(s.fields[0][0], sp.Float)
    assert isinstance(s.parameter_values["k"], sp.Float)


def test_parameter_given_as_constant_expression():
    s = system_from_dict({"coordinates": ["x"], "parameters": {"a": "sqrt(2)/2"},
                          "fields": [{"x": "a"}]})
    assert s.parameter_values["a"] == sp.sqrt(2) / 2
    assert s.specialized_fields[0][0] == sp.sqrt(2) / 2


def test_unicode_coordinate_names():
    s = system_from_dict({"coordinates": ["θ", "x"], "fields": [{"x": "cos(θ)"}, {"θ": 1}]})
    assert s.coordinate_names == ("θ", "x")


# --- errors ----------------------------------------------------------------------

def _write(tmp_path: Path, text: str, name: str = "m.toml") -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


GOOD_FIELDS = '\n[[fields]]\nx = "1"\n'


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        ('coordinates = ["x"\n' + GOOD_FIELDS, ["m.toml", "TOML syntax error", "line"]),
        (GOOD_FIELDS, ["m.toml", "missing 'coordinates'"]),
        ("coordinates = []\n" + GOOD_FIELDS, ["coordinates must be a non-empty list"]),
        ('coordinates = "x"\n' + GOOD_FIELDS, ["coordinates must be a non-empty list"]),
        ("coordinates = [1]\n" + GOOD_FIELDS, ["coordinates[0] must be a string"]),
        ('coordinates = ["x", "1y"]\n' + GOOD_FIELDS, ["coordinates[1]", "'1y'", "not a valid"]),
        ('coordinates = ["x", "a b"]\n' + GOOD_FIELDS, ["'a b'", "not a valid name"]),
        ('coordinates = ["x", "sin"]\n' + GOOD_FIELDS, ["'sin'", "clashes"]),
        ('coordinates = ["x", "pi"]\n' + GOOD_FIELDS, ["'pi'", "clashes"]),
        ('coordinates = ["x", "E"]\n' + GOOD_FIELDS, ["'E'", "clashes"]),
        ('coordinates = ["x", "lambda"]\n' + GOOD_FIELDS, ["'lambda'", "reserved word"]),
        ('coordinates = ["x", "__class__"]\n' + GOOD_FIELDS, ["'__class__'", "not allowed"]),
        ('coordinates = ["x", "x"]\n' + GOOD_FIELDS, ["duplicate coordinate 'x'"]),
        ('coordinates = ["x"]\n', ["m.toml", "missing 'fields'"]),
        ('coordinates = ["x"]\nfields = []\n', ["fields must be a non-empty list"]),
        ('coordinates = ["x"]\n[[fields]]\ny = "1"\n',
         ["m.toml", "fields[0] (X1)", "unknown coordinate 'y'", "coordinates: x"]),
        ('coordinates = ["x"]\n' + GOOD_FIELDS + "\n[[fields]]\n", ["fields[1] (X2) is zero"]),
        ('coordinates = ["x"]\n' + GOOD_FIELDS + '\n[[fields]]\nx = "0"\n',
         ["fields[1] (X2) is zero"]),
        ('coordinates = ["x"]\n[[fields]]\nx = [1]\n', ["fields[0].x (X1)", "[1]"]),
        ('coordinates = ["x"]\n[[fields]]\nx = true\n', ["fields[0].x (X1)", "True"]),
        ('coordinates = ["x"]\nparameters = {a = [1]}\n' + GOOD_FIELDS,
         ["parameters.a", "number or a constant expression"]),
        ('coordinates = ["x"]\nparameters = {a = "x + 1"}\n' + GOOD_FIELDS,
         ["parameters.a", "unknown name 'x'"]),
        ('coordinates = ["x"]\nparameters = {a = "log(-1)"}\n' + GOOD_FIELDS,
         ["parameters.a"]),
        ('coordinates = ["x"]\nparameters = {x = 1}\n' + GOOD_FIELDS,
         ["parameters.x", "also a coordinate"]),
        ('coordinates = ["x"]\nparameters = {pi = 1}\n' + GOOD_FIELDS, ["'pi'", "clashes"]),
        ('coordinates = ["x"]\nparameters = 3\n' + GOOD_FIELDS, ["parameters must be a table"]),
        ('coordinates = ["x"]\nextra = 1\n' + GOOD_FIELDS,
         ["unknown key 'extra'", "allowed keys: " + ", ".join(ALLOWED_KEYS)]),
        ('name = 3\ncoordinates = ["x"]\n' + GOOD_FIELDS, ["name must be a non-empty string"]),
        ('description = 3\ncoordinates = ["x"]\n' + GOOD_FIELDS, ["description must be"]),
        ('coordinates = ["x"]\nfields = [1]\n', ["fields[0] (X1) must be a table"]),
    ],
)
def test_model_errors_name_file_field_and_text(tmp_path, text, fragments):
    with pytest.raises((ModelError, ExpressionError)) as info:
        load_model_file(_write(tmp_path, text))
    message = str(info.value)
    for fragment in fragments:
        assert fragment in message, message


def test_component_outside_the_grammar_names_file_field_and_text(tmp_path):
    text = (
        'coordinates = ["x", "theta"]\n[[fields]]\nx = "1"\n'
        '[[fields]]\ntheta = "__import__(\'os\')"\n'
    )
    with pytest.raises(ExpressionError) as info:
        load_model_file(_write(tmp_path, text))
    message = str(info.value)
    assert "m.toml: fields[1].theta (X2)" in message
    assert "__import__('os')" in message


def test_json_errors(tmp_path):
    with pytest.raises(ModelError, match=r"JSON syntax error.*line 2"):
        load_model_file(_write(tmp_path, '{"coordinates": ["x"],\n "fields": [}', "m.json"))
    with pytest.raises(ModelError, match="must be a table/object"):
        load_model_file(_write(tmp_path, "[1, 2]", "m.json"))


def test_file_level_errors(tmp_path):
    with pytest.raises(ModelError, match=r"unknown model file type '\.yaml'"):
        load_model_file(_write(tmp_path, "x: 1", "m.yaml"))
    with pytest.raises(ModelError, match="not found"):
        load_model_file(tmp_path / "missing.toml")
    p = tmp_path / "bad.toml"
    p.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ModelError, match="UTF-8"):
        load_model_file(p)
    with pytest.raises(ModelError, match="unknown model file type"):
        dump_model_file(UNICYCLE, tmp_path / "out.txt")


# --- writing and round trips -------------------------------------------------------

@pytest.mark.parametrize("fixture", ["unicycle.toml", "car_trailer.toml", "heisenberg.json"])
@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_dump_then_load_is_identity(tmp_path, fixture, suffix):
    s = load_model_file(DATA / fixture)
    out = tmp_path / ("copy" + suffix)
    dump_model_file(s, out)
    assert load_model_file(out) == s
    assert load_model_file(out).name == s.name  # name is written, not taken from "copy"


def test_written_toml_escapes_strings(tmp_path):
    s = ControlSystem("odd \"name\"", (x,), ((1,),),
                      description='quote " backslash \\ tab \t newline \n bell \x07 del \x7f é ∂')
    out = tmp_path / "odd.toml"
    dump_model_file(s, out)
    assert tomllib.loads(out.read_text(encoding="utf-8"))["description"] == s.description
    assert load_model_file(out) == s


def test_system_to_dict_matches_the_documented_format():
    d = system_to_dict(load_model_file(DATA / "car_trailer.toml"))
    assert d["coordinates"] == ["x", "y", "phi", "theta0", "theta1"]
    assert d["parameters"] == {"l": 1, "d": "1/2"}
    assert d["fields"][1] == {"phi": "1"}
    json.dumps(d)  # plain JSON data


_names = st.sampled_from(["x", "y", "z", "theta", "q1", "q2", "phi", "θ", "u_2", "match"])
_component_text = st.sampled_from(
    ["1", "-1", "x0", "cos(x0)", "sin(x0)*x1", "x1**2/2", "sqrt(2)*x0", "0.25", "exp(-x1)",
     "atan2(x1, 1 + x0**2)", "pi/3", "E*x0", "k*x0", "-k/3"]
)


@st.composite
def _systems(draw):
    coords = draw(st.lists(_names, min_size=2, max_size=4, unique=True))
    m = draw(st.integers(min_value=1, max_value=3))
    fields = []
    for _ in range(m):
        f = {}
        for c in draw(st.lists(st.sampled_from(coords), min_size=1, unique=True)):
            text = draw(_component_text)
            f[c] = text.replace("x0", coords[0]).replace("x1", coords[1])
        fields.append(f)
    return {"coordinates": coords, "parameters": {"k": draw(st.sampled_from([2, 0.5, "pi"]))},
            "fields": fields}


@settings(max_examples=60, deadline=2000)
@given(_systems(), st.sampled_from([".toml", ".json"]))
def test_random_systems_round_trip_through_files(tmp_path_factory, data, suffix):
    s = system_from_dict(data, default_name="random")
    assert system_from_dict(system_to_dict(s)) == s
    out = tmp_path_factory.mktemp("rt") / ("random" + suffix)
    dump_model_file(s, out)
    assert load_model_file(out) == s


# --- fuzzing -------------------------------------------------------------------------

VALID = (DATA / "car_trailer.toml").read_text(encoding="utf-8")


@st.composite
def _mutated_text(draw):
    text = VALID
    for _ in range(draw(st.integers(min_value=1, max_value=4))):
        kind = draw(st.sampled_from(["delete", "insert", "replace", "line"]))
        i = draw(st.integers(min_value=0, max_value=max(len(text) - 1, 0)))
        if kind == "delete":
            j = draw(st.integers(min_value=i, max_value=min(len(text), i + 12)))
            text = text[:i] + text[j:]
        elif kind == "insert":
            piece = draw(st.sampled_from(
                ['"', "[", "]", "=", "\n", "x", "**9", "(", ")", ",", "__class__", "[[fields]]\n",
                 "\nfoo = 1\n", "0", ".", "'", "\\", "#", "{", "}", " = ", "9**9**9", "-", "é"]
            ) | st.text(max_size=5))
            text = text[:i] + piece + text[i:]
        elif kind == "replace":
            text = text[:i] + draw(st.characters()) + text[i + 1:]
        else:
            lines = text.split("\n")
            k = draw(st.integers(min_value=0, max_value=len(lines) - 1))
            del lines[k]
            text = "\n".join(lines)
    return text


@settings(max_examples=300, deadline=2000, suppress_health_check=[HealthCheck.too_slow])
@given(_mutated_text())
def test_fuzz_mutated_toml_loads_or_raises_model_errors(tmp_path_factory, text):
    p = tmp_path_factory.mktemp("fuzz") / "m.toml"
    p.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        s = load_model_file(p)
    except (ModelError, ExpressionError) as exc:
        assert str(exc)
    else:
        assert isinstance(s, ControlSystem)


_json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=12),
    lambda c: st.lists(c, max_size=3) | st.dictionaries(st.text(max_size=6), c, max_size=3),
    max_leaves=8,
)


@st.composite
def _mutated_dict(draw):
    data = json.loads(json.dumps(tomllib.loads(VALID)))
    path_kind = draw(st.sampled_from(["top", "coord", "param", "field", "component", "drop"]))
    value = draw(_json_values)
    if path_kind == "top":
        data[draw(st.sampled_from([*ALLOWED_KEYS, "other"]))] = value
    elif path_kind == "coord":
        data["coordinates"][draw(st.integers(0, 4))] = value
    elif path_kind == "param":
        data["parameters"][draw(st.sampled_from(["l", "d", "new", "x"]))] = value
    elif path_kind == "field":
        data["fields"][draw(st.integers(0, 1))] = value
    elif path_kind == "component":
        data["fields"][0][draw(st.sampled_from(["x", "phi", "nope"]))] = value
    else:
        del data[draw(st.sampled_from(list(data)))]
    return data


@settings(max_examples=300, deadline=2000)
@given(_mutated_dict())
def test_fuzz_mutated_structures_load_or_raise_model_errors(data):
    try:
        s = system_from_dict(data, "fuzz.json")
    except (ModelError, ExpressionError) as exc:
        assert str(exc).startswith("fuzz.json")
    else:
        assert isinstance(s, ControlSystem)
