"""Reading the files users write (model files, world files): one reader, one set of rules.

:func:`read_data_file` reads a ``.toml`` or ``.json`` file into its table:

* only a regular file is opened: a folder, a named pipe (FIFO), a device
  (``/dev/zero``) or a socket is refused from :func:`os.stat` before any read
  (a FIFO would wait forever, ``/dev/zero`` grow without end);
* at most :data:`MAX_FILE_BYTES` bytes (a :class:`~nilpotent.errors.ComputationLimitError`
  past it, checked before reading and again on the bytes read);
* UTF-8 text; a leading UTF-8 byte-order mark is read past (some Windows
  editors write one), UTF-16 is refused with a message saying so;
* TOML by the standard library's :mod:`tomllib` (which refuses a key given
  twice); JSON by :mod:`json` with every key of an object once and integers of
  at most :data:`MAX_INT_DIGITS` digits, never Python's 4300-digit limit as a
  traceback.

Every other problem is the caller's ``error`` class, naming the file.
"""

from __future__ import annotations

import json
import stat
import tomllib
from pathlib import Path
from typing import Any

from nilpotent.errors import ComputationLimitError, NilpotentError

__all__ = ["MAX_FILE_BYTES", "MAX_INT_DIGITS", "SUFFIXES", "read_data_file"]

#: File suffixes understood (TOML or the same structure as JSON).
SUFFIXES: tuple[str, ...] = (".toml", ".json")
#: Largest file read, in bytes.
MAX_FILE_BYTES = 1_000_000
#: Most decimal digits of an integer written as a number (not as text) in a JSON file.
MAX_INT_DIGITS = 1000


def _show(value: object, limit: int = 80) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[:limit] + "..."


def describe_kind(mode: int) -> str | None:
    """What a non-regular file is, in words (``None`` for a regular file)."""
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a named pipe (FIFO)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def _size_limit(path: Path, size: int) -> None:
    if size > MAX_FILE_BYTES:
        raise ComputationLimitError(
            f"{path}: {size:,} bytes, above the limit {MAX_FILE_BYTES:,} of a file read "
            "(nilpotent.core.model.datafile.MAX_FILE_BYTES)"
        )


def read_text(path: Path, what: str, error: type[NilpotentError]) -> str:
    """The text of the file ``path`` (a ``what`` such as ``"model file"``): a regular file
    of at most :data:`MAX_FILE_BYTES`, UTF-8, a leading byte-order mark skipped.  Never
    blocks on a FIFO or reads a device.

    Raises
    ------
    NilpotentError
        ``error`` for a missing, unreadable or non-regular file or text that is not
        UTF-8; :class:`~nilpotent.errors.ComputationLimitError` past the size limit.
    """
    try:
        info = path.stat()
    except FileNotFoundError:
        raise error(f"{path}: {what} not found") from None
    except OSError as exc:
        raise error(f"{path}: cannot read the {what} ({exc.strerror})") from None
    kind = describe_kind(info.st_mode)
    if kind is not None:
        raise error(f"{path} is {kind}, not a {what} (give a .toml or .json file)")
    _size_limit(path, info.st_size)
    try:
        with path.open("rb") as handle:
            raw = handle.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise error(f"{path}: cannot read the {what} ({exc.strerror})") from None
    _size_limit(path, len(raw))
    if raw.startswith(b"\xef\xbb\xbf"):
        raw = raw[3:]  # a UTF-8 byte-order mark: read past it
    elif raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise error(f"{path}: UTF-16 text (byte-order mark); save the file as UTF-8")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None


def _no_duplicates(path: Path, error: type[NilpotentError]):
    def hook(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for key, value in pairs:
            if key in out:
                raise error(
                    f"{path}: duplicate key {_show(key)} in one JSON object (each key once; "
                    "TOML refuses this too)"
                )
            out[key] = value
        return out

    return hook


def _json_int(path: Path, error: type[NilpotentError]):
    def parse(text: str) -> int:
        if len(text.lstrip("-")) > MAX_INT_DIGITS:
            raise error(
                f"{path}: an integer of {len(text.lstrip('-')):,} digits, too long (at most "
                f"{MAX_INT_DIGITS})"
            )
        return int(text)

    return parse


def file_suffix(path: Path, what: str, error: type[NilpotentError]) -> str:
    """``.toml`` or ``.json`` (lower case), else ``error``."""
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise error(
            f"{path}: unknown {what} type {path.suffix or '(no suffix)'!r} "
            f"(use {' or '.join(SUFFIXES)})"
        )
    return suffix


def read_data_file(path: str | Path, what: str, error: type[NilpotentError]) -> Any:
    """The structure of the TOML or JSON file ``path`` (module doc).

    Parameters
    ----------
    path : str or Path
        The file; its suffix (``.toml`` or ``.json``) says the syntax.
    what : str
        What the file is, in words (``"model file"``, ``"world file"``), for messages.
    error : type of NilpotentError
        The error raised for every problem but the size limit.

    Returns
    -------
    Any
        The parsed structure (a table for TOML; whatever the JSON holds).

    Raises
    ------
    NilpotentError
        ``error``: unknown suffix, missing, unreadable or non-regular file, text that
        is not UTF-8, a syntax error (with its line), a duplicate JSON key, an integer
        too long; :class:`~nilpotent.errors.ComputationLimitError`: a file too large.
    """
    path = Path(path)
    text = read_text(path, what, error)
    if file_suffix(path, what, error) == ".toml":
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise error(f"{path}: TOML syntax error: {exc}") from None
        except ValueError as exc:  # e.g. an integer past Python's 4300-digit limit
            raise error(f"{path}: TOML value not readable: {_show(str(exc))}") from None
    try:
        return json.loads(text, object_pairs_hook=_no_duplicates(path, error),
                          parse_int=_json_int(path, error))
    except json.JSONDecodeError as exc:
        raise error(
            f"{path}: JSON syntax error: {exc.msg} (line {exc.lineno}, column {exc.colno})"
        ) from None
    except RecursionError:
        raise error(f"{path}: JSON nested too deeply") from None
