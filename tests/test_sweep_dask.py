"""Sweeps through a real Dask scheduler: ``dask scheduler`` + ``dask worker`` processes.

No mock: :func:`nilpotent.simulation.executors.loopback_cluster` starts the scheduler and
two workers as separate processes on 127.0.0.1, the sweep goes to them by address (what
``--dask tcp://HOST:PORT`` does), and the rows must equal a local run's.
"""

from __future__ import annotations

import socket

import numpy as np
import pytest

from nilpotent.models import get_model
from nilpotent.simulation import sweep
from nilpotent.simulation.executors import loopback_cluster

pytest.importorskip("distributed")


def test_sweep_on_a_real_scheduler_equals_the_local_sweep():
    system = get_model("trident-snake")
    kw = dict(samples=1000, radius=0.05, seed=3, design="random", chunk_size=1000,
              time_samples=5)
    amps = [0.01, 0.2]
    with loopback_cluster(workers=2, lifetime=300) as address:
        assert address.startswith("tcp://127.0.0.1:")
        remote = sweep(system, [(1, 2), (2, 3)], amps, dask=address, **kw)
    local = sweep(system, [(1, 2), (2, 3)], amps, **kw)
    assert remote.backend == "dask" and remote.scheduler == address
    assert local.backend == "local"
    assert remote.final_original.shape[0] == 1000
    np.testing.assert_array_equal(local.final_original, remote.final_original)
    np.testing.assert_array_equal(local.final_approximation, remote.final_approximation)
    np.testing.assert_array_equal(local.status_original, remote.status_original)
    for w in local.groups:
        np.testing.assert_array_equal(local.endpoint_by_weight[w], remote.endpoint_by_weight[w])
        np.testing.assert_array_equal(local.along_by_weight[w], remote.along_by_weight[w])
    # the scheduler is gone once the block is left
    host, port = address.removeprefix("tcp://").rsplit(":", 1)
    with pytest.raises(OSError), socket.create_connection((host, int(port)), timeout=2):
        pass


def test_a_cluster_object_is_accepted_and_left_running():
    # a distributed.deploy.Cluster (what dask-jobqueue and dask-kubernetes return), here an
    # in-process LocalCluster: the sweep uses it and leaves it running; rows as local
    import distributed

    system = get_model("unicycle")
    kw = dict(samples=1000, radius=0.05, seed=2, design="random", chunk_size=1000,
              time_samples=3)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        remote = sweep(system, (1, 2), [0.02, 0.1], dask=cluster, **kw)
        assert remote.scheduler == cluster.scheduler_address
        assert cluster.status.name == "running"
    local = sweep(system, (1, 2), [0.02, 0.1], **kw)
    np.testing.assert_array_equal(local.final_original, remote.final_original)
    np.testing.assert_array_equal(local.final_approximation, remote.final_approximation)


# --- faults: nothing hangs, every failure is a clear error -----------------------------
#
# Servers listen on 127.0.0.1 port 0 (the kernel picks a free port: no clashes between
# runs); timeouts are 1-3 s and the elapsed-time bounds are generous upper bounds only.

SLACK = 60.0  # seconds: far above every timeout used here, far below "hangs"


@pytest.fixture
def silent_server():
    """A TCP port that accepts connections and never answers."""
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(16)
    held: list[socket.socket] = []

    def accept() -> None:
        while True:
            try:
                held.append(server.accept()[0])
            except OSError:  # closed at the end of the test
                return

    threading.Thread(target=accept, daemon=True).start()
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    server.close()
    for conn in held:
        conn.close()


@pytest.fixture
def http_server():
    """An HTTP server (http.server) on its own thread."""
    import http.server
    import threading

    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args) -> None:
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Quiet)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


@pytest.fixture
def scheduler_process(tmp_path):
    """A ``dask scheduler`` process without workers: (address, process)."""
    import json
    import subprocess
    import sys
    import time

    file = tmp_path / "scheduler.json"
    proc = subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
         "--port", "0", "--no-dashboard", "--scheduler-file", str(file)],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        address = None
        while address is None and time.monotonic() < deadline and proc.poll() is None:
            try:
                address = json.loads(file.read_text())["address"]
            except (OSError, ValueError, KeyError):
                time.sleep(0.1)
        assert address is not None, "the scheduler did not start"
        yield address, proc
    finally:
        proc.kill()
        proc.wait(30)


@pytest.mark.parametrize("address", [
    "tls://127.0.0.1:8786", "ucx://127.0.0.1:8786", "ws://127.0.0.1:8786",
    "wss://127.0.0.1:8786", "inproc://127.0.0.1/1/1", "http://127.0.0.1:8786",
])
def test_unsupported_schemes_are_refused_naming_the_address(address):
    from nilpotent.errors import OptionError
    from nilpotent.simulation.executors import check_dask

    with pytest.raises(OptionError) as info:
        check_dask(address, 1000)
    message = str(info.value)
    assert repr(address) in message
    assert "tcp://HOST:PORT" in message and address.split("://")[0] + "://" in message


@pytest.mark.parametrize("address", [
    "tcp://127.0.0.1", "tcp://:8786", "tcp://h:0", "tcp://h:65536", "tcp://h:port",
    "h:-1", "tcp://a b:8786", "", "tcp://h:123456789012345678901234567890", "LOCAL",
])
def test_malformed_addresses_are_refused(address):
    from nilpotent.errors import OptionError
    from nilpotent.simulation.executors import check_dask

    with pytest.raises(OptionError, match="not of the form"):
        check_dask(address, 1000)


@pytest.mark.parametrize("value", [0, -1.0, float("nan"), float("inf"), 1e308, "5", True])
def test_bad_timeouts_are_refused(value):
    from nilpotent.errors import OptionError
    from nilpotent.simulation.executors import check_dask

    for name in ("connect_timeout", "progress_timeout"):
        with pytest.raises(OptionError, match=f"--dask-{name.replace('_', '-')}"):
            check_dask("tcp://127.0.0.1:8786", 1000, **{name: value})


def test_timeouts_without_dask_are_refused():
    from nilpotent.errors import OptionError

    with pytest.raises(OptionError, match="Dask only"):
        sweep(get_model("unicycle"), (1, 2), [0.1], dask_progress_timeout=5.0)


@pytest.mark.parametrize("server", ["silent_server", "http_server"])
def test_a_server_that_is_not_a_scheduler_ends_within_the_connect_timeout(server, request):
    import time

    from nilpotent.errors import OptionError
    from nilpotent.simulation.executors import execute

    address = request.getfixturevalue(server)
    t0 = time.monotonic()
    with pytest.raises(OptionError, match="did not answer as a Dask scheduler") as info:
        execute(abs, [1], [1], dask=address, connect_timeout=1.0)
    assert time.monotonic() - t0 < SLACK
    assert address in str(info.value)


def test_a_closed_port_is_unreachable():
    import time

    from nilpotent.errors import OptionError
    from nilpotent.simulation.executors import execute

    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    address = f"tcp://127.0.0.1:{probe.getsockname()[1]}"
    probe.close()  # nothing listens there now
    t0 = time.monotonic()
    with pytest.raises(OptionError, match="cannot reach the Dask scheduler"):
        execute(abs, [1], [1], dask=address, connect_timeout=1.0)
    assert time.monotonic() - t0 < SLACK


def test_a_scheduler_without_workers_is_an_error_after_the_progress_timeout(run_cli, tmp_path):
    # the CLI end to end: exit 2, kind "dask", one JSON object, no CSV left behind
    import json
    import time

    import distributed

    import nilpotent.cli.cmd_sweep  # noqa: F401  (registers the command)

    out = tmp_path / "rows.csv"
    with distributed.LocalCluster(n_workers=0, processes=False, protocol="tcp",
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        address = cluster.scheduler_address
        assert address.startswith("tcp://")
        t0 = time.monotonic()
        status, stdout, _ = run_cli(
            "sweep", "unicycle", "--bracket", "1,2", "--samples", "1000", "--radius", "0.05",
            "--design", "random", "--chunk-size", "1000", "--dask", address,
            "--dask-progress-timeout", "1.5", "--out", str(out), "--json")
        elapsed = time.monotonic() - t0
    assert status == 2 and elapsed < SLACK
    error = json.loads(stdout)["error"]
    assert error["kind"] == "dask"
    assert "no workers" in error["message"] and address in error["message"]
    assert list(tmp_path.iterdir()) == []


def test_a_worker_address_is_not_a_scheduler():
    import distributed

    from nilpotent.errors import OptionError
    from nilpotent.simulation.executors import execute

    with distributed.LocalCluster(n_workers=1, processes=False, protocol="tcp",
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        worker = next(iter(cluster.scheduler.workers))
        with pytest.raises(OptionError, match="Dask Worker, not the scheduler"):
            execute(abs, [1], [1], dask=worker, connect_timeout=3.0)


def test_losing_the_scheduler_mid_run_is_a_clear_error(scheduler_process):
    import threading
    import time

    import distributed

    from nilpotent.errors import DaskError
    from nilpotent.simulation.executors import execute

    address, proc = scheduler_process
    with distributed.Client(address, timeout=30) as client:
        # no workers: the tasks wait; the scheduler dies 1 s into the run, long before
        # the progress timeout, so the error must be the loss
        killer = threading.Timer(1.0, proc.kill)
        killer.start()
        t0 = time.monotonic()
        try:
            with pytest.raises(DaskError, match="lost the connection to the Dask scheduler"):
                execute(abs, [1, 2, 3], [1, 1, 1], dask=client, progress_timeout=SLACK)
        finally:
            killer.cancel()
        assert time.monotonic() - t0 < SLACK


def _square_or_die(task):
    """``k*k``; kills its own worker process the first ``deaths`` times it runs task 0."""
    import os
    import signal

    folder, k, deaths = task
    if k == 0:
        for n in range(deaths):
            try:
                os.close(os.open(os.path.join(folder, f"death-{n}"), os.O_CREAT | os.O_EXCL))
            except FileExistsError:
                continue
            os.kill(os.getpid(), signal.SIGKILL)
    return k * k


@pytest.mark.slow
def test_a_killed_worker_is_retried_and_a_task_that_kills_every_worker_is_an_error(tmp_path):
    # worker processes (nannies restart them); the scheduler here allows one death per task
    import sys

    import cloudpickle
    import dask
    import distributed

    from nilpotent.errors import DaskError
    from nilpotent.simulation.executors import execute

    cloudpickle.register_pickle_by_value(sys.modules[__name__])  # workers lack this module
    try:
        with dask.config.set({"distributed.scheduler.allowed-failures": 1}), \
                distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                         dashboard_address=None) as cluster:
            once = tmp_path / "once"
            once.mkdir()
            done = execute(_square_or_die, [(str(once), k, 1) for k in range(4)], [1] * 4,
                           dask=cluster, progress_timeout=SLACK)
            assert done.outputs == [0, 1, 4, 9]
            assert (once / "death-0").exists()  # the worker did die mid-run
            always = tmp_path / "always"
            always.mkdir()
            with pytest.raises(DaskError, match="workers that died"):
                execute(_square_or_die, [(str(always), k, 10) for k in range(2)], [1] * 2,
                        dask=cluster, progress_timeout=SLACK)
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])


def test_a_chunk_that_never_finishes_is_an_error_after_the_progress_timeout():
    # a worker is there but busy past the timeout (as a hung one would be)
    import time

    import distributed

    from nilpotent.errors import DaskError
    from nilpotent.simulation.executors import execute

    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        t0 = time.monotonic()
        with pytest.raises(DaskError, match=r"no chunk finished for 1 s .*workers: 1\)"):
            execute(time.sleep, [4.0], [1], dask=cluster, progress_timeout=1.0)
        assert time.monotonic() - t0 < SLACK
