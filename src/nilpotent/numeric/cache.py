"""The on-disk cache of generated code.

Generated right-hand sides and integrator kernels are written as real ``.py``
files (numba can cache only code that lives in a file) into one directory:

1. ``$NILPOTENT_CACHE`` when set;
2. else ``$XDG_CACHE_HOME/nilpotent``, or ``~/.cache/nilpotent``;
3. else (none usable) a private folder made for this process only
   (:func:`tempfile.mkdtemp`, removed at exit): no disk cache between runs.

A cached module is code that runs as the user, so a folder is used only if it is
safe (:func:`safe_folder`): created with mode 0700, owned by the user, not
writable by group or others (a folder that fails this is never used nor
repaired: files may have been planted while it was open). And a file is
imported only if its content is byte for byte what this process generated
(SHA-256 compared); otherwise it is rewritten first.

A file's name carries a hash of everything it was generated from (the
expressions with the coordinates renamed ``q0..``, parameters substituted; never
the model's name, which appears nowhere in the text either), so a file is never
stale and a renamed model reuses it: a change of expressions, generator or
library version gives a new name.  Files are written whole (temporary file +
rename), so concurrent processes never see half a file.

A library that keeps compiled native code on disk itself (heyoka's LLVM object
code) gets a subfolder of this one (:func:`library_cache`) under the same
policy, never its own default folder; when none is safe its disk cache is off.
"""

from __future__ import annotations

import atexit
import contextlib
import hashlib
import importlib.util
import os
import shutil
import stat
import sys
import tempfile
import warnings
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

#: Bumped whenever the code generators change what they write.
GENERATOR_VERSION = "2"

_private: dict[str, Path] = {}  # the private folder and the folder already warned about

#: Counts of this process: ``"written"`` generated files (re)written, ``"reused"``
#: files found holding exactly the generated text (a test hook: reuse is observable).
STATS: Counter[str] = Counter()


def safe_folder(folder: Path) -> str | None:
    """Why ``folder`` must not hold code to import (``None``: it is safe).

    Safe means: an existing directory (not a symbolic link), owned by the current
    user, not writable by group or others.
    """
    try:
        info = os.lstat(folder)
    except OSError as exc:
        return f"cannot inspect it ({exc.strerror})"
    if stat.S_ISLNK(info.st_mode):
        return "it is a symbolic link"
    if not stat.S_ISDIR(info.st_mode):
        return "it is not a folder"
    if hasattr(os, "getuid") and info.st_uid != os.getuid():
        return f"it is owned by another user (uid {info.st_uid})"
    if info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return f"it is writable by others (mode {stat.S_IMODE(info.st_mode):o})"
    return None


def _usable(folder: Path) -> bool:
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
        folder.mkdir(mode=0o700, exist_ok=True)
    except OSError:
        return False
    if safe_folder(folder) is not None or not os.access(folder, os.W_OK | os.X_OK):
        return False
    # numba keeps its compiled code (pickles, loaded as code) in __pycache__: that folder
    # must be as safe as the cache itself (made here 0700 before numba makes it)
    bytecode = folder / "__pycache__"
    try:
        bytecode.mkdir(mode=0o700, exist_ok=True)
    except OSError:
        return False
    return safe_folder(bytecode) is None


def _private_folder() -> Path:
    """A folder for this process only (0700, random name), removed at exit."""
    folder = _private.get("dir")
    if folder is None or not folder.is_dir():
        folder = Path(tempfile.mkdtemp(prefix="nilpotent-generated-"))
        _private["dir"] = folder
        atexit.register(shutil.rmtree, folder, True)
    return folder


def cache_dir() -> Path:
    """The directory of generated modules (created when missing, mode 0700).

    ``$NILPOTENT_CACHE``, else the XDG cache folder; a folder that is not safe
    (:func:`safe_folder`) is skipped, and then this process writes its modules
    to a private temporary folder instead (no cache between runs).
    """
    env = os.environ.get("NILPOTENT_CACHE")
    if env:
        folder = Path(env)
    else:
        xdg = os.environ.get("XDG_CACHE_HOME")
        base = Path(xdg) if xdg else Path.home() / ".cache"
        folder = base / "nilpotent"
    if _usable(folder):
        return folder
    if "warned" not in _private:
        _private["warned"] = folder
        why = safe_folder(folder) or (
            f"its __pycache__ folder is not safe: {inner}"
            if (inner := safe_folder(folder / "__pycache__")) and folder.is_dir()
            else "it cannot be created or written")
        warnings.warn(
            f"nilpotent: not using the code cache {folder}: {why}; generated code goes to a "
            "private temporary folder (no cache between runs). Fix: chmod 700 the folder, "
            "or set NILPOTENT_CACHE to a folder of your own",
            RuntimeWarning, stacklevel=2,
        )
    return _private_folder()


def is_private(folder: Path) -> bool:
    """Whether ``folder`` is this process's private folder (no cache between runs)."""
    return folder == _private.get("dir")


def _unsafe_entry(folder: Path) -> str | None:
    """Why some entry of ``folder`` must not be trusted (``None``: every entry is safe).

    Each entry must be the user's own, not a symbolic link, not writable by
    group or others (a file planted or made writable there could be loaded as code).
    """
    try:
        entries = list(os.scandir(folder))
    except OSError as exc:
        return f"cannot list it ({exc.strerror})"
    for entry in entries:
        try:
            info = os.lstat(entry.path)
        except OSError as exc:
            return f"cannot inspect {entry.name} ({exc.strerror})"
        if stat.S_ISLNK(info.st_mode):
            return f"it holds a symbolic link ({entry.name})"
        if hasattr(os, "getuid") and info.st_uid != os.getuid():
            return f"it holds {entry.name}, owned by another user (uid {info.st_uid})"
        if info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
            return (f"it holds {entry.name}, writable by others "
                    f"(mode {stat.S_IMODE(info.st_mode):o})")
    return None


def library_cache(name: str) -> tuple[Path | None, str]:
    """A folder for a library's own on-disk cache of compiled code: ``<cache>/<name>``.

    Under the policy of :func:`cache_dir`: created with mode 0700 inside the
    (safe) cache folder, owned by the user, not writable by group or others, and
    every entry in it the user's own, no symbolic link, not writable by others.

    Parameters
    ----------
    name : str
        The subfolder's name (e.g. ``"heyoka"``).

    Returns
    -------
    tuple of (Path or None, str)
        The folder and ``""``; or ``None`` and why there is none (the code cache
        itself falls back to a private folder, or the subfolder is not safe):
        the library must then keep no disk cache.
    """
    base = cache_dir()
    if is_private(base):
        return None, "the code cache folder is not usable (no cache between runs)"
    folder = base / name
    try:
        folder.mkdir(mode=0o700, exist_ok=True)
    except OSError as exc:
        return None, f"{folder} cannot be created ({exc.strerror})"
    why = safe_folder(folder) or _unsafe_entry(folder)
    if why is None and not os.access(folder, os.W_OK | os.X_OK):
        why = "it is not writable"
    return (None, f"{folder}: {why}") if why else (folder, "")


def content_key(*parts: str) -> str:
    """A short hex digest of ``parts`` (plus the generator version)."""
    digest = hashlib.sha256()
    for part in (GENERATOR_VERSION, *parts):
        digest.update(part.encode())
        digest.update(b"\0")
    return digest.hexdigest()[:20]


def _matches(path: Path, data: bytes) -> bool:
    """Whether ``path`` is a regular file (not a link) holding exactly ``data``."""
    try:
        info = os.lstat(path)
        if not stat.S_ISREG(info.st_mode) or info.st_size != len(data):
            return False
        if hasattr(os, "getuid") and info.st_uid != os.getuid():
            return False
        with path.open("rb") as handle:
            found = handle.read(len(data) + 1)
    except OSError:
        return False
    return hashlib.sha256(found).digest() == hashlib.sha256(data).digest()


def _write(folder: Path, path: Path, stem: str, data: bytes) -> None:
    fd, tmp = tempfile.mkstemp(prefix=f".{stem}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def load_generated_module(
    stem: str, source: str | None, make_source: Callable[[], str] | None = None
) -> ModuleType:
    """Import the generated module ``<cache>/<stem>.py``, writing it first if needed.

    The text is generated in this process every time (``source`` or
    ``make_source()``) and the file is imported only if it holds exactly that text
    (SHA-256); a missing or different file (stale, damaged, planted) is rewritten
    first. A file that cannot be made right is never imported: the module is then
    written to this process's private folder.

    Parameters
    ----------
    stem:
        File name without ``.py``; must already contain the content hash.
    source, make_source:
        The module text, or a callable producing it.
    """
    name = f"nilpotent_generated.{stem}"
    module = sys.modules.get(name)
    if module is not None:
        return module
    text = source if source is not None else make_source()  # type: ignore[misc]
    data = text.encode("utf-8")
    folder = cache_dir()
    path = folder / f"{stem}.py"
    if _matches(path, data):
        STATS["reused"] += 1
    else:
        STATS["written"] += 1
        with contextlib.suppress(OSError):
            _write(folder, path, stem, data)
        if not _matches(path, data):
            folder = _private_folder()
            path = folder / f"{stem}.py"
            _write(folder, path, stem, data)
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:  # pragma: no cover - importlib contract
        raise ImportError(f"cannot load generated module {path}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        # run the text generated here, never a cached .pyc beside the file (one planted
        # in __pycache__ would otherwise be imported in place of the checked source)
        exec(compile(data, str(path), "exec", dont_inherit=True), module.__dict__)
    except BaseException:
        sys.modules.pop(name, None)
        raise
    return module
