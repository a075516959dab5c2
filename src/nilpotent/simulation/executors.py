"""Where the chunks of a sweep run: this process, or a Dask cluster.

:func:`execute` maps a picklable module-level function over picklable tasks and
returns the outputs in task order with the wall time of the work (cluster
start-up excluded).  Locally the tasks run one after another (each is already
parallel: the batched integrators use every core); with ``dask=`` they go to
Dask workers: ``"local"`` starts a :class:`distributed.LocalCluster` on this
machine (one single-threaded worker per core) and closes it afterwards; a
scheduler address, a :class:`distributed.Client` or a cluster object
(:class:`distributed.deploy.Cluster`: dask-jobqueue's, dask-kubernetes') uses
that cluster (left running).  Dask is
the optional extra ``pip install "nilpotent[dask]"``.

:func:`loopback_cluster` starts what a user starts on a cluster, here: a
``dask scheduler`` and ``dask worker`` processes, separate from this one,
listening on 127.0.0.1 only, with a bounded lifetime, and stopped on exit
(benchmarks and tests of the real scheduler path use it).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from nilpotent.errors import MissingExtraError, OptionError

__all__ = ["MIN_DASK_CHUNK", "Execution", "check_dask", "execute", "loopback_cluster",
           "versions"]

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
    if not isinstance(dask, str | distributed.Client | distributed.deploy.Cluster):
        raise OptionError("dask must be 'local', a scheduler address, a distributed.Client "
                          "or a cluster object (distributed.deploy.Cluster)")


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
    elif isinstance(dask, distributed.deploy.Cluster):  # e.g. dask-jobqueue, KubeCluster
        client = distributed.Client(dask)
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


@contextlib.contextmanager
def loopback_cluster(
    workers: int = 2, *, threads_per_worker: int = 1, lifetime: float = 1800.0,
    start_timeout: float = 120.0,
) -> Iterator[str]:
    """A Dask scheduler and ``workers`` worker processes on 127.0.0.1; yields its address.

    Started as a user starts them on a cluster (``python -m
    distributed.cli.dask_scheduler`` and ``…dask_worker``, each its own process
    group, the same Python and the same ``nilpotent`` sources as this process),
    listening on the loopback interface only, without dashboards.  Lifetime is
    bounded twice: the workers stop themselves after ``lifetime`` seconds
    (``--lifetime``) and when the scheduler has gone for 60 s
    (``--death-timeout``); the scheduler after ``lifetime`` seconds idle
    (``--idle-timeout``).  On leaving the block (also on an error) every
    process started here is terminated (its process group: SIGTERM, then
    SIGKILL after 10 s).

    Parameters
    ----------
    workers:
        Worker processes (each ``--nthreads threads_per_worker``).
    lifetime:
        Seconds after which the processes stop by themselves.
    start_timeout:
        Seconds to wait for the scheduler's address and for every worker.

    Raises
    ------
    MissingExtraError
        Without the dask extra.
    RuntimeError
        The cluster did not come up within ``start_timeout`` (its output is in
        the message).
    """
    distributed = import_distributed()
    env = dict(os.environ)
    src = str(Path(__file__).resolve().parents[2])  # the nilpotent this process runs
    env["PYTHONPATH"] = os.pathsep.join([src, *filter(None, [env.get("PYTHONPATH")])])
    procs: list[subprocess.Popen[bytes]] = []
    with tempfile.TemporaryDirectory(prefix="nilpotent-dask-") as tmp:
        file = Path(tmp) / "scheduler.json"
        logs = [Path(tmp) / "scheduler.log"]

        def start(args: list[str], log: Path) -> None:
            with open(log, "wb") as out:
                procs.append(subprocess.Popen(
                    [sys.executable, "-m", *args], stdout=out, stderr=subprocess.STDOUT,
                    env=env, cwd=tmp, start_new_session=True,
                ))

        try:
            start(["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
                   "--no-dashboard", "--scheduler-file", str(file),
                   "--idle-timeout", f"{lifetime:.0f}s"], logs[0])
            deadline = time.monotonic() + start_timeout
            address = None
            while address is None:
                if file.exists():
                    with contextlib.suppress(ValueError):
                        address = json.loads(file.read_text())["address"]
                if address is None:
                    _check_alive(procs, logs, deadline)
                    time.sleep(0.1)
            for k in range(workers):
                logs.append(Path(tmp) / f"worker-{k}.log")
                start(["distributed.cli.dask_worker", str(address), "--host", "127.0.0.1",
                       "--nthreads", str(threads_per_worker), "--no-dashboard",
                       "--name", f"loopback-{k}", "--lifetime", f"{lifetime:.0f}s",
                       "--death-timeout", "60s", "--local-directory", tmp], logs[-1])
            with distributed.Client(address, timeout=start_timeout) as client:
                while len(client.scheduler_info()["workers"]) < workers:
                    _check_alive(procs, logs, deadline)
                    time.sleep(0.1)
            yield str(address)
        finally:
            for proc in reversed(procs):
                _stop(proc)


def _check_alive(procs: Sequence[subprocess.Popen[bytes]], logs: Sequence[Path],
                 deadline: float) -> None:
    """Raise if a process of :func:`loopback_cluster` died or the start took too long."""
    dead = [k for k, p in enumerate(procs) if p.poll() is not None]
    if dead or time.monotonic() > deadline:
        k = dead[0] if dead else 0
        tail = logs[k].read_text(errors="replace")[-2000:] if logs[k].exists() else ""
        why = "exited" if dead else "did not start in time"
        raise RuntimeError(f"the loopback Dask cluster {why} ({logs[k].name}):\n{tail}")


def _stop(proc: subprocess.Popen[bytes]) -> None:
    """Terminate ``proc``'s process group (SIGTERM, then SIGKILL after 10 s)."""
    for sig, wait in ((signal.SIGTERM, 10.0), (signal.SIGKILL, 5.0)):
        if proc.poll() is not None:
            break
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, sig)
        with contextlib.suppress(subprocess.TimeoutExpired):
            proc.wait(wait)
    # the group may hold children of a process that already exited (a nanny's worker)
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, signal.SIGKILL)


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
