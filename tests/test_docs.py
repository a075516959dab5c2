"""The documentation: the tutorial notebook is kept without outputs (it is executed by
``make test`` through nbmake), and the public docstrings say what they raise (a ``Raises``
section wherever the body raises) and document every field of the public dataclasses.
The parameters of public functions are checked by ``tests/test_public_api.py``."""

from __future__ import annotations

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


# --- the site stands alone -------------------------------------------------------------

#: What a page must not name: the project's design notes and a developer's folders are not
#: part of the repository or of the site (their content is on mathematics.md and
#: interface.md).
_OUTSIDE = ("../shared", "/work/", "/home/", "/Users/", "MATH.md", "INTERFACE.md")

#: An inline markdown link ``[text](target)`` (reference-style ``[text][id]`` links are
#: autorefs of the API and checked by the strict site build).
_LINK = re.compile(r"\[[^\]\n]*\]\((?P<target>[^)\s]+)\)")


def _doc_sources() -> list[Path]:
    """The pages of the site and the README."""
    pages = [p for p in (ROOT / "docs").rglob("*") if p.suffix in (".md", ".ipynb")]
    return [*sorted(pages), ROOT / "README.md"]


_CODE_OR_MATH = re.compile(
    r"^(?P<f>```|~~~).*?^(?P=f)|`[^`\n]*`|\$\$.*?\$\$|\$[^$\n]*\$", re.DOTALL | re.MULTILINE
)


def _prose(path: Path) -> str:
    """The text of a page where links can be: no code, no formulas (``[X, Y](p)`` is
    mathematics); of a notebook, its markdown cells."""
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".ipynb":
        cells = json.loads(text)["cells"]
        text = "\n\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "markdown")
    return _CODE_OR_MATH.sub(" ", text)


def _hook():
    """The site's hook, ``docs/hooks/generated_pages.py``, as a module."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "generated_pages", ROOT / "docs" / "hooks" / "generated_pages.py"
    )
    assert spec and spec.loader
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)
    return hook


def _generated_pages() -> set[str]:
    """The pages ``docs/hooks/generated_pages.py`` adds when the site is built."""
    hook = _hook()
    api = {f"api/{key}.md" for key, *_ in hook.API_TOPICS} | {"api/index.md"}
    return {"cli.md", "tutorial-notebook.md", *api}


def test_docs_and_readme_name_nothing_outside_the_repository():
    found = [
        f"{path.relative_to(ROOT)}:{n}: {needle}"
        for path in _doc_sources()
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        for needle in _OUTSIDE
        if needle in line
    ]
    assert found == []


def test_the_code_names_no_design_note_outside_the_repository():
    """The docstrings (shown by ``help()`` and on the API pages), the messages and the
    examples name the site's pages, never the project's design notes."""
    sources = [*(ROOT / "src").rglob("*.py"), *(ROOT / "examples").rglob("*.py")]
    found = [
        f"{path.relative_to(ROOT)}:{n}: {needle}"
        for path in sorted(sources)
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        for needle in _OUTSIDE
        if needle in line
    ]
    assert found == []


def test_the_docstrings_mentions_of_sections_exist():
    """``the mathematics page, §N`` and ``the interface page, "Heading"`` in the code name
    a section that exists (the site's hook links them, and fails the build otherwise)."""
    hook = _hook()
    math, interface, _ = hook._headings()
    assert set(math) == {str(k) for k in range(1, len(math) + 1)} and len(math) >= 8
    found, missing = 0, []
    for path in sorted((ROOT / "src").rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        for m in hook._PAGE_REF.finditer(text):
            found += 1
            if m.group("section") and m.group("section") not in math:
                missing.append(f"{path.relative_to(ROOT)}: {m.group(0)}")
            heading = m.group("heading")
            if heading and " ".join(heading.split()) not in interface:
                missing.append(f"{path.relative_to(ROOT)}: {m.group(0)}")
    assert missing == []
    assert found > 20


def test_every_relative_link_of_the_docs_and_readme_resolves():
    docs = ROOT / "docs"
    generated = _generated_pages()
    broken = []
    checked = 0
    for path in _doc_sources():
        for m in _LINK.finditer(_prose(path)):
            target = m.group("target").split("#", 1)[0]
            if not target or "://" in target or target.startswith("mailto:"):
                continue
            checked += 1
            resolved = (path.parent / target).resolve()
            ok = resolved.exists()
            if not ok and resolved.is_relative_to(docs):
                ok = resolved.relative_to(docs).as_posix() in generated
            if not ok:
                broken.append(f"{path.relative_to(ROOT)}: {m.group(0)}")
    assert broken == []
    assert checked > 50  # the pages do link to one another


def test_the_link_checker_sees_a_broken_link(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("[there](missing.md) [ok](page.md) [web](https://example.org)")
    targets = [m.group("target") for m in _LINK.finditer(page.read_text())]
    assert targets == ["missing.md", "page.md", "https://example.org"]
    assert not (tmp_path / "missing.md").exists() and (tmp_path / "page.md").exists()


def test_mentions_of_other_pages_are_links_not_file_names():
    """``docs/tutorial.md`` written as code is a dead end in a browser: a page names
    another page with a link."""
    name = re.compile(r"`(?:docs/)?[\w-]+\.(?:md|ipynb)`")
    found = [
        f"{path.relative_to(ROOT)}:{n}: {m.group(0)}"
        for path in _doc_sources()
        if path.suffix == ".md"
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        for m in name.finditer(line)
        if not m.group(0).startswith("`benchmarks/")
    ]
    assert found == []


_CODE = re.compile(r"^(?P<f>```|~~~).*?^(?P=f)|`[^`\n]*`", re.DOTALL | re.MULTILINE)
_FORMULA = re.compile(r"\$\$(?P<display>.+?)\$\$|\$(?P<inline>[^$\n]+)\$", re.DOTALL)


def _formulas(path: Path) -> list[str]:
    """The ``$...$`` and ``$$...$$`` formulas of a page (of a notebook, of its markdown),
    outside code."""
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".ipynb":
        cells = json.loads(text)["cells"]
        text = "\n\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "markdown")
    text = _CODE.sub(" ", text)
    return [m.group("display") or m.group("inline") for m in _FORMULA.finditer(text)]


def _mathml_problems(latex: str) -> list[str]:
    """What ``latex2mathml`` (the site's typesetter) silently gets wrong: a command it
    does not know left as text, ``&`` outside an ``array``/matrix (``aligned``) as a
    letter, a fence with a subscript (``\\end{pmatrix}_{i}``)."""
    from nilpotent.typeset import mathml

    try:
        out = mathml(latex, display=True)
    except Exception as exc:  # the site would show the source
        return [f"{type(exc).__name__}: {exc}"]
    text = re.sub(r"<annotation.*?</annotation>", "", out, flags=re.DOTALL)
    problems = [f"raw {t!r}" for t in re.findall(r">([^<]*\\[A-Za-z]+[^<]*)<", text)]
    if re.search(r"<mi>&(?:amp;)?</mi>", text):
        problems.append("'&' as a letter")
    if re.search(r"<msub><mo>[^<]*</mo><mtable>", text):
        problems.append("a subscript on a fence")
    return problems


def test_every_formula_of_the_docs_typesets():
    found, bad = 0, []
    for path in _doc_sources():
        for latex in _formulas(path):
            found += 1
            where = f"{path.relative_to(ROOT)}: ${latex[:60]}$"
            bad += [f"{where}: {p}" for p in _mathml_problems(latex)]
    assert bad == []
    assert found > 500  # derivations are typeset, not code


def test_the_formula_check_sees_what_the_typesetter_gets_wrong():
    assert _mathml_problems(r"[X, Y] = DY\cdot X - DX\cdot Y") == []
    assert _mathml_problems(r"\begin{aligned} a &= b \end{aligned}") != []
    assert _mathml_problems(r"\det\begin{pmatrix} a & b \end{pmatrix}_{i}") != []


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
