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
