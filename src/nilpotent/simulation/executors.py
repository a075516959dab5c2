"""Where the chunks of a sweep run: this process, or a Dask cluster.

:func:`execute` maps a picklable module-level function over picklable tasks and
returns the outputs in task order with the wall time of the work (cluster
start-up excluded).  Locally the tasks run one after another (each is already
parallel: the batched integrators use every core); with ``dask=`` they go to
Dask workers: ``"local"`` starts a :class:`distributed.LocalCluster` on this
machine (one single-threaded worker per core) and closes it afterwards; a
scheduler address or a :class:`distributed.Client` uses that cluster.  Dask is
the optional extra ``pip install "nilpotent[dask]"``.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from nilpotent.errors import MissingExtraError, OptionError

__all__ = ["MIN_DASK_CHUNK", "Execution", "check_dask", "execute", "versions"]

#: Smallest chunk sent to a Dask worker (scheduling one task costs 30–70 trajectories).
MIN_DASK_CHUNK = 1000

_INSTALL_DASK = 'pip install "nilpotent[dask]"'


@dataclass(frozen=True)
class Execution:
    """Outputs of :func:`execute` (in task order) and how they were obtained."""

    outputs: list[Any]
    backend: str
    scheduler: str | None
    wall_time: float


def import_distributed() -> Any:
    """The ``distributed`` module, or :class:`MissingExtraError` naming the extra."""
    try:
        import distributed
    except ImportError:
        raise MissingExtraError(
            "sweeps on Dask need the dask extra, which is not installed: "
            f"{_INSTALL_DASK}"
        ) from None
    return distributed


def check_dask(dask: Any, chunk_size: int) -> None:
    """Refuse, before any work, a Dask request that cannot run (extra, chunk size, type)."""
    if dask is None:
        return
    distributed = import_distributed()
    if int(chunk_size) < MIN_DASK_CHUNK:
        raise OptionError(
            f"chunk_size {chunk_size} is too small for Dask: one task costs as much as "
            f"30–70 trajectories; use at least {MIN_DASK_CHUNK}"
        )
    if not isinstance(dask, str | distributed.Client):
        raise OptionError("dask must be 'local', a scheduler address or a distributed.Client")


def execute(
    func: Callable[[Any], Any],
    tasks: Sequence[Any],
    sizes: Sequence[int],
    *,
    dask: Any = None,
    progress: Callable[[int, int], None] | None = None,
) -> Execution:
    """``[func(task) for task in tasks]``, here or on Dask (module docstring).

    ``sizes[k]`` is the work in task ``k`` (trajectories); ``progress(done,
    total)``, when given, is called after each task with the sums of ``sizes``
    (the CLI feeds it to :func:`nilpotent.progress.progress`).
    """
    total = int(sum(sizes))

    def tick(done: int) -> None:
        if progress is not None:
            progress(done, total)

    if dask is None:
        return _execute_here(func, tasks, sizes, tick)
    return _execute_dask(func, tasks, sizes, dask, tick)


def _execute_here(func: Callable[[Any], Any], tasks: Sequence[Any], sizes: Sequence[int],
                  tick: Callable[[int], None]) -> Execution:
    t0 = time.perf_counter()
    outputs = []
    done = 0
    for task, size in zip(tasks, sizes, strict=True):
        outputs.append(func(task))
        done += int(size)
        tick(done)
    return Execution(outputs, "local", None, time.perf_counter() - t0)


def _execute_dask(func: Callable[[Any], Any], tasks: Sequence[Any], sizes: Sequence[int],
                  dask: Any, tick: Callable[[int], None]) -> Execution:
    distributed = import_distributed()
    cluster = None
    if isinstance(dask, str):
        if dask == "local":
            cluster = distributed.LocalCluster(
                n_workers=os.cpu_count() or 1, threads_per_worker=1, processes=True,
                dashboard_address=None,
            )
            client = distributed.Client(cluster)
        else:
            try:
                client = distributed.Client(dask)
            except (OSError, TimeoutError, ValueError) as exc:
                raise OptionError(f"cannot reach the Dask scheduler at {dask!r}: {exc}") from None
            except MemoryError:  # something answered, but not a Dask scheduler
                raise OptionError(
                    f"the server at {dask!r} did not answer as a Dask scheduler"
                ) from None
        own_client = True
    else:
        client = dask
        own_client = False
    try:
        scheduler = str(client.scheduler.address)
        t0 = time.perf_counter()
        futures = client.map(func, list(tasks), pure=False)
        index = {f.key: k for k, f in enumerate(futures)}
        results: list[Any] = [None] * len(tasks)
        done = 0
        for fut in distributed.as_completed(futures):
            k = index[fut.key]
            results[k] = fut.result()
            done += int(sizes[k])
            tick(done)
        wall = time.perf_counter() - t0
    finally:
        if own_client:
            client.close()
        if cluster is not None:
            cluster.close()
    return Execution(results, "dask", scheduler, wall)


def versions(backend: str) -> dict[str, str]:
    """Versions of Python, nilpotent and the numeric packages (plus Dask's on Dask)."""
    from importlib import metadata

    from nilpotent.version import __version__

    out = {"python": sys.version.split()[0], "nilpotent": __version__}
    names = ["numpy", "sympy", "symengine", "numba"]
    if backend == "dask":
        names += ["dask", "distributed"]
    for name in names:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return out
