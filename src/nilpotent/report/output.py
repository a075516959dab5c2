"""The reproduction's output folder: refusing a foreign folder, atomic replacement, JSON/CSV.

The reproduction is written into a temporary folder beside the target and moved
into place at the end (:func:`move_into_place`), so the target is never left
half-written; :func:`check_target` refuses a target that is neither empty nor a
previous reproduction.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from nilpotent import interrupts
from nilpotent.errors import OptionError
from nilpotent.outputs import temporary_prefix

__all__ = ["check_target", "move_into_place", "write_csv", "write_json"]


def check_target(target: Path) -> None:
    """Refuse an output folder that cannot be written or holds something else.

    Raises
    ------
    OptionError
        The parent folder is missing, ``target`` is a file, or ``target`` is a
        non-empty folder without a ``nilpotent/audit@1`` ``audit.json``.
    """
    from nilpotent.report.audit import AUDIT_SCHEMA

    if not target.exists():
        if not target.parent.exists():
            raise OptionError(f"cannot write {target}: folder {target.parent} does not exist")
        return
    if not target.is_dir():
        raise OptionError(f"--out {target} exists and is not a folder")
    if not any(target.iterdir()):
        return
    audit = target / "audit.json"
    try:
        ours = json.loads(audit.read_text(encoding="utf-8")).get("schema") == AUDIT_SCHEMA
    except (OSError, ValueError, AttributeError):
        ours = False
    if not ours:
        raise OptionError(
            f"--out {target} exists and is not a previous reproduction (no {AUDIT_SCHEMA} "
            "audit.json in it); choose another folder or remove it"
        )


def move_into_place(tmp: Path, target: Path, existed: bool = True) -> None:
    """Replace ``target`` by the finished folder ``tmp`` (two renames; the old one is removed).

    Raises
    ------
    OptionError
        ``target`` did not exist when the work started (``existed`` false) and
        was created meanwhile by something else, or is no longer a previous
        reproduction (:func:`check_target` again); it is left untouched.
    """
    if target.exists() and not existed:
        raise OptionError(
            f"--out {target} was created by something else while the reproduction ran; it is "
            "left untouched (run again, or choose another folder)"
        )
    check_target(target)  # again: what is there now must still be a previous reproduction
    interrupts.checkpoint()  # an interrupt whose exception was swallowed: not in place
    if target.exists():
        with interrupts.deferred():  # Ctrl-C never leaves the target moved away
            old = Path(tempfile.mkdtemp(prefix=temporary_prefix(target, "old"),
                                        dir=target.parent))
            os.replace(target, old / target.name)
            os.replace(tmp, target)
            shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(tmp, target)


def write_json(path: Path, obj: Any) -> Path:
    """Write ``obj`` as JSON with the one strict encoder (:mod:`nilpotent.strict_json`)."""
    from nilpotent.strict_json import json_text

    path.write_text(json_text(obj), encoding="utf-8")
    return path


def write_csv(path: Path, header: Sequence[str], rows: Sequence[Sequence[Any]]) -> Path:
    """Write a header row and rows as CSV; return ``path``."""
    with path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows(rows)
    return path
