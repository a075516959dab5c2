"""Benchmark of `nilpotent.core.analysis.filtration.analyze` against plain sympy brackets.

Cases: ``car-trailers:K`` at the origin (regular, step K + 2) for K = 1..K_max
(default 9), and at the configuration where every trailer is perpendicular to the
one before (``theta_i = i*pi/2``; singular, step 3, 5, 8, 13 for K = 1, 2, 3, 4:
the Fibonacci numbers of F. Jean 1996).

* ``nilpotent``: :func:`analyze` on a fresh copy of the system (empty caches),
  everything included (generic growth vector at random points, exact ranks at
  the point, Hall adapted frame); wall-clock and CPU seconds (single thread:
  the CPU figure is what a quiet machine would show as wall-clock).
* ``sympy``: the plain approach: every Hall word of each length, its field by
  nested sympy brackets ``DY·X − DX·Y`` (sympy ``diff``, no expansion), its value
  at the point by ``subs``, the rank by ``Matrix.rank``, until the rank is n.
  Run in a subprocess and stopped after ``--timeout`` seconds (default 60);
  once a K times out, larger K are not run for that family.

Usage: ``PYTHONPATH=src python benchmarks/filtration.py [--max-k 9] [--timeout 60]
[--markdown]``.  Each line: case, family, step, regular, wall and CPU time of
``analyze``, wall time of the sympy baseline, ratio of wall times.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import time

import sympy as sp

from nilpotent.core.analysis.filtration import analyze
from nilpotent.core.lie.brackets import hall_basis, word_length
from nilpotent.core.model.system import ControlSystem
from nilpotent.models import get_model


def fresh_system(k: int) -> ControlSystem:
    """``car-trailers:k`` with its parameters substituted and empty caches."""
    s = get_model(f"car-trailers:{k}").specialized()
    return ControlSystem(s.name, s.coordinates, s.fields, (), s.description)


def case_point(k: int, family: str) -> tuple[sp.Expr, ...]:
    if family == "origin":
        return tuple(sp.Integer(0) for _ in range(k + 3))
    return (sp.Integer(0), sp.Integer(0), *(sp.pi / 2 * i for i in range(k + 1)))


def sympy_baseline(k: int, family: str) -> int:
    """Step of car-trailers:k at the case point by plain nested sympy brackets."""
    sys = fresh_system(k)
    coords = sys.coordinates
    point = dict(zip(coords, case_point(k, family), strict=True))
    fields: dict = {i + 1: sp.Matrix(f) for i, f in enumerate(sys.fields)}

    def field(w):
        if w not in fields:
            X, Y = field(w[0]), field(w[1])
            fields[w] = Y.jacobian(coords) * X - X.jacobian(coords) * Y
        return fields[w]

    rows: list[list[sp.Expr]] = []
    rank = 0
    length = 0
    while rank < sys.n:
        length += 1
        for w in hall_basis(sys.m, length):
            if word_length(w) == length:
                rows.append([e.subs(point) for e in field(w)])
        rank = sp.Matrix(rows).rank()
    return length


def _baseline_worker(k: int, family: str, queue) -> None:
    t0 = time.perf_counter()
    step = sympy_baseline(k, family)
    queue.put((step, time.perf_counter() - t0))


def run_baseline(k: int, family: str, timeout: float) -> tuple[int | None, float | None]:
    queue: mp.Queue = mp.Queue()
    proc = mp.Process(target=_baseline_worker, args=(k, family, queue))
    proc.start()
    proc.join(timeout)
    if proc.is_alive():
        proc.terminate()
        proc.join()
        return None, None
    return queue.get()


def run_ours(k: int, family: str) -> tuple[int, float, float, bool]:
    """Step, wall-clock seconds, CPU seconds of this process, regular verdict."""
    sys = fresh_system(k)
    t0, c0 = time.perf_counter(), time.process_time()
    f = analyze(sys, case_point(k, family))
    return f.step, time.perf_counter() - t0, time.process_time() - c0, f.regular


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-k", type=int, default=9)
    parser.add_argument("--timeout", type=float, default=60.0)
    parser.add_argument("--markdown", action="store_true")
    args = parser.parse_args()
    cases = [("origin", k) for k in range(1, args.max_k + 1)]
    cases += [("perpendicular", k) for k in (1, 2, 3, 4)]
    timed_out: set[str] = set()
    lines = []
    if args.markdown:
        print("| case | point | step | regular | analyze (wall) | analyze (CPU) "
              "| plain sympy (wall) | ratio |")
        print("|---|---|---|---|---|---|---|---|")
    for family, k in cases:
        step, ours, cpu, regular = run_ours(k, family)
        if family in timed_out:
            base_step, base = None, None
            base_text = f"> {args.timeout:.0f} s (not run)"
        else:
            base_step, base = run_baseline(k, family, args.timeout)
            if base is None:
                timed_out.add(family)
                base_text = f"> {args.timeout:.0f} s (stopped)"
            else:
                base_text = f"{base:.2f} s"
        if base is not None and base_step != step:
            raise SystemExit(f"step mismatch for {family} K={k}: {step} vs sympy {base_step}")
        ratio = f"{base / ours:.0f}×" if base is not None else f"> {args.timeout / ours:.0f}×"
        row = (f"car-trailers:{k}", family, step, "yes" if regular else "no", f"{ours:.2f} s",
               f"{cpu:.2f} s", base_text, ratio)
        lines.append(row)
        if args.markdown:
            print("| " + " | ".join(str(c) for c in row) + " |", flush=True)
        else:
            print("  ".join(str(c) for c in row), flush=True)


if __name__ == "__main__":
    main()
