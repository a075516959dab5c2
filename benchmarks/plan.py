"""Benchmark of `nilpotent.planning`: iterative nilpotent steering against two baselines.

For each model, random goals at homogeneous distance d ∈ [0.05, 0.5] from a
start (d = max_j |y_j|^{1/w_j} in the privileged coordinates y at the start:
y = δ_d(v) with v uniform on the quasi-sphere, goal = x(y)) are steered to with

* ``iterative``: :func:`nilpotent.planning.plan` (tol 1e-8);
* ``single``: one non-iterated nilpotent step (the controls computed on the
  approximation at the start, applied once to the true system);
* ``shooting``: a generic shooting method, ``scipy.optimize.least_squares``
  (trust-region reflective, finite-difference Jacobian) on the coefficients of
  one segment of sinusoids (constant + harmonics 1..K, K = step + 1, duration 1),
  from a small seeded random guess, the true system integrated by the same
  engine (so only the method differs).

Success = the true system reaches the goal within 1e-8 (Euclidean).  Prints a
table and, with ``--markdown``, the same as a Markdown table for
benchmarks/RESULTS.md.  Timings include everything after the first plan of a
model (which compiles and caches its kernels).

Usage: ``PYTHONPATH=src python benchmarks/plan.py [--goals N] [--models a,b] [--markdown]``.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scipy.optimize import least_squares

from nilpotent.errors import NilpotentError
from nilpotent.models import get_model
from nilpotent.planning import plan
from nilpotent.planning.controls import InputSignal, Segment
from nilpotent.planning.local_model import BUILDERS, choose_builder
from nilpotent.planning.nilpotent import steer_nilpotent
from nilpotent.planning.simulation import PLANNING_SETTINGS, simulate_candidates

TOL = 1e-8
#: The compiled integrator for every method (the warm-up plan compiles it).
ENGINE = "numba"
SETTINGS = PLANNING_SETTINGS.replace(engine=ENGINE)
DEFAULT_MODELS = (
    "trident-snake",
    "trident-snake-paper",
    "unicycle",
    "engel",
    "car-trailers:1",
    "car-trailers:2",
)


def sample_goals(model, count: int, rng: np.random.Generator) -> list[np.ndarray]:
    tri = model.nilpotent
    goals = []
    for _ in range(count):
        v = rng.uniform(-1.0, 1.0, size=tri.n)
        v = tri.dilate(v, 1.0 / tri.quasi_norm(v))
        d = rng.uniform(0.05, 0.5)
        goals.append(model.inverse(tri.dilate(v, d)))
    return goals


def shooting(system, x0: np.ndarray, goal: np.ndarray, k: int, rng) -> tuple[bool, float]:
    m = system.m
    size = m * (2 * k + 1)

    def segments(theta: np.ndarray) -> list[Segment]:
        inputs = []
        for i in range(m):
            c = theta[i * (2 * k + 1) : (i + 1) * (2 * k + 1)]
            inputs.append(InputSignal(c[0], tuple(c[1 : k + 1]), tuple(c[k + 1 :])))
        return [Segment(1.0, 2 * np.pi, tuple(inputs))]

    def residual(theta: np.ndarray) -> np.ndarray:
        end = simulate_candidates(system, x0, [segments(theta)], SETTINGS)[0]
        return np.nan_to_num(end - goal, nan=1e3)

    t = time.perf_counter()
    sol = least_squares(residual, rng.normal(scale=0.1, size=size), xtol=1e-15, ftol=1e-15,
                        gtol=1e-15, max_nfev=200 * size)
    err = float(np.linalg.norm(residual(sol.x)))
    return err <= TOL, time.perf_counter() - t


def run_model(name: str, goals: int, seed: int, shooting_goals: int) -> dict:
    system = get_model(name)
    x0 = np.array([float(v) for v in system.origin()])
    builder = choose_builder(system, x0)
    start_model = BUILDERS[builder](system, system.origin())
    rng = np.random.default_rng(seed)
    targets = sample_goals(start_model, goals, rng)
    # warm-up: compile and cache kernels, symbolic approximation at the start
    plan(system, system.origin(), targets[0], TOL, raise_on_failure=False, settings=SETTINGS)
    ok, iters, times, single_err = 0, [], [], []
    for g in targets:
        t = time.perf_counter()
        try:
            p = plan(system, system.origin(), g, TOL, raise_on_failure=False, settings=SETTINGS)
        except NilpotentError:
            times.append(time.perf_counter() - t)
            continue
        times.append(time.perf_counter() - t)
        if p.converged:
            ok += 1
            iters.append(len(p.iterations))
        # baseline: one nilpotent step from the start, not iterated
        st = steer_nilpotent(start_model.nilpotent, np.zeros(system.n), start_model.forward(g))
        end = simulate_candidates(system, x0, [list(st.segments)], SETTINGS)[0]
        single_err.append(float(np.linalg.norm(end - g)))
    k = start_model.nilpotent.step + 1
    shoot_ok, shoot_t = 0, []
    for g in targets[:shooting_goals]:
        good, dt = shooting(system, x0, g, k, rng)
        shoot_ok += good
        shoot_t.append(dt)
    return {
        "model": name,
        "builder": builder,
        "goals": goals,
        "success": ok / goals,
        "median_iterations": statistics.median(iters) if iters else float("nan"),
        "max_iterations": max(iters) if iters else float("nan"),
        "median_seconds": statistics.median(times),
        "single_success": float(np.mean(np.array(single_err) <= TOL)) if single_err else 0.0,
        "single_median_error": statistics.median(single_err) if single_err else float("nan"),
        "shooting_goals": shooting_goals,
        "shooting_success": shoot_ok / max(shooting_goals, 1),
        "shooting_median_seconds": statistics.median(shoot_t) if shoot_t else float("nan"),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--goals", type=int, default=200, help="goals per model (default 200)")
    ap.add_argument("--shooting-goals", type=int, default=20,
                    help="goals per model for the (slow) shooting baseline (default 20)")
    ap.add_argument("--models", default=",".join(DEFAULT_MODELS))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = ap.parse_args()
    rows = [
        run_model(name, args.goals, args.seed, min(args.shooting_goals, args.goals))
        for name in args.models.split(",")
    ]
    header = ("model", "approx.", "goals", "success", "median it.", "max it.", "median s/plan",
              "1-step success", "1-step median err", "shooting success", "shooting s/plan")
    lines = []
    for r in rows:
        lines.append((
            r["model"], r["builder"], str(r["goals"]), f"{100 * r['success']:.1f}%",
            f"{r['median_iterations']:g}", f"{r['max_iterations']:g}",
            f"{r['median_seconds']:.3f}", f"{100 * r['single_success']:.1f}%",
            f"{r['single_median_error']:.2e}",
            f"{100 * r['shooting_success']:.0f}% of {r['shooting_goals']}",
            f"{r['shooting_median_seconds']:.3f}",
        ))
    if args.markdown:
        print("| " + " | ".join(header) + " |")
        print("|" + "---|" * len(header))
        for line in lines:
            print("| " + " | ".join(line) + " |")
    else:
        widths = [max(len(h), *(len(x[i]) for x in lines)) for i, h in enumerate(header)]
        print("  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True)))
        for line in lines:
            print("  ".join(c.ljust(w) for c, w in zip(line, widths, strict=True)))


if __name__ == "__main__":
    main()
