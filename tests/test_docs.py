"""The documentation: the tutorial notebook is kept without outputs (it is executed by
``make test`` through nbmake), and the public docstrings say what they raise (a ``Raises``
section wherever the body raises) and document every field of the public dataclasses.
The parameters of public functions are checked by ``tests/test_public_api.py``."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_tutorial_notebook_is_stored_without_outputs():
    nb = json.loads((ROOT / "docs" / "tutorial.ipynb").read_text(encoding="utf-8"))
    code = [c for c in nb["cells"] if c["cell_type"] == "code"]
    assert code, "the tutorial has code cells"
    for cell in code:
        assert cell["outputs"] == [] and cell["execution_count"] is None, cell["source"]


# --- the public docstrings (numpydoc) --------------------------------------------------------

import ast  # noqa: E402
import dataclasses  # noqa: E402
import inspect  # noqa: E402
import re  # noqa: E402
import textwrap  # noqa: E402

import pytest  # noqa: E402

import nilpotent  # noqa: E402

_SECTION = re.compile(r"^(\w[\w ]*)\n-{3,}\s*$", re.MULTILINE)


def _sections(doc: str) -> dict[str, str]:
    """numpydoc sections of a docstring: title -> body."""
    heads = list(_SECTION.finditer(doc))
    return {
        m.group(1).strip(): doc[m.end() : heads[k + 1].start() if k + 1 < len(heads) else None]
        for k, m in enumerate(heads)
    }


def _entries(body: str) -> set[str]:
    """The names of the ``name : type`` entries of a section (``a, b : float`` gives both)."""
    names: set[str] = set()
    for line in body.splitlines():
        m = re.match(r"^([*\w][\w*]*(?:\s*,\s*[*\w][\w*]*)*)\s*(?::.*)?$", line)
        if m and not line.startswith(" "):
            names.update(n.strip().lstrip("*") for n in m.group(1).split(","))
    return names


def _raises(func) -> bool:
    """Whether the body of ``func`` (not of functions nested in it) has a ``raise``."""
    try:
        source = textwrap.dedent(inspect.getsource(func))
    except (OSError, TypeError):
        return False
    tree = ast.parse(source).body[0]

    def walk(node) -> bool:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
                continue
            if isinstance(child, ast.Raise) or walk(child):
                return True
        return False

    return walk(tree)


def _public():
    for name in sorted(nilpotent.__all__):
        obj = getattr(nilpotent, name)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            yield name, obj


def _problems(name: str, obj) -> list[str]:
    doc = inspect.getdoc(obj) or ""
    sections = _sections(doc)
    out = []
    if inspect.isfunction(obj):
        # every parameter's entry: tests/test_public_api.py (one check, not two)
        if _raises(obj) and "Raises" not in sections:
            out.append("raises but has no Raises section")
    else:
        documented = _entries(sections.get("Parameters", "")) | _entries(
            sections.get("Attributes", "")
        )
        if dataclasses.is_dataclass(obj):
            fields = [f.name for f in dataclasses.fields(obj) if not f.name.startswith("_")]
            out += [f"field {f!r} has no numpydoc entry" for f in fields if f not in documented]
        own = [getattr(obj, m) for m in ("__init__", "__post_init__") if m in vars(obj)]
        if any(_raises(m) for m in own) and "Raises" not in sections:
            out.append("its constructor raises but the class has no Raises section")
    return [f"nilpotent.{name}: {p}" for p in out]


@pytest.mark.parametrize("name, obj", list(_public()), ids=[n for n, _ in _public()])
def test_public_docstring_documents_parameters_and_raises(name, obj):
    assert _problems(name, obj) == []


def test_the_entry_matcher_wants_entries_not_substrings():
    body = "point : tuple\n    The point, not the points.\nstart, goal : float\n    Ends.\n"
    assert _entries(body) == {"point", "start", "goal"}
    assert "points" not in _entries(body) and "The" not in _entries(body)
