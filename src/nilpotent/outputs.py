"""Writing output files and folders safely.

Every file the tool writes (figures, CSV, animations, the reproduced paper) goes
through this module, so that:

- a path that cannot be written (a missing or read-only folder, a folder where a
  file is expected, ``/proc/...``) is refused *before* the work, by
  :func:`check_writable`, with an :class:`~nilpotent.errors.OptionError` (kind
  ``option``: the option's value is unusable);
- a file is written whole or not at all (:func:`write_atomically`: a temporary
  file beside the target, renamed into place on success, removed on failure,
  on Ctrl-C and on SIGTERM, which the CLI turns into the same interruption);
- a temporary left behind by a run that was killed outright (SIGKILL, power
  loss) is removed by the next run that writes the same target: temporaries
  carry the writing process's id (``.<name>.<pid>.tmp<random>``) and those of
  processes no longer alive are deleted (:func:`remove_stale_temporaries`);
- any :class:`OSError` while writing (disk full, permission) becomes an
  :class:`~nilpotent.errors.OutputError` naming the file and the reason.
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from nilpotent import interrupts
from nilpotent.errors import OptionError, OutputError

__all__ = [
    "check_writable",
    "remove_stale_temporaries",
    "temporary_prefix",
    "write_atomically",
]

_SHOW = 200  # characters of a path shown in messages


def shown_path(path: str | os.PathLike[str]) -> str:
    """``path`` as text for a message: control characters escaped, length bounded."""
    text = os.fspath(path)
    clean = "".join(ch if ch.isprintable() else ascii(ch)[1:-1] for ch in text)
    if len(clean) > _SHOW:
        clean = clean[:_SHOW] + f"... ({len(clean) - _SHOW} more characters)"
    return clean


def _reason(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def temporary_prefix(target: Path, kind: str = "tmp") -> str:
    """The name prefix of this process's temporaries for ``target`` (pid included)."""
    return f".{target.name}.{kind}.{os.getpid()}."


def _pid_alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, owned by someone else
        return True
    except OSError:
        return False
    return True


def remove_stale_temporaries(target: Path) -> list[Path]:
    """Delete the temporaries of ``target`` left by processes that are no longer alive.

    Only names this module makes are considered (``.<name>.<kind>.<pid>.<random>``
    beside ``target``) and only those whose process is gone; a concurrent run's
    temporaries are left alone.

    Returns
    -------
    list of Path
        What was removed.
    """
    removed: list[Path] = []
    folder = target.parent
    stem = f".{target.name}."
    try:
        entries = list(folder.iterdir()) if folder.is_dir() else []
    except OSError:
        return removed
    for entry in entries:
        name = entry.name
        if not name.startswith(stem):
            continue
        rest = name[len(stem):].split(".")
        if len(rest) < 3 or rest[0] not in ("tmp", "old") or not rest[1].isdigit():
            continue
        if _pid_alive(int(rest[1])):
            continue
        try:
            if entry.is_dir() and not entry.is_symlink():
                shutil.rmtree(entry)
            else:
                entry.unlink()
            removed.append(entry)
        except OSError:
            continue
    return removed


def check_writable(path: str | os.PathLike[str] | None, option: str, *, folder: bool = False
                   ) -> None:
    """Refuse, before any work, an output path that cannot be written.

    The check creates and removes a temporary file in the target's folder, which
    is the only reliable test (permissions, read-only file systems, ``/proc``,
    root's special cases). A target that is a folder (when a file is expected)
    or a file (when a folder is expected) is refused too.

    Parameters
    ----------
    path:
        The output path (``None``: nothing to check).
    option:
        The option that named it (``--plot``), for the message.
    folder:
        Whether the output is a folder (``reproduce --out``).

    Raises
    ------
    OptionError
        With the option, the path and the reason (the option's value is unusable).
    """
    if path is None:
        return
    target = Path(path)
    where = f"{option} {shown_path(target)}"
    if (not target.name or target.name in (".", "..")) and not folder:
        raise OptionError(f"{where}: a file name is needed, not a folder")
    if target.is_dir() and not folder:
        raise OptionError(f"{where}: is a folder (give a file name)")
    if target.exists() and folder and not target.is_dir():
        raise OptionError(f"{where}: exists and is not a folder")
    if target.exists() and not folder and not target.is_file():
        raise OptionError(f"{where}: exists and is not a regular file")
    parent = target.parent if str(target.parent) else Path(".")
    if not parent.is_dir():
        raise OptionError(f"{where}: folder {shown_path(parent)} does not exist")
    with interrupts.deferred():  # an interrupt never leaves the probe behind
        try:
            fd, probe = tempfile.mkstemp(prefix=temporary_prefix(target), dir=parent)
        except OSError as exc:
            raise OptionError(f"{where}: cannot write in {shown_path(parent)} ({_reason(exc)})"
                              ) from None
        os.close(fd)
        with contextlib.suppress(OSError):
            os.unlink(probe)


@contextlib.contextmanager
def write_atomically(path: str | os.PathLike[str], suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; move it into place only on success.

    The temporary is removed whatever happens (an exception, Ctrl-C, SIGTERM
    turned into an interruption by the CLI). Stale temporaries of the same
    target from dead processes are removed first.

    Raises
    ------
    OutputError
        The folder is missing or unwritable, or writing failed (disk full, ...).
    """
    target = Path(path)
    parent = target.parent if str(target.parent) else Path(".")
    if not parent.is_dir():
        raise OptionError(
            f"cannot write {shown_path(target)}: folder {shown_path(parent)} does not exist")
    if target.is_dir():
        raise OptionError(f"cannot write {shown_path(target)}: it is a folder")
    remove_stale_temporaries(target)
    tmp_path: Path | None = None
    try:
        with interrupts.deferred():  # created and known to the clean-up below as one step
            try:
                fd, tmp = tempfile.mkstemp(
                    prefix=temporary_prefix(target), suffix=suffix or target.suffix, dir=parent
                )
            except OSError as exc:
                raise OutputError(f"cannot write {shown_path(target)} ({_reason(exc)})"
                                  ) from None
            os.close(fd)
            tmp_path = Path(tmp)
        mask = os.umask(0)
        os.umask(mask)
        yield tmp_path
        interrupts.checkpoint()  # an interrupt whose exception was swallowed: not in place
        os.chmod(tmp_path, 0o666 & ~mask)  # mkstemp makes it private; the result is ordinary
        os.replace(tmp_path, target)
    except OSError as exc:
        if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EACCES, errno.EPERM, errno.EROFS,
                         errno.EISDIR, errno.ENOENT, errno.EIO, errno.EFBIG):
            raise OutputError(f"cannot write {shown_path(target)} ({_reason(exc)})") from None
        raise
    finally:
        with contextlib.suppress(OSError):
            if tmp_path is not None and tmp_path.exists():
                tmp_path.unlink()
