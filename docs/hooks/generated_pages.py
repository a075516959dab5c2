"""mkdocs hook: the pages generated from the code, never copied by hand.

* ``cli.md``: the help of ``nilpotent`` and of each of its commands, as the
  commands print it (``--help``, through the CLI's own parser);
* ``api.md``: one mkdocstrings entry per name of ``nilpotent.__all__``, at the
  module that defines it (numpydoc docstrings);
* ``tutorial-notebook.md``: the cells of ``docs/tutorial.ipynb`` (markdown as
  is, code as Python blocks) with a link to the notebook itself;

and the mathematics of every page typeset as MathML (:func:`on_page_content`).
"""

from __future__ import annotations

import html
import inspect
import json
import re
from pathlib import Path

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


def api_page() -> str:
    import nilpotent

    parts = [
        "# API reference\n",
        "Every name of `nilpotent.__all__`, from its docstring (numpydoc), at the module "
        "that defines it. `import nilpotent as nil` and call `nil.<name>`.\n",
    ]
    shown: dict[int, str] = {}
    for name in sorted(nilpotent.__all__):
        obj = getattr(nilpotent, name)
        if not (inspect.isclass(obj) or inspect.isfunction(obj)):
            parts.append(f"## `{name}`\n\n`nilpotent.{name} = {obj!r}`\n")
            continue
        if id(obj) in shown:  # a second name (named like a command): one entry per object
            first = shown[id(obj)]
            parts.append(f"## `{name}`\n\nThe same function as [`{first}`](#{first}).\n")
            continue
        shown[id(obj)] = name
        parts.append(
            f"## `{name}`\n\n::: {obj.__module__}.{obj.__qualname__}\n"
            "    options:\n      show_root_heading: false\n      heading_level: 3\n"
        )
    return "\n".join(parts)


def notebook_page(path: Path) -> str:
    nb = json.loads(path.read_text(encoding="utf-8"))
    parts = [
        "_This page shows the cells of [the notebook](tutorial.ipynb) (download it and run "
        "it in Jupyter: the results display typeset). The test suite executes it._\n"
    ]
    for cell in nb["cells"]:
        source = "".join(cell["source"])
        if cell["cell_type"] == "markdown":
            parts.append(source + "\n")
        elif cell["cell_type"] == "code":
            parts.append("```python\n" + source + "\n```\n")
    return "\n".join(parts)


def on_files(files, config):
    docs = Path(config["docs_dir"])
    pages = {
        "cli.md": cli_page(),
        "api.md": api_page(),
        "tutorial-notebook.md": notebook_page(docs / "tutorial.ipynb"),
    }
    for name, content in pages.items():
        files.append(File.generated(config, name, content=content))
    return files


_MATH = re.compile(
    r'<(span|div) class="arithmatex">\\[(\[](.*?)\\[)\]]</\1>', re.DOTALL
)


_ROLE = re.compile(r":(?:func|class|mod|meth|attr|data|exc|obj):<code>")


def on_page_content(html_text: str, page, config, files) -> str:
    r"""Typeset the ``$...$`` of the pages as MathML (offline, no MathJax).

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

    html_text = _ROLE.sub("<code>", html_text)  # Sphinx roles of the docstrings
    return _MATH.sub(typeset, html_text)
