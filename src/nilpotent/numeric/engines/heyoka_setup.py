"""heyoka's process-wide settings: its disk cache under the product's policy, its log off stdout.

heyoka keeps compiled LLVM object code in an on-disk cache (an SQLite file) and
runs what it finds there under the genuine keys.  Its default folder
(``~/.cache/heyoka``, made with the umask's mode and never checked) is outside
the product's cache policy (:mod:`nilpotent.numeric.cache`), so it is never
used: :func:`use_safe_disk_cache` points heyoka at
:func:`~nilpotent.numeric.cache.library_cache` ``("heyoka")`` (0700, the
user's own, every entry the user's own, no link, not writable by others),
checked again before every compilation, or switches the disk cache off.

heyoka logs through spdlog on stdout (e.g. when its cache folder is unusable):
:func:`quiet_logger` sets its level to ``critical`` and :func:`stdout_to_stderr`
points file descriptor 1 at stderr while an integrator is built, so nothing
of heyoka's reaches stdout.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import warnings
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

from nilpotent.numeric.cache import library_cache

__all__ = ["quiet_logger", "stdout_to_stderr", "use_safe_disk_cache"]

_state: dict[str, Any] = {}  # "quiet": logger set; "folder": the disk cache in use
_stdout_lock = threading.Lock()


def quiet_logger(hy: ModuleType) -> None:
    """Set heyoka's log level to ``critical`` (once per process): its warnings went to stdout."""
    if "quiet" not in _state:
        hy.set_logger_level_critical()
        _state["quiet"] = True


def use_safe_disk_cache(hy: ModuleType) -> Path | None:
    """Point heyoka's on-disk cache at the checked folder, or switch it off; returns it.

    The folder is :func:`~nilpotent.numeric.cache.library_cache` ``("heyoka")``,
    checked on every call (before each compilation); heyoka's own default
    folder is never used.  When no folder is safe the disk cache is off and a
    ``RuntimeWarning`` (once per reason) says why.
    """
    folder, why = library_cache("heyoka")
    llvm = hy.llvm_state
    if folder is None:
        if llvm.get_diskcache_enabled():
            llvm.set_diskcache_enabled(False)
        if why and _state.get("warned") != why:
            _state["warned"] = why
            warnings.warn(
                f"nilpotent: heyoka's disk cache is off: {why}; integrators are compiled "
                "in every process. Fix: remove that folder (it is made again, 0700), or "
                "set NILPOTENT_CACHE to a folder of your own",
                RuntimeWarning, stacklevel=3,
            )
    else:
        if _state.get("folder") != folder or Path(llvm.get_diskcache_path()) != folder:
            llvm.set_diskcache_path(str(folder))
        if not llvm.get_diskcache_enabled():
            llvm.set_diskcache_enabled(True)
    _state["folder"] = folder
    return folder


@contextlib.contextmanager
def stdout_to_stderr() -> Iterator[None]:
    """Run with file descriptor 1 pointed at stderr (a native library's prints leave stdout)."""
    with _stdout_lock:
        try:
            sys.stdout.flush()
            saved = os.dup(1)
        except (OSError, ValueError, AttributeError):  # no usable fd 1: nothing to protect
            yield
            return
        try:
            os.dup2(2, 1)
        except OSError:
            os.close(saved)
            yield
            return
        try:
            yield
        finally:
            os.dup2(saved, 1)
            os.close(saved)
