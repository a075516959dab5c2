"""Benchmark: what the command line costs a user, in CPU seconds, against the library.

What ``nilpotent sweep`` and ``nilpotent reproduce`` cost as a user runs them (a
fresh process each: imports, loading the compiled integrators from the on-disk
cache, the work, printing), in CPU seconds of the child process
(``resource.getrusage(RUSAGE_CHILDREN)``: user + system, all its threads), so
that a loaded, shared machine changes the figure less than wall time would.

(a) baseline, in this process: :func:`nilpotent.simulation.sweep` of the same
    sweep with ``time_samples=2`` (errors at the start and the end only, as
    ``benchmarks/sweep_dask.py``), after a warm-up; CPU seconds of this process
    (``time.process_time``);
(b) ``nilpotent --version`` (start-up: Python and the CLI's imports);
(c) ``nilpotent sweep trident-snake --bracket 1,2 --amplitudes 0.01:0.3:8
    --samples S --radius 0.01 --json`` with the default ``--time-samples 33``;
(d) the same with ``--time-samples 2``;
(e) with ``--reproduce``: ``nilpotent reproduce --out DIR`` (and ``--quick``).

The last line is ``cli_speed: sweep <P> pairs: <R33> pairs/CPU-s (33 time samples),
<R2> pairs/CPU-s (2), library <L> pairs/CPU-s; CLI/library <X>x``.

Usage: ``python benchmarks/cli_speed.py [--samples 2000] [--reproduce]``.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _child_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _run(args: list[str]) -> tuple[float, float]:
    """CPU seconds and wall seconds of ``nilpotent ARGS`` in a fresh process."""
    cpu0, wall0 = _child_cpu(), time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "nilpotent", *args], capture_output=True,
                          text=True, check=False)
    cpu, wall = _child_cpu() - cpu0, time.perf_counter() - wall0
    if done.returncode != 0:
        raise SystemExit(f"nilpotent {' '.join(args)} failed ({done.returncode}):\n"
                         f"{done.stderr[-2000:]}")
    return cpu, wall


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=2000, help="start points per amplitude")
    parser.add_argument("--reproduce", action="store_true", help="also time `reproduce`")
    args = parser.parse_args(argv)

    from nilpotent.models import get_model
    from nilpotent.simulation import amplitude_range, sweep

    load = os.getloadavg()
    print(f"machine: {os.cpu_count()} CPUs, load average {load[0]:.2f} {load[1]:.2f} "
          f"{load[2]:.2f} at the start (shared and noisy: CPU seconds are reported)")
    amps = list(amplitude_range(0.01, 0.3, 8))
    pairs = len(amps) * args.samples
    system = get_model("trident-snake")
    kw = dict(samples=args.samples, radius=0.01, seed=0, time_samples=2)
    sweep(system, [(1, 2)], amps, **{**kw, "samples": 50})  # warm-up: compile or load
    cpu0 = time.process_time()
    sweep(system, [(1, 2)], amps, **kw)
    library = time.process_time() - cpu0
    print(f"(a) library sweep(), this process, time_samples=2: {pairs:,} pairs in "
          f"{library:.2f} CPU-s -> {pairs / library:,.0f} pairs/CPU-s")

    start, start_wall = _run(["--version"])
    print(f"(b) nilpotent --version: {start:.2f} CPU-s ({start_wall:.2f} s wall)")
    command = ["sweep", "trident-snake", "--bracket", "1,2", "--amplitudes", "0.01:0.3:8",
               "--samples", str(args.samples), "--radius", "0.01", "--json", "--quiet"]
    rates = {}
    for n, label in ((33, "c"), (2, "d")):
        cpu, wall = _run([*command, "--time-samples", str(n)])
        rates[n] = pairs / cpu
        print(f"({label}) nilpotent sweep ... --time-samples {n}: {pairs:,} pairs in "
              f"{cpu:.2f} CPU-s ({wall:.2f} s wall) -> {rates[n]:,.0f} pairs/CPU-s, "
              f"{(cpu - start) / library:.1f}x the library's CPU time after start-up")
    if args.reproduce:
        for extra in (["--quick"], []):
            with tempfile.TemporaryDirectory() as tmp:
                cpu, wall = _run(["reproduce", "--out", str(Path(tmp) / "paper"), "--quiet",
                                  *extra])
            print(f"(e) nilpotent reproduce {' '.join(extra)}: {cpu:.1f} CPU-s "
                  f"({wall:.1f} s wall)")
    load = os.getloadavg()
    print(f"load average at the end: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    print(f"cli_speed: sweep {pairs} pairs: {rates[33]:.0f} pairs/CPU-s (33 time samples), "
          f"{rates[2]:.0f} pairs/CPU-s (2), library {pairs / library:.0f} pairs/CPU-s; "
          f"CLI/library {rates[2] / (pairs / library):.2f}x")


if __name__ == "__main__":
    main()
