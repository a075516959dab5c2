"""The public surface: one explicit list, every name resolves, every parameter is documented."""

from __future__ import annotations

import ast
import inspect
import re
import subprocess
import sys
from pathlib import Path

import pytest

import nilpotent

INIT = Path(nilpotent.__file__)


def _listed_imports() -> tuple[set[str], set[str]]:
    """Names imported ``X as X`` at top level (eager) and inside ``if TYPE_CHECKING:`` (lazy;
    ``f as g`` there makes ``g`` a second public name of ``f``)."""
    tree = ast.parse(INIT.read_text(encoding="utf-8"))
    eager: set[str] = set()
    lazy: set[str] = set()
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and node.module.startswith("nilpotent"):
            eager |= {a.asname for a in node.names if a.asname == a.name}
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for stmt in node.body:
                assert isinstance(stmt, ast.ImportFrom), ast.unparse(stmt)
                for alias in stmt.names:
                    assert alias.asname, f"write {alias.name} as {alias.name}"
                    lazy.add(alias.asname)
    return eager, lazy


def test_all_is_exactly_the_listed_imports():
    eager, lazy = _listed_imports()
    assert not eager & lazy
    assert sorted(nilpotent.__all__) == sorted(eager | lazy | {"__version__"})
    assert len(set(nilpotent.__all__)) == len(nilpotent.__all__)


@pytest.mark.parametrize("name", sorted(_listed_imports()[1]))
def test_lazy_name_is_the_defining_modules_object(name):
    tree = ast.parse(INIT.read_text(encoding="utf-8"))
    ((module, original),) = {
        (stmt.module, a.name)
        for node in tree.body
        if isinstance(node, ast.If)
        for stmt in node.body
        if isinstance(stmt, ast.ImportFrom)
        for a in stmt.names
        if a.asname == name
    }
    import importlib

    assert getattr(nilpotent, name) is getattr(importlib.import_module(module), original)
    assert name in dir(nilpotent)


#: ``nilpotent COMMAND`` -> the function ``nilpotent.COMMAND`` calls (README "Command line
#: and Python"); ``steer`` is the local steering ``nilpotent plan`` does not expose.
COMMANDS = {
    "analyze": "nilpotent.core.analysis.filtration:analyze",
    "approximate": "nilpotent.core.coordinates.approximation:approximate",
    "simulate": "nilpotent.simulation.comparison:compare_bracket_motion",
    "scaling": "nilpotent.simulation.scaling:scaling_study",
    "sweep": "nilpotent.simulation.sweep:sweep",
    "plan": "nilpotent.planning.global_planner:plan_global",
    "steer": "nilpotent.planning.iterative:plan",
    "execute": "nilpotent.planning.execute:execute_plan",
    "reproduce": "nilpotent.report.pipeline:reproduce",
}


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_the_api_is_named_like_the_commands(name):
    """``nilpotent.X`` is the function (never a module, whatever was imported before)."""
    import importlib
    import types

    importlib.import_module("nilpotent.simulation")
    importlib.import_module("nilpotent.planning")
    module, function = COMMANDS[name].split(":")
    value = getattr(nilpotent, name)
    assert not isinstance(value, types.ModuleType)
    assert value is getattr(importlib.import_module(module), function)
    # no module of that name could shadow it after an ``import nilpotent.<name>``
    assert not (INIT.parent / f"{name}.py").exists()
    assert not (INIT.parent / name).is_dir()


def test_the_commands_call_the_functions_of_the_same_name():
    """Each command module imports the function the API names after it (read from the code)."""
    cli = INIT.parent / "cli"
    for name, target in COMMANDS.items():
        if name == "steer":
            continue
        module, function = target.split(":")
        paths = [cli / f"cmd_{name}.py", cli / f"{name}_options.py"]
        imported = {
            (node.module, a.name)
            for path in paths
            if path.exists()
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
            if isinstance(node, ast.ImportFrom)
            for a in node.names
        }
        faces = {module, module.rpartition(".")[0]}
        assert any((m, function) in imported for m in faces), (name, target)


def test_unknown_attribute_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        nilpotent.no_such_name  # noqa: B018


def test_import_nilpotent_is_light():
    code = (
        "import sys, nilpotent;"
        "print(','.join(m for m in ('scipy', 'matplotlib', 'numba') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


# --- docstrings: every parameter of every public function has a numpydoc entry -----------

_SECTION = re.compile(r"^(?P<title>[A-Z][A-Za-z ]+)\n-{3,}\n", re.M)
_ENTRY = re.compile(r"^(?P<names>\*{0,2}[A-Za-z_]\w*(?:, \*{0,2}[A-Za-z_]\w*)*) ?:(?: |$)")


def documented_parameters(doc: str) -> set[str]:
    """The names of the entries of the ``Parameters`` section (``name : type`` lines).

    Only lines at the section's own indentation count (not words in the prose
    of another entry), and only inside the ``Parameters`` section.
    """
    sections = list(_SECTION.finditer(doc))
    for k, sec in enumerate(sections):
        if sec.group("title") != "Parameters":
            continue
        end = sections[k + 1].start() if k + 1 < len(sections) else len(doc)
        names: set[str] = set()
        for line in doc[sec.end() : end].splitlines():
            m = _ENTRY.match(line)
            if m:
                names |= {n.strip().lstrip("*") for n in m.group("names").split(",")}
        return names
    return set()


def test_the_entry_parser_reads_entries_not_prose():
    doc = inspect.cleandoc(
        """Summary mentioning x0 and sys.

        Parameters
        ----------
        sys : ControlSystem
            The system; see also timepts below.
        a, b : float
            Two numbers.

        Returns
        -------
        x0 : float
            Not a parameter.
        """
    )
    assert documented_parameters(doc) == {"sys", "a", "b"}


def _public_functions() -> list[str]:
    return sorted(
        n
        for n in nilpotent.__all__
        if inspect.isfunction(getattr(nilpotent, n, None))
        or inspect.isfunction(getattr(getattr(nilpotent, n, None), "__wrapped__", None))
    )


@pytest.mark.parametrize("name", _public_functions())
def test_every_parameter_has_a_numpydoc_entry(name):
    func = getattr(nilpotent, name)
    doc = inspect.getdoc(func) or ""
    assert doc, f"nilpotent.{name} has no docstring"
    params = [
        p.name
        for p in inspect.signature(func).parameters.values()
        if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
    ]
    missing = sorted(set(params) - documented_parameters(doc))
    assert not missing, f"nilpotent.{name}: no 'name : type' entry for {missing}"


@pytest.mark.parametrize("name", sorted(n for n in nilpotent.__all__ if n != "__version__"))
def test_every_public_class_and_function_has_a_docstring(name):
    obj = getattr(nilpotent, name)
    if callable(obj):
        assert inspect.getdoc(obj), f"nilpotent.{name} has no docstring"


# --- names follow docs/conventions.md ------------------------------------------------------

#: Names the convention replaces, with the conventional one.
_NOT_CONVENTIONAL = {
    "system": "sys",
    "timepts": "times",
    "t_eval": "times",
    "initial_state": "x0",
    "x_0": "x0",
    "p": "point",
}


@pytest.mark.parametrize("name", _public_functions())
def test_parameter_names_follow_the_convention(name):
    func = getattr(nilpotent, name)
    params = inspect.signature(func).parameters
    hints = {k: str(v.annotation) for k, v in params.items()}
    for pname, hint in hints.items():
        if "ControlSystem" in hint and "CompiledSystem" not in hint:
            assert pname == "sys", f"nilpotent.{name}: a ControlSystem argument is named 'sys'"
        if pname in _NOT_CONVENTIONAL and "ControlSystem" in hint:
            pytest.fail(f"nilpotent.{name}({pname}): write {_NOT_CONVENTIONAL[pname]}")
        if pname in ("timepts", "t_eval", "initial_state", "x_0", "p"):
            pytest.fail(f"nilpotent.{name}({pname}): write {_NOT_CONVENTIONAL[pname]}")


def test_every_to_json_is_strict():
    """Every ``to_json`` returns through the strict encoder (``json_object`` or
    ``plan_json``, both :func:`nilpotent.strict_json.json_safe`): no NaN/Infinity ever."""
    loose = []
    for path in sorted(INIT.parent.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for func in ast.walk(tree):
            if not (isinstance(func, ast.FunctionDef) and func.name == "to_json"):
                continue
            nested = {id(n) for d in ast.walk(func) if isinstance(d, ast.FunctionDef | ast.Lambda)
                      and d is not func for n in ast.walk(d)}
            for node in ast.walk(func):
                if isinstance(node, ast.Return) and id(node) not in nested and not (
                        isinstance(node.value, ast.Call)
                        and getattr(node.value.func, "id", "") in ("json_object", "plan_json")):
                    loose.append(f"{path.relative_to(INIT.parent)}:{node.lineno}")
    assert loose == []
    from nilpotent.strict_json import json_object

    assert json_object({"a": [1.0, float("inf")]}) == {
        "a": [1.0, None],
        "undefined": {"paths": ["a[1]"], "why": json_object({"x": float("nan")})["undefined"][
            "why"]},
    }
