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

Nothing waits on Dask without a bound.  A scheduler address must be
``tcp://HOST:PORT`` or ``HOST:PORT`` (:func:`check_dask`; other schemes are
refused); it is probed first with Dask's own handshake, within
``connect_timeout`` seconds (:data:`DEFAULT_CONNECT_TIMEOUT`): a port that
accepts and never answers, or a server that is not a Dask scheduler, is an
:class:`~nilpotent.errors.OptionError`.  While the chunks run, a period of
``progress_timeout`` seconds (:data:`DEFAULT_PROGRESS_TIMEOUT`) in which no
chunk finishes (a scheduler without workers, a hung worker), the loss of the
scheduler, or a chunk that killed its worker more often than the scheduler's
``distributed.scheduler.allowed-failures`` is a :class:`~nilpotent.errors.DaskError`.
A worker lost mid-run is not an error: the scheduler runs its chunks again on
the other workers (or on the worker its nanny restarts).

:func:`loopback_cluster` starts what a user starts on a cluster, here: a
``dask scheduler`` and ``dask worker`` processes, separate from this one,
listening on 127.0.0.1 only, with a bounded lifetime, and stopped on exit
(benchmarks and tests of the real scheduler path use it).
"""

from __future__ import annotations

import contextlib
import json
import logging
import math
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

from nilpotent.errors import DaskError, MissingExtraError, NilpotentError, OptionError
from nilpotent.progress import ProgressCallback, ProgressEvent

__all__ = ["DEFAULT_CONNECT_TIMEOUT", "DEFAULT_PROGRESS_TIMEOUT", "MAX_DASK_TIMEOUT",
           "MIN_DASK_CHUNK", "Execution", "check_dask", "execute", "loopback_cluster",
           "versions"]

#: Smallest chunk sent to a Dask worker (scheduling one task costs 30–70 trajectories).
MIN_DASK_CHUNK = 1000

#: Seconds to reach a Dask scheduler and get its answer to the handshake.
DEFAULT_CONNECT_TIMEOUT = 10.0

#: Seconds without a finished chunk after which a Dask sweep stops with an error.
DEFAULT_PROGRESS_TIMEOUT = 120.0

#: Largest timeout accepted (one day).
MAX_DASK_TIMEOUT = 86_400.0

#: Address forms accepted for a scheduler given as text.
SUPPORTED_ADDRESSES = "tcp://HOST:PORT, HOST:PORT or 'local'"

_INSTALL_DASK = 'pip install "nilpotent[dask]"'
_POLL = 0.5  # seconds between checks of the scheduler connection while waiting


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


def check_dask(dask: Any, chunk_size: int, *, connect_timeout: float | None = None,
               progress_timeout: float | None = None) -> None:
    """Refuse, before any work, a Dask request that cannot run.

    Checks the extra, the chunk size, the type of ``dask``, the form of a
    scheduler address (:func:`check_address`) and the timeouts (seconds, more
    than 0 and at most :data:`MAX_DASK_TIMEOUT`; only with ``dask``).

    Parameters
    ----------
    dask : Any
        ``None``, ``"local"``, a scheduler address, a client or a cluster object.
    chunk_size : int
        Tasks' size in trajectory pairs.
    connect_timeout : float or None
        Seconds to reach the scheduler (``None``: :data:`DEFAULT_CONNECT_TIMEOUT`).
    progress_timeout : float or None
        Seconds without a finished chunk before giving up (``None``:
        :data:`DEFAULT_PROGRESS_TIMEOUT`).

    Raises
    ------
    MissingExtraError
        Dask is asked for and the extra is not installed.
    OptionError
        Anything else that cannot run.
    """
    for name, value in (("connect_timeout", connect_timeout),
                        ("progress_timeout", progress_timeout)):
        if value is None:
            continue
        if dask is None:
            raise OptionError(f"dask_{name} (--dask-{name.replace('_', '-')}) applies to "
                              "Dask only: give dask (--dask) too, or leave it out")
        _check_timeout(name, value)
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
    if isinstance(dask, str) and dask != "local":
        check_address(dask)


def _check_timeout(name: str, value: Any) -> float:
    """``value`` as seconds in ``(0, MAX_DASK_TIMEOUT]``, else :class:`OptionError`."""
    option = f"dask_{name} (--dask-{name.replace('_', '-')})"
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise OptionError(f"{option} must be a number of seconds, got {value!r:.60}")
    seconds = float(value)
    if not (math.isfinite(seconds) and 0 < seconds <= MAX_DASK_TIMEOUT):
        raise OptionError(f"{option} must be a number of seconds above 0 and at most "
                          f"{MAX_DASK_TIMEOUT:,.0f}, got {value!r:.60}")
    return seconds


def check_address(address: str) -> str:
    """A scheduler address as ``tcp://HOST:PORT`` (``HOST:PORT`` gets the scheme).

    Only plain TCP is accepted from text: ``tls://`` needs certificates and
    ``ucx://``, ``ws://``, ``inproc://`` need set-up that an address alone
    does not carry (a :class:`distributed.Client` made with them may be passed
    from Python instead).

    Parameters
    ----------
    address : str
        What the user gave (``--dask``).

    Returns
    -------
    str
        The address with its scheme.

    Raises
    ------
    OptionError
        Another scheme, no host, or no port in 1–65535.
    """
    shown = repr(address) if len(address) <= 200 else repr(address[:200]) + "…"
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    if scheme.lower() != "tcp":
        hint = (" (TLS needs certificates: pass a distributed.Client made with a "
                "distributed.Security from Python)" if scheme.lower() in ("tls", "wss") else "")
        raise OptionError(f"the Dask scheduler address {shown} uses the scheme "
                          f"{scheme[:20] + '://'!r}, which is not supported; use "
                          f"{SUPPORTED_ADDRESSES}{hint}")
    host, colon, port = rest.rpartition(":")
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    if (not colon or not host or any(c.isspace() or c in "/?#@[]" for c in host)
            or not (port.isascii() and port.isdigit() and len(port) <= 5)
            or not 0 < int(port) <= 65535):
        raise OptionError(f"the Dask scheduler address {shown} is not of the form "
                          f"{SUPPORTED_ADDRESSES} (PORT from 1 to 65535)")
    return f"tcp://{rest}"


def _probe(address: str, timeout: float) -> None:
    """Reach ``address`` and ask it, with Dask's handshake, what it is.

    Two steps, each within ``timeout`` seconds: a TCP connection (refusals
    retried, as Dask does, while the scheduler may still be starting), then
    Dask's handshake and an ``identity`` request.  Run on a thread of its own
    (its own event loop, whatever the caller's) and bounded there:
    ``distributed``'s own connect does not bound the handshake, so a port that
    accepts and never answers would hold ``Client()`` forever.  Which step
    failed decides the message, not how long it took.

    Raises
    ------
    OptionError
        Nothing accepts the connection, something that is not a Dask scheduler
        answers, or nothing answers.
    """
    import asyncio
    import threading

    from distributed.comm.addressing import parse_address, parse_host_port
    from distributed.comm.core import connect

    host, port = parse_host_port(parse_address(address)[1])
    answer: dict[str, Any] = {"step": "connect"}

    async def reach() -> None:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        while True:
            try:
                _, writer = await asyncio.wait_for(asyncio.open_connection(host, port),
                                                   max(deadline - loop.time(), 0.01))
            except ConnectionRefusedError:
                if loop.time() + 0.2 >= deadline:
                    raise
                await asyncio.sleep(0.2)
                continue
            writer.close()
            with contextlib.suppress(OSError):
                await writer.wait_closed()
            return

    async def ask() -> Any:
        await reach()
        answer["step"] = "answer"
        comm = await asyncio.wait_for(connect(address, timeout=timeout), timeout)
        try:
            await asyncio.wait_for(comm.write({"op": "identity", "reply": True}), timeout)
            return await asyncio.wait_for(comm.read(), timeout)
        finally:
            comm.abort()

    def run() -> None:
        try:
            answer["reply"] = asyncio.run(ask())
        except BaseException as exc:  # reported to the caller's thread below
            answer["error"] = exc

    thread = threading.Thread(target=run, name="nilpotent-dask-probe", daemon=True)
    thread.start()
    thread.join(4 * timeout + 5.0)  # the steps bound themselves; this is a last resort
    shown = repr(address)[:200]
    error = answer.get("error")
    if answer["step"] == "connect":
        if thread.is_alive() or isinstance(error, TimeoutError):
            why = "no answer to the connection: a firewall, or a wrong host?"
        else:
            why = f"{error}: is it running, and is the address right?"
        raise OptionError(f"cannot reach the Dask scheduler at {shown} within {timeout:g} s "
                          f"({why})") from None
    if thread.is_alive() or isinstance(error, TimeoutError):
        raise OptionError(
            f"the server at {shown} did not answer as a Dask scheduler within {timeout:g} s "
            "(another service on that port?); raise dask_connect_timeout "
            "(--dask-connect-timeout) if it is only slow") from None
    if error is not None and not isinstance(error, Exception):
        raise error
    reply = answer.get("reply")
    kind = reply.get("type") if isinstance(reply, dict) else None
    if error is not None or kind != "Scheduler":
        what = f" (it is a Dask {kind}, not the scheduler)" if isinstance(kind, str) else ""
        raise OptionError(f"the server at {shown} did not answer as a Dask scheduler{what}"
                          ) from None


def execute(
    func: Callable[[Any], Any],
    tasks: Sequence[Any],
    sizes: Sequence[int],
    *,
    dask: Any = None,
    progress: ProgressCallback | None = None,
    connect_timeout: float | None = None,
    progress_timeout: float | None = None,
    stage: str = "tasks",
) -> Execution:
    """``[func(task) for task in tasks]``, here or on Dask (module docstring).

    Parameters
    ----------
    func : Callable[[Any], Any]
        A picklable module-level function.
    tasks : Sequence[Any]
        Its arguments, one task each.
    sizes : Sequence[int]
        ``sizes[k]`` is the work in task ``k`` (trajectories).
    dask : Any
        ``None`` (this process), ``"local"``, a scheduler address, a
        :class:`distributed.Client` or a cluster object.
    progress : ProgressCallback or None
        Called with ``ProgressEvent(stage, done, total)`` after each task, ``done`` and
        ``total`` the sums of ``sizes`` (:mod:`nilpotent.progress`; the CLI passes its
        bar).
    connect_timeout : float or None
        Seconds to reach the scheduler (default :data:`DEFAULT_CONNECT_TIMEOUT`).
    progress_timeout : float or None
        Seconds without a finished task before giving up (default
        :data:`DEFAULT_PROGRESS_TIMEOUT`).
    stage : str
        The stage named in the progress events.

    Returns
    -------
    Execution
        The outputs in task order, the backend, the scheduler's address, the wall time.

    Raises
    ------
    OptionError
        The scheduler cannot be reached or is not one (and :func:`check_dask`'s refusals).
    DaskError
        No progress within ``progress_timeout``, the scheduler lost, a task
        that killed its workers, a worker that cannot import ``nilpotent``.
    """
    total = int(sum(sizes))

    def tick(done: int) -> None:
        if progress is not None:
            progress(ProgressEvent(stage, done, total))

    if dask is None:
        check_dask(None, 0, connect_timeout=connect_timeout, progress_timeout=progress_timeout)
        return _execute_here(func, tasks, sizes, tick)
    check_dask(dask, MIN_DASK_CHUNK, connect_timeout=connect_timeout,
               progress_timeout=progress_timeout)
    connect = DEFAULT_CONNECT_TIMEOUT if connect_timeout is None else float(connect_timeout)
    patience = DEFAULT_PROGRESS_TIMEOUT if progress_timeout is None else float(progress_timeout)
    return _execute_dask(func, tasks, sizes, dask, tick, connect, patience)


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
                  dask: Any, tick: Callable[[int], None], connect: float,
                  patience: float) -> Execution:
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
            address = check_address(dask)
            _probe(address, connect)
            try:
                client = distributed.Client(address, timeout=connect)
            except (OSError, TimeoutError, ValueError) as exc:
                raise OptionError(f"cannot reach the Dask scheduler at {dask!r:.200}: {exc}"
                                  ) from None
        own_client = True
    elif isinstance(dask, distributed.deploy.Cluster):  # e.g. dask-jobqueue, KubeCluster
        client = distributed.Client(dask, timeout=connect)
        own_client = True
    else:
        client = dask
        own_client = False
    failed = True
    try:
        scheduler = str(client.scheduler.address)
        t0 = time.perf_counter()
        try:
            results = _gather(distributed, client, func, tasks, sizes, tick, patience, scheduler)
        except OSError as exc:  # the comm to the scheduler closed under a request
            raise _lost(scheduler, exc) from None
        failed = False
        wall = time.perf_counter() - t0
    finally:
        # after a failure, the client's own reports of its reconnection attempts
        # (tracebacks on stderr) say nothing the error does not
        with _quiet("distributed") if failed else contextlib.nullcontext():
            if own_client:
                with contextlib.suppress(TimeoutError, OSError):  # the results are in hand
                    client.close(timeout=connect)
            if cluster is not None:
                cluster.close()
    return Execution(results, "dask", scheduler, wall)


def _gather(distributed: Any, client: Any, func: Callable[[Any], Any], tasks: Sequence[Any],
            sizes: Sequence[int], tick: Callable[[int], None], patience: float,
            scheduler: str) -> list[Any]:
    """Submit the tasks and collect their results, never waiting more than ``patience``.

    Raises
    ------
    DaskError
        No task finished for ``patience`` seconds, the scheduler was lost, a
        task killed its workers, or a worker cannot import what the task needs.
    """
    futures = client.map(func, list(tasks), pure=False)
    pending = set(futures)
    try:
        return _collect(distributed, client, futures, pending, sizes, tick, patience,
                        scheduler)
    finally:
        for fut in pending:  # after a failure: the cluster (perhaps the user's) drops them
            fut.release()


def _collect(distributed: Any, client: Any, futures: list[Any], pending: set[Any],
             sizes: Sequence[int], tick: Callable[[int], None], patience: float,
             scheduler: str) -> list[Any]:
    """The loop of :func:`_gather`: results in order; ``pending`` shrinks as they come."""
    from distributed.client import FutureCancelledError, FuturesCancelledError

    index = {f.key: k for k, f in enumerate(futures)}
    results: list[Any] = [None] * len(futures)
    done = 0
    last = time.monotonic()
    while pending:
        try:
            finished, _ = distributed.wait(list(pending), timeout=_POLL,
                                           return_when="FIRST_COMPLETED")
        except (FutureCancelledError, FuturesCancelledError):
            raise _lost(scheduler, None) from None
        except TimeoutError:
            finished = set()
        if client.status != "running":  # "connecting": lost, the futures with it
            raise _lost(scheduler, None)
        for fut in finished:
            k = index[fut.key]
            results[k] = _result(distributed, fut, k, len(futures), scheduler)
            pending.discard(fut)
            done += int(sizes[k])
            tick(done)
        if finished:
            last = time.monotonic()
        elif time.monotonic() - last > patience:
            raise _stalled(client, scheduler, patience, len(futures) - len(pending),
                           len(futures))
    return results


def _result(distributed: Any, fut: Any, k: int, count: int, scheduler: str) -> Any:
    """The result of a finished future, with Dask's failures as :class:`DaskError`."""
    from distributed.client import FutureCancelledError

    try:
        return fut.result()
    except NilpotentError:
        raise
    except distributed.KilledWorker as exc:
        raise DaskError(
            f"chunk {k + 1} of {count} was running on Dask workers that died each time "
            f"(more than the scheduler's distributed.scheduler.allowed-failures): {exc}; "
            "a chunk may need more memory than a worker has (lower the chunk size, "
            "--chunk-size), or the workers cannot load nilpotent (every worker needs the "
            f"same nilpotent installed: {_INSTALL_DASK})") from None
    except FutureCancelledError:
        raise _lost(scheduler, None) from None
    except ImportError as exc:
        raise DaskError(
            f"a Dask worker of {scheduler} cannot run the sweep: {exc}; every worker needs "
            f"the same nilpotent installed ({_INSTALL_DASK})") from None


def _lost(scheduler: str, exc: BaseException | None) -> DaskError:
    why = "" if exc is None else f" ({exc})"
    return DaskError(f"lost the connection to the Dask scheduler at {scheduler}{why}: it "
                     "stopped, or the network failed; the tasks not finished are lost, nothing "
                     "was written; run the sweep again once the scheduler is back")


def _stalled(client: Any, scheduler: str, patience: float, finished: int,
             count: int) -> DaskError:
    try:
        info = client.sync(client.scheduler.identity, n_workers=-1, callback_timeout=10.0)
        workers = len(info["workers"])
    except Exception:  # the scheduler does not answer either: say what is known
        workers = -1
    where = f"{finished} of {count} chunks finished"
    option = "raise dask_progress_timeout (--dask-progress-timeout)"
    if workers == 0:
        return DaskError(
            f"the Dask scheduler at {scheduler} has no workers: no chunk finished for "
            f"{patience:g} s ({where}); start workers (dask worker {scheduler}; each needs "
            f"the same nilpotent installed, a worker that cannot load it stops at its first "
            f"chunk) or {option}")
    return DaskError(
        f"no chunk finished for {patience:g} s on the Dask scheduler at {scheduler} "
        f"({where}; workers: {workers if workers >= 0 else 'unknown'}): a worker may hang, "
        f"or a chunk takes longer; lower the chunk size (--chunk-size) or {option}")


@contextlib.contextmanager
def _quiet(name: str) -> Iterator[None]:
    """Silence logger ``name`` and its descendants inside the block.

    Each descendant is set on its own: Dask's logging configuration gives some
    (``distributed.client``) levels of their own, which a parent's does not override.
    """
    manager = logging.Logger.manager
    names = [name, *(n for n in list(manager.loggerDict) if n.startswith(name + "."))]
    loggers = [logging.getLogger(n) for n in names]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels, strict=True):
            logger.setLevel(level)


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
