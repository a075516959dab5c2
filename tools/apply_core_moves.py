"""Apply the module moves of ``tools/core_moves.txt`` to a tree (idempotent).

Usage::

    python tools/apply_core_moves.py [ROOT] [--map FILE] [--dry-run]

``ROOT`` defaults to the repository this script lives in.  Three passes:

1. **Files.**  A module of the map still at its old path (``src/nilpotent/core/x.py``,
   e.g. brought back by a merge of a branch that edited or created it there) is moved
   to its new path with ``git mv`` (plain rename outside git).  Where both exist the
   script stops and names them: merge the two by hand first.
2. **Module paths.**  Every ``nilpotent.a.b`` of the map is replaced, as a whole
   dotted name, in ``.py``, ``.md``, ``.ipynb``, ``.yml``/``.yaml``, ``.toml`` and
   ``.txt`` files under ``src``, ``tests``, ``docs``, ``examples``, ``benchmarks``
   and in ``mkdocs.yml``/``README.md`` (import statements, ``import x as y``,
   monkeypatch strings, ``:mod:`` references, mkdocstrings' ``:::``); and
   ``from nilpotent.core import filtration`` becomes
   ``from nilpotent.core.analysis import filtration``.
3. **Names.**  A line ``old.module:name new.module:new_name`` of the map moves a
   name: in ``.py`` files, ``from old.module import name`` is split so that the name
   comes from ``new.module``; when ``new_name`` differs, the name is renamed (as a
   whole word) in the files that import it and in the module that defines it.

With ``--resolve-imports REF`` (after ``git merge REF`` stopped on conflicts; the
markers are re-made with the ancestor, ``git checkout --conflict=diff3``), a
conflict hunk where ``REF`` only rewrote paths takes the other side, rewritten;
a hunk whose two sides are import statements only takes the side being merged
into (``<<<<<<<``, the old paths: the passes above rewrite them); every other
hunk is left for a person, and listed.  Then, for each name
``ruff`` finds undefined (F821) in ``src``/``tests``, the import that binds it in
``REF``'s version of the file is added back (an import only the merged side had).
Resolve the hunks left, run again with the same option, then ``ruff check --fix``.
A module left directly in ``src/nilpotent/core/`` (new on a merged branch) is
listed: add it to the map.

Run ``ruff check --fix --select I`` afterwards to sort the rewritten imports.
"""

from __future__ import annotations

import argparse
import ast
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
TEXT_SUFFIXES = {".py", ".md", ".ipynb", ".yml", ".yaml", ".toml", ".txt", ".cfg"}
TREES = ("src", "tests", "docs", "examples", "benchmarks")
TOP_FILES = ("mkdocs.yml", "README.md", "pyproject.toml")


def read_map(path: Path) -> tuple[list[tuple[str, str]], list[tuple[str, str, str, str]]]:
    """The module moves and the name moves of a map file (``#`` starts a comment)."""
    modules: list[tuple[str, str]] = []
    names: list[tuple[str, str, str, str]] = []
    for k, raw in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split()
        if len(parts) != 2:
            raise SystemExit(f"{path}:{k}: expected two fields, got {raw!r}")
        old, new = parts
        if ":" in old:
            (om, on), (nm, nn) = old.split(":"), new.split(":")
            names.append((om, on, nm, nn))
        else:
            modules.append((old, new))
    return modules, names


def module_file(root: Path, module: str) -> Path:
    return root / "src" / Path(*module.split(".")).with_suffix(".py")


def files(root: Path) -> list[Path]:
    out = [root / f for f in TOP_FILES if (root / f).is_file()]
    for tree in TREES:
        base = root / tree
        if base.is_dir():
            out += sorted(
                p for p in base.rglob("*")
                if p.is_file() and p.suffix in TEXT_SUFFIXES and "__pycache__" not in p.parts
                and "tools" not in p.relative_to(root).parts[:1]
            )
    return out


def move_files(root: Path, modules: list[tuple[str, str]], dry: bool) -> list[str]:
    done = []
    for old, new in modules:
        src, dst = module_file(root, old), module_file(root, new)
        if not src.exists():
            continue
        if dst.exists():
            raise SystemExit(f"both {src} and {dst} exist: merge them by hand, then re-run")
        done.append(f"move {src.relative_to(root)} -> {dst.relative_to(root)}")
        if dry:
            continue
        dst.parent.mkdir(parents=True, exist_ok=True)
        tracked = subprocess.run(
            ["git", "-C", str(root), "ls-files", "--error-unmatch", str(src)],
            capture_output=True,
        ).returncode == 0
        if tracked:
            subprocess.run(["git", "-C", str(root), "mv", str(src), str(dst)], check=True)
        else:
            shutil.move(src, dst)
    return done


def rewrite_modules(text: str, modules: list[tuple[str, str]]) -> str:
    for old, new in modules:
        text = re.sub(rf"(?<![\w.]){re.escape(old)}(?![\w])", new, text)
        parent, leaf = old.rsplit(".", 1)
        new_parent, new_leaf = new.rsplit(".", 1)
        # ``from nilpotent.core import filtration [as f]`` (alone on its statement)
        text = re.sub(
            rf"^(\s*)from {re.escape(parent)} import {re.escape(leaf)}\b"
            r"(?! *,)(?=[ \t]*(as \w+)?[ \t]*$)",
            rf"\1from {new_parent} import {new_leaf}",
            text,
            flags=re.M,
        )
    return text


def _statement_text(indent: str, module: str, aliases: list[ast.alias]) -> str:
    names = [a.name + (f" as {a.asname}" if a.asname else "") for a in aliases]
    one = f"{indent}from {module} import {', '.join(names)}"
    if len(one) <= 99:
        return one
    body = "".join(f"{indent}    {n},\n" for n in names)
    return f"{indent}from {module} import (\n{body}{indent})"


def rewrite_names(
    text: str, names: list[tuple[str, str, str, str]]
) -> tuple[str, set[tuple[str, str]]]:
    """Split ``from old import name`` statements; returns the text and the renames it needs."""
    try:
        tree = ast.parse(text)
    except SyntaxError:
        return text, set()
    moved = {(om, on): (nm, nn) for om, on, nm, nn in names}
    renamed = {(nm, nn): on for om, on, nm, nn in names if on != nn}
    lines = text.splitlines(keepends=True)
    renames: set[tuple[str, str]] = set()
    edits = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.ImportFrom) or node.level or not node.module:
            continue
        # already the new name (a merged import line): rename what is left of the old one
        renames |= {(renamed[(node.module, a.name)], a.name) for a in node.names
                    if (node.module, a.name) in renamed}
        hits = [a for a in node.names if (node.module, a.name) in moved]
        if not hits:
            continue
        indent = re.match(r"\s*", lines[node.lineno - 1]).group(0)
        keep = [a for a in node.names if (node.module, a.name) not in moved]
        groups: dict[str, list[ast.alias]] = {}
        for a in hits:
            nm, nn = moved[(node.module, a.name)]
            if nn != a.name:
                renames.add((a.name, nn))
            groups.setdefault(nm, []).append(ast.alias(nn, a.asname))
        stmts = [_statement_text(indent, node.module, keep)] if keep else []
        stmts += [_statement_text(indent, m, al) for m, al in groups.items()]
        edits.append((node.lineno, node.end_lineno or node.lineno, "\n".join(stmts) + "\n"))
    for start, end, new in sorted(edits, reverse=True):
        lines[start - 1 : end] = [new]
    return "".join(lines), renames


def rename_words(text: str, renames: set[tuple[str, str]]) -> str:
    for old, new in renames:
        text = re.sub(rf"(?<![\w.]){re.escape(old)}\b", new, text)
    return text


_IMPORT_LINE = re.compile(
    r"^\s*(from [\w.]+ import .*|import [\w., ]+|[\w]+( as \w+)?,?|\)|#.*|)\s*$"
)


def resolve_conflicts(text: str, rewrite) -> tuple[str, int, int]:
    """Resolve the conflict hunks (``diff3`` style: ours ||| base === theirs) that are this
    script's business; returns ``(text, resolved, left)``.

    A hunk where the merged branch only rewrote paths (``rewrite(base) == theirs``) takes
    our side, rewritten; a hunk of import lines only takes our side (the passes after
    rewrite it; what it lacks is taken back later).  Others are left.
    """
    out: list[str] = []
    lines = text.splitlines(keepends=True)
    k = resolved = left = 0
    while k < len(lines):
        if not lines[k].startswith("<<<<<<<"):
            out.append(lines[k])
            k += 1
            continue
        mid = next(j for j in range(k, len(lines)) if lines[j].startswith("======="))
        end = next(j for j in range(mid, len(lines)) if lines[j].startswith(">>>>>>>"))
        bar = next((j for j in range(k, mid) if lines[j].startswith("|||||||")), mid)
        ours, base, theirs = lines[k + 1 : bar], lines[bar + 1 : mid], lines[mid + 1 : end]
        if bar < mid and rewrite("".join(base)) == "".join(theirs):
            out.append(rewrite("".join(ours)))
            resolved += 1
        elif all(_IMPORT_LINE.match(x) for x in ours + theirs):
            out.extend(ours)
            resolved += 1
        else:
            out.extend(lines[k : end + 1])
            left += 1
        k = end + 1
    return "".join(out), resolved, left


def undefined_names(root: Path) -> dict[Path, set[str]]:
    """``ruff``'s F821 (undefined name) findings under ``src`` and ``tests``, by file."""
    ruff = shutil.which("ruff") or str(Path(sys.executable).with_name("ruff"))
    out = subprocess.run(
        [ruff, "check", "--select", "F821", "--output-format", "json", "--exit-zero",
         *(str(root / t) for t in ("src", "tests") if (root / t).is_dir())],
        capture_output=True, text=True, check=True,
    )
    found: dict[Path, set[str]] = {}
    for item in json.loads(out.stdout or "[]"):
        m = re.search(r"`([^`]+)`", item["message"])
        if m:
            found.setdefault(Path(item["filename"]), set()).add(m.group(1))
    return found


def take_back_imports(path: Path, names: set[str], ref_text: str) -> list[str]:
    """Add the top-level imports of ``ref_text`` that bind ``names`` (undefined in ``path``)."""
    try:
        ref = ast.parse(ref_text)
        tree = ast.parse(path.read_text(encoding="utf-8"))
    except SyntaxError:
        return []
    added = [
        f"from {stmt.module} import {a.name}" + (f" as {a.asname}" if a.asname else "")
        for stmt in ref.body
        if isinstance(stmt, ast.ImportFrom) and not stmt.level and stmt.module
        for a in stmt.names
        if (a.asname or a.name) in names
    ] + [
        f"import {a.name}" + (f" as {a.asname}" if a.asname else "")
        for stmt in ref.body
        if isinstance(stmt, ast.Import)
        for a in stmt.names
        if (a.asname or a.name.split(".")[0]) in names
    ]
    imports = [n for n in tree.body if isinstance(n, ast.Import | ast.ImportFrom)]
    if added and imports:
        lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
        last = max(n.end_lineno or n.lineno for n in imports)
        lines[last:last] = [line + "\n" for line in added]
        path.write_text("".join(lines), encoding="utf-8")
    return added


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("root", nargs="?", default=str(HERE.parent))
    parser.add_argument("--map", default=str(HERE / "core_moves.txt"))
    parser.add_argument("--dry-run", action="store_true")
    parser.add_argument("--resolve-imports", metavar="REF",
                        help="resolve conflict hunks made of import lines only, taking back "
                             "the imports of REF (the merged branch) they need (module doc)")
    args = parser.parse_args(argv)
    root = Path(args.root).resolve()
    modules, names = read_map(Path(args.map))
    report = []
    if args.resolve_imports:
        unmerged = subprocess.run(["git", "-C", str(root), "diff", "--name-only",
                                   "--diff-filter=U"], capture_output=True, text=True).stdout
        for rel in unmerged.split():
            # the markers again, with the common ancestor's text (diff3)
            subprocess.run(["git", "-C", str(root), "checkout", "--conflict=diff3", "--", rel],
                           check=True)
        for path in files(root):
            text = path.read_text(encoding="utf-8")
            if "<<<<<<<" not in text:
                continue

            def rewrite(part: str, py: bool = path.suffix == ".py") -> str:
                part = rewrite_modules(part, modules)
                if py:
                    part, renames = rewrite_names(part, names)
                    part = rename_words(part, renames)
                return part

            new, resolved, left = resolve_conflicts(text, rewrite)
            report.append(f"conflicts {path.relative_to(root)}: {resolved} hunks "
                          f"resolved, {left} left")
            if not args.dry_run:
                path.write_text(new, encoding="utf-8")
    report += move_files(root, modules, args.dry_run)
    for path in files(root):
        text = path.read_text(encoding="utf-8")
        new = rewrite_modules(text, modules)
        if path.suffix == ".py":
            new, renames = rewrite_names(new, names)
            new = rename_words(new, renames)
        if new != text:
            report.append(f"rewrite {path.relative_to(root)}")
            if not args.dry_run:
                path.write_text(new, encoding="utf-8")
    # a renamed name, in the module that defines it
    for _, on, nm, nn in names:
        target = module_file(root, nm)
        if on != nn and target.exists():
            text = target.read_text(encoding="utf-8")
            if re.search(rf"^(class|def) {re.escape(on)}\b|^{re.escape(on)} =", text, re.M):
                report.append(f"rename {on} -> {nn} in {target.relative_to(root)}")
                if not args.dry_run:
                    target.write_text(rename_words(text, {(on, nn)}), encoding="utf-8")
    if args.resolve_imports and not args.dry_run:
        # what the side merged into did not import: take it back from the merged branch
        # (and what the merged-into side imported and a resolution dropped: from HEAD)
        for ref in (args.resolve_imports, "HEAD"):
            for path, missing in sorted(undefined_names(root).items()):
                rel = path.resolve().relative_to(root)
                shown = subprocess.run(["git", "-C", str(root), "show", f"{ref}:{rel}"],
                                       capture_output=True, text=True)
                if shown.returncode == 0:
                    added = take_back_imports(path, missing, shown.stdout)
                    if added:
                        report.append(f"imports taken back from {ref} into {rel}: "
                                      + "; ".join(added))
    core = root / "src" / "nilpotent" / "core"
    if core.is_dir():
        report += [f"UNPLACED {p.relative_to(root)}: add it to the map" for p in
                   sorted(core.glob("*.py")) if p.name != "__init__.py"]
    print("\n".join(report) or "nothing to do")
    return 0


if __name__ == "__main__":
    sys.exit(main())
