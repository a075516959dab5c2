"""mkdocs hook: the pages generated from the code, never copied by hand.

* ``cli.md``: the help of ``nilpotent`` and of each of its commands, as the
  commands print it (``--help``, through the CLI's own parser);
* ``api/*.md``: one mkdocstrings entry per name of ``nilpotent.__all__``, at the
  module that defines it (numpydoc docstrings), one page per topic (``API_TOPICS``)
  and an index of them all;
* ``tutorial-notebook.md``: the cells of ``docs/tutorial.ipynb`` (markdown as
  is, code as Python blocks) with the outputs of a fresh run (figures as PNG,
  results as their typeset HTML) and a link to the notebook itself;

the mathematics of every page typeset as MathML, the docstrings' Sphinx-style
cross-references and their mentions of the site's pages made links
(:func:`on_page_content`); the README's links, on the
home page, made relative to the site (:func:`on_page_markdown`).
"""

from __future__ import annotations

import html
import inspect
import re
from pathlib import Path
from typing import Any

from mkdocs.structure.files import File

HELP_ENV = {"COLUMNS": "100", "NO_COLOR": "1", "TERM": "dumb"}


def _help(args: list[str]) -> str:
    from typer.testing import CliRunner

    from nilpotent.cli.app import app

    result = CliRunner().invoke(app, [*args, "--help"], env=HELP_ENV, prog_name="nilpotent")
    if result.exit_code != 0:
        raise RuntimeError(f"`nilpotent {' '.join(args)} --help` failed: {result.output}")
    return result.output.rstrip()


def cli_page() -> str:
    import typer

    from nilpotent.cli.app import app

    names = list(typer.main.get_command(app).commands)  # type: ignore[attr-defined]
    parts = [
        "# Command-line reference\n",
        "Generated from the commands' own `--help` when the site is built.\n",
        "```text\n" + _help([]) + "\n```\n",
    ]
    for name in names:
        parts.append(f"## `nilpotent {name}`\n\n```text\n{_help([name])}\n```\n")
    return "\n".join(parts)


#: The pages of the API reference, in order: (file, title, what it covers, module prefixes).
#: A name of ``nilpotent.__all__`` goes to the first page one of whose prefixes starts its
#: module; one no prefix claims goes to "Other" (so a new name is never left out).
API_TOPICS: tuple[tuple[str, str, str, tuple[str, ...]], ...] = (
    (
        "systems",
        "Systems and analysis",
        "control systems, brackets and the filtration (growth vector, weights, singular locus)",
        (
            "nilpotent.core.model.system",
            "nilpotent.core.analysis.filtration",
            "nilpotent.core.lie.brackets",
            "nilpotent.core.analysis.orbit",
        ),
    ),
    (
        "coordinates",
        "Coordinates and approximation",
        "privileged coordinates, non-holonomic orders, the nilpotent approximation and its "
        "certificate",
        (
            "nilpotent.core.coordinates.privileged",
            "nilpotent.core.coordinates.approximation",
            "nilpotent.core.coordinates.orders",
            "nilpotent.core.coordinates.jets",
        ),
    ),
    (
        "simulation",
        "Simulation",
        "compiled fields, input signals, batched integration, bracket motions and scaling",
        (
            "nilpotent.numeric",
            "nilpotent.simulation.comparison",
            "nilpotent.simulation.scaling",
            "nilpotent.simulation.trajectory",
        ),
    ),
    (
        "sweeps",
        "Sweeps",
        "many bracket motions in batches, locally or with Dask",
        ("nilpotent.simulation.sweep",),
    ),
    (
        "planning",
        "Planning",
        "steering with the approximation, limits, outlines, worlds, closed-loop execution",
        ("nilpotent.planning", "nilpotent.core.model.outline"),
    ),
    (
        "models",
        "Models and input",
        "built-in models, model files, points and the expression grammar",
        (
            "nilpotent.models",
            "nilpotent.core.model.modelfile",
            "nilpotent.core.model.points",
            "nilpotent.core.model.expressions",
        ),
    ),
    ("paper", "The paper", "the trident snake paper reproduced and audited", ("nilpotent.report",)),
    (
        "errors",
        "Errors",
        "the exceptions a user can cause, with their `kind`",
        ("nilpotent.errors",),
    ),
)


#: Objects outside ``nilpotent.__all__`` that the public docstrings refer to (results'
#: parts, the plotting functions behind ``.plot()``): documented under "Supporting
#: objects" of their topic so that the references resolve.
API_SUPPORTING: dict[str, tuple[str, ...]] = {
    "systems": (
        "nilpotent.core.analysis.orbit.OrbitCertificate",
        "nilpotent.core.analysis.singular.singular_set",
        "nilpotent.core.analysis.singular.invariant_hypersurface",
    ),
    "coordinates": ("nilpotent.core.coordinates.jets.Poly",),
    "simulation": (
        "nilpotent.numeric.integrate.BatchSolution",
        "nilpotent.numeric.integrate.Status",
        "nilpotent.numeric.signals.FunctionSignal",
        "nilpotent.numeric.sampled.as_signal",
        "nilpotent.numeric.engines.ENGINES",
        "nilpotent.numeric.settings.DEFAULT_SETTINGS",
        "nilpotent.simulation.comparison.BRACKET_SETTINGS",
        "nilpotent.viz.simulation.plot_comparison",
        "nilpotent.viz.simulation.plot_scaling_study",
    ),
    "sweeps": (
        "nilpotent.viz.simulation.plot_sweep",
        "nilpotent.simulation.sweep.SWEEP_SETTINGS",
        "nilpotent.progress.ProgressEvent",
        "nilpotent.progress.ProgressCallback",
    ),
    "planning": (
        "nilpotent.planning.nilpotent.METHODS",
        "nilpotent.planning.simulation.PLANNING_SETTINGS",
        "nilpotent.planning.world.builtin_worlds",
        "nilpotent.viz.plan.plot_plan",
        "nilpotent.planning.iterative.PlanFigure",
        "nilpotent.viz.plan_world.plot_plan_world",
        "nilpotent.viz.plan_world.animate_plan_world",
        "nilpotent.planning.timing.TimedTrajectory",
        "nilpotent.planning.timing.InputBounds",
        "nilpotent.planning.timing.retime",
    ),
}


def api_groups() -> dict[str, list[tuple[str, object]]]:
    """The names of ``nilpotent.__all__`` by API page (``API_TOPICS``; ``"other"`` last)."""
    import nilpotent

    groups: dict[str, list[tuple[str, object]]] = {t[0]: [] for t in API_TOPICS}
    groups["other"] = []
    for name in sorted(nilpotent.__all__):
        obj = getattr(nilpotent, name)
        module = getattr(obj, "__module__", "") if _documented(obj) else ""
        if name == "MODELS":
            module = "nilpotent.models"
        page = next((t[0] for t in API_TOPICS if any(module.startswith(p) for p in t[3])), "other")
        groups[page].append((name, obj))
    return groups


def _documented(obj: object) -> bool:
    """A class or a function (also one wrapped by a cache), which mkdocstrings documents."""
    return inspect.isclass(obj) or inspect.isfunction(inspect.unwrap(obj))  # type: ignore[arg-type]


def api_pages() -> dict[str, str]:
    """``api/index.md`` (the topics and every name) and one page per topic."""
    import nilpotent

    groups = api_groups()
    titles = {t[0]: (t[1], t[2]) for t in API_TOPICS}
    titles["other"] = ("Other", "names no topic claims")
    index = [
        "# API reference\n",
        "Every name of `nilpotent.__all__`, from its docstring (numpydoc), at the module "
        "that defines it. `import nilpotent as nil` and call `nil.<name>`; "
        f"`nil.__version__` is `{nilpotent.__version__!r}`. The command line and its JSON "
        "are on [the interface](../interface.md).\n",
        "| page | what it covers | names |",
        "|---|---|---|",
    ]
    pages: dict[str, str] = {}
    shown: dict[int, str] = {}
    for key, members in groups.items():
        members = [(n, o) for n, o in members if n != "__version__"]
        if not members:
            continue
        title, what = titles[key]
        names = ", ".join(_index_link(key, n, o) for n, o in members)
        index.append(f"| [{title}]({key}.md) | {what} | {names} |")
        parts = [f"# {title}\n", f"{what[0].upper()}{what[1:]}.\n"]
        for name, obj in members:
            if id(obj) in shown:  # a second name (named like a command): one entry per object
                first = shown[id(obj)]
                target = f"[`{first}`][{_path(obj)}]" if _documented(obj) else f"`{first}`"
                parts.append(f"## `{name}`\n\nThe same function as {target}.\n")
                continue
            shown[id(obj)] = name
            if not _documented(obj):
                parts.append(f"## `{name}`\n\n{_describe(name, obj)}\n")
                continue
            parts.append(
                f"::: {_path(obj)}\n"
                "    options:\n      show_root_heading: true\n      heading_level: 2\n"
                "      show_root_full_path: false\n"
            )
        if API_SUPPORTING.get(key):
            parts.append(
                "## Supporting objects\n\nNot in `nilpotent.__all__`: import them from their "
                "module. The names above refer to them.\n"
            )
            for path in API_SUPPORTING[key]:
                parts.append(
                    f"::: {path}\n"
                    "    options:\n      show_root_heading: true\n      heading_level: 3\n"
                    "      show_root_full_path: true\n"
                )
        if key == "errors":  # every error class, with its kind, not only the base
            parts.append(
                "## All error classes\n\n::: nilpotent.errors\n"
                "    options:\n      show_root_heading: false\n      heading_level: 3\n"
                "      members_order: source\n      show_bases: true\n"
                "      filters: ['!^NilpotentError$']\n"
            )
        pages[f"api/{key}.md"] = "\n".join(parts)
    pages["api/index.md"] = "\n".join(index) + "\n"
    return pages


def _describe(name: str, obj: object) -> str:
    from collections.abc import Mapping

    if isinstance(obj, Mapping):
        keys = ", ".join(f"`{k}`" for k in obj)
        return f"`nilpotent.{name}`: a read-only mapping with the keys {keys}."
    return f"`nilpotent.{name}` = `{obj!r}`"


def _path(obj: object) -> str:
    return f"{obj.__module__}.{obj.__qualname__}"  # type: ignore[attr-defined]


def _index_link(page: str, name: str, obj: object) -> str:
    if not _documented(obj):
        return f"[`{name}`]({page}.md#{name.lower()})"
    return f"[`{name}`][{_path(obj)}]"


def executed(text: str) -> Any:
    """The notebook run top to bottom in a fresh kernel (``nbclient``), in a temporary
    folder; a cell that raises fails the build (the notebook is broken)."""
    import tempfile

    import nbclient
    import nbformat

    notebook = nbformat.reads(text, as_version=4)
    with tempfile.TemporaryDirectory() as folder:
        nbclient.NotebookClient(
            notebook, timeout=600, kernel_name="python3", resources={"metadata": {"path": folder}}
        ).execute()
    return notebook


def _output(output: dict) -> str:
    """One output of a code cell as the page shows it: a figure as its PNG, a result as
    its HTML (typeset MathML), else its text."""
    kind = output.get("output_type")
    if kind == "stream":
        return "```text\n" + "".join(output["text"]).rstrip() + "\n```\n"
    data = output.get("data", {})
    if "image/png" in data:
        png = "".join(data["image/png"]).replace("\n", "")
        img = f'<img alt="figure" src="data:image/png;base64,{png}">'
        return f'<div class="nb-output">{img}</div>\n'
    if "text/html" in data:
        body = "".join(data["text/html"]).strip()
        return f'<div class="nb-output">\n{body}\n</div>\n'
    if "text/plain" in data:
        return "```text\n" + "".join(data["text/plain"]).rstrip() + "\n```\n"
    return ""


def notebook_page(path: Path) -> str:
    """The tutorial notebook's cells with the outputs of a fresh run (``executed``)."""
    nb = executed(path.read_text(encoding="utf-8"))
    parts = [
        "_This page shows [the notebook](tutorial.ipynb) with the outputs of a run made "
        "when the site was built (download it and run it in Jupyter: the results display "
        "the same way). The test suite executes it too._\n"
    ]
    for cell in nb["cells"]:
        source = "".join(cell["source"])
        if cell["cell_type"] == "markdown":
            parts.append(source + "\n")
        elif cell["cell_type"] == "code":
            parts.append("```python\n" + source + "\n```\n")
            parts.extend(_output(o) for o in cell.get("outputs", []))
    return "\n".join(parts)


def on_files(files, config):
    docs = Path(config["docs_dir"])
    pages = {
        "cli.md": cli_page(),
        "tutorial-notebook.md": notebook_page(docs / "tutorial.ipynb"),
        **api_pages(),
    }
    for name, content in pages.items():
        files.append(File.generated(config, name, content=content))
    return files


_MATH = re.compile(r'<(span|div) class="arithmatex">\\[(\[](.*?)\\[)\]]</\1>', re.DOTALL)


_ROLE = re.compile(r":(?:func|class|mod|meth|attr|data|exc|obj):<code>")

#: A Sphinx-style cross-reference of the docstrings, after markdown: a role, then
#: ``<code>~dotted.path</code>`` (shown as its last part) or ``<code>dotted.path</code>``.
_XREF = re.compile(
    r"(?P<role>:(?:func|class|mod|meth|attr|data|exc|obj):)?"
    r"<code>(?P<tilde>~)?(?P<path>[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*)(?P<call>\(\))?</code>"
)

#: A docstring's mention of a page of the site (:func:`page_references`).
_PAGE_REF = re.compile(
    r"[Tt]he\s+(?P<page>mathematics|interface|Model\s+files|World\s+files)\s+page"
    r"(?:\s+of\s+the\s+documentation)?"
    r'(?:,\s*(?:§(?P<section>\d+)(?:[–-]\d+)?|(?:"|&quot;)(?P<heading>[^"&<]+)(?:"|&quot;)))?'
)
_PAGES = {
    "mathematics": "mathematics.md",
    "interface": "interface.md",
    "model files": "model-files.md",
    "world files": "worlds.md",
}
#: A JSON schema's name in code (``nilpotent/plan@1``), not already in a link.
_SCHEMA = re.compile(r"(?<!>)<code>(?P<schema>nilpotent/[\w-]+@\d+)</code>(?!</a>)")
_HEADING = re.compile(r"^#+ (?P<title>.*?) \{#(?P<id>[\w-]+)\}\s*$", re.MULTILINE)


def _headings() -> tuple[dict[str, str], dict[str, str], dict[str, str]]:
    """``mathematics.md``'s numbered sections (``"3" -> "order"``), ``interface.md``'s
    headings (title -> id) and its schema sections (``"nilpotent/plan@1" -> "plan"``)."""
    docs = Path(__file__).resolve().parents[1]
    math = {}
    for m in _HEADING.finditer((docs / "mathematics.md").read_text(encoding="utf-8")):
        number, _, _ = m.group("title").partition(". ")
        if number.isdigit():
            math[number] = m.group("id")
    interface, schemas = {}, {}
    for m in _HEADING.finditer((docs / "interface.md").read_text(encoding="utf-8")):
        title = m.group("title")
        interface[title] = m.group("id")
        if title.startswith("`nilpotent/"):
            schemas[title.strip("`")] = m.group("id")
    return math, interface, schemas


def _short_names() -> dict[str, str]:
    """``name -> module.qualname`` of the documented names of ``nilpotent.__all__``."""
    import nilpotent

    return {
        n: _path(getattr(nilpotent, n))
        for n in nilpotent.__all__
        if _documented(getattr(nilpotent, n))
    }


def cross_references(html_text: str) -> str:
    """Sphinx roles of the docstrings as autorefs links (``optional``: an object the site
    does not document stays code, without a warning).  ``:func:`~a.b.c``` shows ``c``;
    ``:class:`Name``` of a public name links to where it is documented."""
    short = _short_names()

    def link(m: re.Match[str]) -> str:
        path, call = m.group("path"), m.group("call") or ""
        if path in short and m.group("role"):
            identifier = short[path]
        elif path.startswith("nilpotent.") and (m.group("role") or m.group("tilde")):
            identifier = path
        else:
            return m.group(0) if not m.group("role") else m.group(0)[len(m.group("role")) :]
        title = path.rsplit(".", 1)[-1] if m.group("tilde") else path
        return f'<autoref identifier="{identifier}" optional><code>{title}{call}</code></autoref>'

    return _XREF.sub(link, html_text)


def page_references(html_text: str, page) -> str:
    """The docstrings' mentions of the site's pages as links (on the API pages):
    ``the mathematics page, §N`` (a numbered section of ``mathematics.md``), ``the
    interface page`` (with ``, "Heading"``: that heading of ``interface.md``), ``the
    Model files page``, ``the World files page``; and every ``nilpotent/NAME@1`` schema
    in code to its section of ``interface.md``.  A section that does not exist fails the
    build (``ValueError``)."""
    from mkdocs.utils import get_relative_url

    if not page.url.startswith("api/"):
        return html_text
    math, interface, schemas = _headings()

    def url(target: str) -> str:
        path, _, anchor = target.partition("#")
        relative = get_relative_url(path.replace(".md", "/"), page.url)
        return relative + (f"#{anchor}" if anchor else "")

    def link(m: re.Match[str]) -> str:
        page_name = " ".join(m.group("page").split()).lower()
        target = _PAGES[page_name]
        section, heading = m.group("section"), m.group("heading")
        if section is not None:
            if page_name != "mathematics" or section not in math:
                raise ValueError(f"{page.url}: no section §{section} on the {page_name} page")
            target += f"#{math[section]}"
        elif heading is not None:
            key = " ".join(heading.split())
            if page_name != "interface" or key not in interface:
                raise ValueError(f"{page.url}: no heading {key!r} on the {page_name} page")
            target += f"#{interface[key]}"
        return f'<a href="{url(target)}">{m.group(0)}</a>'

    def schema(m: re.Match[str]) -> str:
        anchor = schemas.get(m.group("schema"))
        if anchor is None:
            raise ValueError(f"{page.url}: schema {m.group('schema')} is not on the interface page")
        return f'<a href="{url("interface.md#" + anchor)}">{m.group(0)}</a>'

    html_text = _PAGE_REF.sub(link, html_text)
    return _SCHEMA.sub(schema, html_text)


def on_page_content(html_text: str, page, config, files) -> str:
    r"""Resolve the docstrings' references and typeset the ``$...$`` of the pages as
    MathML (offline, no MathJax).

    ``pymdownx.arithmatex`` (generic mode) leaves ``\(...\)`` and ``\[...\]`` in
    ``arithmatex`` elements; each becomes the formula of
    :func:`nilpotent.typeset.formula_html` (MathML, with its LaTeX for copying).
    A formula ``latex2mathml`` cannot read stays as its source.
    """
    from nilpotent.typeset import formula_html

    def typeset(m: re.Match[str]) -> str:
        latex = html.unescape(m.group(2))
        try:
            return formula_html(latex, display=m.group(1) == "div")
        except Exception:  # latex2mathml does not know the construction: keep the source
            return m.group(0)

    html_text = cross_references(html_text)
    html_text = _ROLE.sub("<code>", html_text)  # roles left over (not a dotted name)
    html_text = page_references(html_text, page)
    return _MATH.sub(typeset, html_text)


#: A markdown link of the README to a file of the repository (``](docs/x.md)``,
#: ``](benchmarks/RESULTS.md)``): relative to the repository's root.
_README_LINK = re.compile(r"\[(?P<text>[^\]]+)\]\((?P<target>[^)#\s]+)(?P<anchor>#[^)\s]*)?\)")


def on_page_markdown(markdown: str, page, config, files) -> str:
    """The home page is the README: its links to ``docs/…`` are to the site's pages;
    its links to other files of the repository (not on the site) become their names."""
    if page.file.src_uri != "index.md":
        return markdown
    if markdown.strip() == '--8<-- "README.md"':  # before the snippets extension runs
        markdown = (Path(config["config_file_path"]).parent / "README.md").read_text("utf-8")

    def relink(m: re.Match[str]) -> str:
        target = m.group("target")
        if "://" in target:
            return m.group(0)
        if target.startswith("docs/"):
            return f"[{m.group('text')}]({target[5:]}{m.group('anchor') or ''})"
        text = m.group("text")
        return text if text.startswith("`") else f"`{text}`"

    return _README_LINK.sub(relink, markdown)
