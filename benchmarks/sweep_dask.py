"""Benchmark: a sweep on a real Dask scheduler against the local executor, in one run.

What a user does on a cluster, on this machine: a ``dask scheduler`` and two
``dask worker`` processes (one thread each) are started as separate processes
listening on 127.0.0.1 only
(:func:`nilpotent.simulation.executors.loopback_cluster`: bounded lifetime,
stopped on exit, also on an error); the sweep goes to them by address, as
``nilpotent sweep --dask tcp://127.0.0.1:PORT`` does.  The problem:
``--pairs`` (default 1,000,000) trajectory pairs of ``trident-snake`` (the
original system and its nilpotent approximation at 0), brackets [X1,X2] and
[X2,X3], amplitudes log-uniform in [0.01, 0.2], start points uniform in the
ball of radius 0.05, ``time_samples=2`` (errors at the start and the end),
chunks of ``--chunk`` pairs.  The same sweep runs through the local executor
(this process, the heyoka engine's threads on every core), then through the
scheduler; the rows must be identical.  Wall times exclude the cluster's
start-up (reported separately) and include shipping the chunks and results.

Last line: ``sweep_dask: <P> pairs, local <L> pairs/s, dask <D> pairs/s
(<W> workers), <R>x local, identical: yes|NO``.

Usage: ``python benchmarks/sweep_dask.py [--pairs 1000000] [--chunk 10000]
[--workers 2]``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import time

import numpy as np


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(np.array_equal(a, b, equal_nan=True))


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=1_000_000, help="trajectory pairs")
    parser.add_argument("--chunk", type=int, default=10_000, help="pairs per task (>= 1000)")
    parser.add_argument("--workers", type=int, default=2, help="dask worker processes")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    from nilpotent.models import get_model
    from nilpotent.simulation import sweep
    from nilpotent.simulation.executors import loopback_cluster

    load = os.getloadavg()
    print(f"machine: {os.cpu_count()} CPUs, load average {load[0]:.2f} {load[1]:.2f} "
          f"{load[2]:.2f} at the start; "
          f"{subprocess.run(['date', '-u'], capture_output=True, text=True).stdout.strip()}")
    system = get_model("trident-snake")
    kw = dict(samples=args.pairs, radius=0.05, seed=args.seed, design="random",
              chunk_size=args.chunk, time_samples=2)
    brackets = [(1, 2), (2, 3)]
    amps = [0.01, 0.2]
    sweep(system, brackets, amps, **{**kw, "samples": 2000, "chunk_size": 1000})  # warm-up

    t0 = time.perf_counter()
    local = sweep(system, brackets, amps, **kw)
    t_local = time.perf_counter() - t0
    print(f"local executor (this process, heyoka engine threads on every core): "
          f"{args.pairs:,} pairs in {t_local:.1f} s -> {args.pairs / t_local:,.0f} pairs/s "
          f"(sweep's own wall time {local.wall_time:.1f} s; engine {local.engine})")

    t0 = time.perf_counter()
    with loopback_cluster(workers=args.workers, lifetime=3600) as address:
        t_start = time.perf_counter() - t0
        print(f"dask: scheduler {address} and {args.workers} worker processes (1 thread "
              f"each) started in {t_start:.1f} s")
        # warm-up: every worker imports nilpotent and loads the compiled integrators
        sweep(system, brackets, amps,
              **{**kw, "samples": 1000 * 2 * args.workers, "chunk_size": 1000},
              dask=address)
        t0 = time.perf_counter()
        remote = sweep(system, brackets, amps, **kw, dask=address)
        t_dask = time.perf_counter() - t0
    print(f"dask scheduler path: {args.pairs:,} pairs in {t_dask:.1f} s -> "
          f"{args.pairs / t_dask:,.0f} pairs/s (sweep's own wall time "
          f"{remote.wall_time:.1f} s; backend {remote.backend}, {remote.scheduler})")

    same = (
        _same(local.final_original, remote.final_original)
        and _same(local.final_approximation, remote.final_approximation)
        and _same(local.status_original, remote.status_original)
        and _same(local.status_approximation, remote.status_approximation)
        and all(_same(local.endpoint_by_weight[w], remote.endpoint_by_weight[w])
                and _same(local.along_by_weight[w], remote.along_by_weight[w])
                for w in local.groups)
    )
    ok = int(np.sum(local.status_original == 0))
    print(f"rows identical (end points, statuses, errors by weight): "
          f"{'yes' if same else 'NO'}; {ok:,} of {args.pairs:,} originals integrated to the end")
    load = os.getloadavg()
    print(f"load average at the end: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} "
          "(the machine may be shared: timings are noisy)")
    print(f"sweep_dask: {args.pairs} pairs, local {args.pairs / t_local:.0f} pairs/s, "
          f"dask {args.pairs / t_dask:.0f} pairs/s ({args.workers} workers), "
          f"{t_local / t_dask:.2f}x local, identical: {'yes' if same else 'NO'}")


if __name__ == "__main__":
    main()
