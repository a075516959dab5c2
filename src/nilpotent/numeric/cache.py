"""The on-disk cache of generated code.

Generated right-hand sides and integrator kernels are written as real ``.py``
files (numba can cache only code that lives in a file) into one directory:

1. ``$NILPOTENT_CACHE`` when set;
2. else ``$XDG_CACHE_HOME/nilpotent``, or ``~/.cache/nilpotent``;
3. else (not writable) a per-user folder in the system temporary directory.

A file's name carries a hash of everything it was generated from, so a file
is never stale: a change of expressions, generator or library version gives a
new name.  Files are written whole (temporary file + rename), so concurrent
processes never see half a file.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

#: Bumped whenever the code generators change what they write.
GENERATOR_VERSION = "2"


def cache_dir() -> Path:
    """The directory of generated modules (created when missing)."""
    candidates: list[Path] = []
    env = os.environ.get("NILPOTENT_CACHE")
    if env:
        candidates.append(Path(env))
    else:
        xdg = os.environ.get("XDG_CACHE_HOME")
        base = Path(xdg) if xdg else Path.home() / ".cache"
        candidates.append(base / "nilpotent")
    user = os.environ.get("USER") or str(os.getuid() if hasattr(os, "getuid") else "user")
    candidates.append(Path(tempfile.gettempdir()) / f"nilpotent-cache-{user}")
    for folder in candidates:
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError:
            continue
        if os.access(folder, os.W_OK):
            return folder
    raise OSError("no writable cache directory (set NILPOTENT_CACHE to a writable folder)")


def content_key(*parts: str) -> str:
    """A short hex digest of ``parts`` (plus the generator version)."""
    digest = hashlib.sha256()
    for part in (GENERATOR_VERSION, *parts):
        digest.update(part.encode())
        digest.update(b"\0")
    return digest.hexdigest()[:20]


def load_generated_module(
    stem: str, source: str | None, make_source: Callable[[], str] | None = None
) -> ModuleType:
    """Import the generated module ``<cache>/<stem>.py``, writing it first if missing.

    Parameters
    ----------
    stem:
        File name without ``.py``; must already contain the content hash.
    source, make_source:
        The module text, or a callable producing it (called only when the
        file does not exist yet, so cached runs skip code generation).

    Raises
    ------
    ValueError
        If neither ``source`` nor ``make_source`` is given (a programming error).
    """
    folder = cache_dir()
    path = folder / f"{stem}.py"
    if not path.exists():
        if source is not None:
            text = source
        elif make_source is not None:
            text = make_source()
        else:
            raise ValueError("load_generated_module needs source or make_source")
        fd, tmp = tempfile.mkstemp(prefix=f".{stem}.", suffix=".tmp", dir=folder)
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(tmp, path)
    name = f"nilpotent_generated.{stem}"
    module = sys.modules.get(name)
    if module is not None:
        return module
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:  # pragma: no cover - importlib contract
        raise ImportError(f"cannot load generated module {path}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        sys.modules.pop(name, None)
        raise
    return module
