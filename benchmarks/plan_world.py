"""Benchmark of planning among obstacles: the global planner against OMPL's kinodynamic RRT.

Two worlds, seeded random start/goal pairs:

* ``doorway`` — the trident snake (r = l = 1, default joint limits
  ``|φ_i| ≤ 5π/6``) crosses a wall through a 4.6 wide doorway (the robot is
  about 3.5 across at best: it passes only near the middle); starts in the
  left room, goals in the right room, random headings, legs straight;
* ``parking`` — ``car-trailers:1`` (rectangles of ``nilpotent.models.outlines``)
  parks in a slot 3.6 long (the car with its trailer is 1.9 long) and 0.8
  deep between two parked cars, from random poses on the street.

Methods, same time budget per query:

* ``ours``: :func:`nilpotent.planning.global_planner.plan_global` (OMPL
  RRTConnect path + nilpotent steering + subdivision), ``tol`` below; success
  = a plan returned (it is verified: re-simulated, admissible, within tol);
* ``krrt``: OMPL's kinodynamic planner with piecewise constant controls in
  ``[-1, 1]^m`` propagated by our compiled integrator (numba DOP853 through
  :func:`nilpotent.numeric.integrate.integrate`), the same validity checker;
  success = an exact solution within the goal radius ``KIN_GOAL`` (far coarser
  than ``ours``' tol: sampling-based kinodynamic planners cannot steer
  exactly).  The issue asked for ``ompl.control.SST``, but the PyPI OMPL 2.0
  Python bindings declare ``SST`` without a constructor (``bindings/control/
  planners/sst/SST.cpp``: "TODO [oc::SST][IMPLEMENT]"), so it cannot be
  created from Python; ``ompl.control.RRT`` (kinodynamic RRT, LaValle–Kuffner)
  is the constructible kinodynamic planner used instead.

Prints a table (``--markdown`` for benchmarks/RESULTS.md).  The compiled
kernels are built by a warm-up plan before timing.

Usage: ``PYTHONPATH=src python benchmarks/plan_world.py [--pairs 50] [--time-limit 20]
[--worlds doorway,parking] [--methods ours,krrt] [--markdown]``.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np

from nilpotent.errors import NilpotentError
from nilpotent.models import get_model
from nilpotent.numeric.integrate import integrate
from nilpotent.numeric.signals import Signal
from nilpotent.planning.global_planner import plan_global
from nilpotent.planning.local_model import compiled_system
from nilpotent.planning.verify import Checker
from nilpotent.planning.world import World, world_from_dict

TOL = 1e-6
KIN_GOAL = 0.1
ENGINE = "numba"

WORLDS = {
    "doorway": {
        "model": "trident-snake",
        "world": {
            "name": "doorway",
            "bounds": {"x": [-6.0, 10.0], "y": [-5.0, 5.0]},
            "obstacles": [
                {"polygon": [[1.7, -5.0], [2.3, -5.0], [2.3, -2.3], [1.7, -2.3]]},
                {"polygon": [[1.7, 2.3], [2.3, 2.3], [2.3, 5.0], [1.7, 5.0]]},
            ],
        },
        # (low, high) of each coordinate for starts and goals
        "start": [(-4.0, -1.0), (-3.0, 3.0), (-math.pi, math.pi), (0, 0), (0, 0), (0, 0)],
        "goal": [(5.0, 8.0), (-3.0, 3.0), (-math.pi, math.pi), (0, 0), (0, 0), (0, 0)],
    },
    "parking": {
        "model": "car-trailers:1",
        "world": {
            "name": "parking",
            "bounds": {"x": [-4.0, 6.0], "y": [-1.2, 2.5]},
            "obstacles": [
                {"polygon": [[-4.0, -1.2], [6.0, -1.2], [6.0, -1.0], [-4.0, -1.0]]},
                {"polygon": [[-4.0, -1.0], [-0.8, -1.0], [-0.8, -0.2], [-4.0, -0.2]]},
                {"polygon": [[2.8, -1.0], [6.0, -1.0], [6.0, -0.2], [2.8, -0.2]]},
            ],
        },
        "start": [(-2.5, 1.0), (0.6, 1.5), (-0.3, 0.3), (-0.3, 0.3)],
        "goal": [(1.6, 1.8), (-0.6, -0.5), (-0.05, 0.05), (-0.05, 0.05)],
    },
}


def sample_pairs(spec: dict, checker: Checker, count: int, seed: int) -> list[tuple]:
    """``count`` admissible (start, goal) pairs; a leg/trailer angle is drawn relative to the
    heading for the car (``θ1 = θ0 + δ``)."""
    rng = np.random.default_rng(seed)

    def draw(box: list[tuple[float, float]]) -> np.ndarray:
        while True:
            q = np.array([rng.uniform(lo, hi) if hi > lo else lo for lo, hi in box])
            if spec["model"].startswith("car-trailers"):
                q[3] = q[2] + q[3]
            if checker.valid(q[None, :])[0]:
                return q

    return [(draw(spec["start"]), draw(spec["goal"])) for _ in range(count)]


def run_ours(system, world: World, start, goal, budget: float, seed: int) -> tuple:
    t = time.perf_counter()
    try:
        g = plan_global(system, start, goal, TOL, world=world, time_limit=budget, seed=seed,
                        engine=ENGINE)
    except NilpotentError:
        return False, time.perf_counter() - t, math.nan, math.nan
    return True, time.perf_counter() - t, g.plan.duration, g.verification.clearance


def run_kinodynamic(system, checker: Checker, start, goal, budget: float, seed: int) -> tuple:
    from ompl import base as ob
    from ompl import control as oc
    from ompl import util as ou

    from nilpotent.planning.global_planner import _box

    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    ou.RNG.setSeed(seed + 1)
    n, m = system.n, system.m
    compiled = compiled_system(system)
    lo, hi = _box(checker, np.asarray(start), np.asarray(goal))
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for j in range(n):
        bounds.setLow(j, float(lo[j]))
        bounds.setHigh(j, float(hi[j]))
    space.setBounds(bounds)
    cspace = oc.RealVectorControlSpace(space, m)
    cb = ob.RealVectorBounds(m)
    for i in range(m):
        cb.setLow(i, -1.0)
        cb.setHigh(i, 1.0)
    cspace.setBounds(cb)
    setup = oc.SimpleSetup(cspace)

    def valid(state) -> bool:
        q = np.array([state[j] for j in range(n)])
        return bool(checker.valid(q[None, :])[0])

    zeros = np.zeros((1, 1, m, 0))

    def propagate(state, control, duration, result) -> None:
        x = np.array([state[j] for j in range(n)])
        u = np.array([control[i] for i in range(m)])
        inputs = Signal(np.array([[duration]]), np.zeros((1, 1)), u[None, None, :],
                        zeros, zeros)
        sol = integrate(compiled, x[None, :], inputs, engine=ENGINE, rtol=1e-8, atol=1e-10)
        y = np.asarray(sol.final)[0]
        for j in range(n):
            result[j] = float(y[j])

    setup.setStateValidityChecker(valid)
    setup.setStatePropagator(propagate)
    si = setup.getSpaceInformation()
    si.setPropagationStepSize(0.1)
    si.setMinMaxControlDuration(1, 10)
    s, g = space.allocState(), space.allocState()
    for j in range(n):
        s[j], g[j] = float(start[j]), float(goal[j])
    setup.setStartAndGoalStates(s, g, KIN_GOAL)
    setup.setPlanner(oc.RRT(si))
    t = time.perf_counter()
    status = setup.solve(budget)
    seconds = time.perf_counter() - t
    if not (status and setup.haveExactSolutionPath()):
        return False, seconds, math.nan, math.nan
    path = setup.getSolutionPath()
    duration = float(sum(path.getControlDurations()))
    return True, seconds, duration, math.nan


def summary(rows: list[tuple], budget: float) -> tuple[float, float, float, float]:
    """Success rate (a plan within the budget: a plan found later counts as a failure),
    median time of all queries, median time and path duration of the successes."""
    ok = [r for r in rows if r[0] and r[1] <= budget]
    rate = 100.0 * len(ok) / len(rows) if rows else math.nan
    med_t = statistics.median(r[1] for r in rows) if rows else math.nan
    med_ok_t = statistics.median(r[1] for r in ok) if ok else math.nan
    med_d = statistics.median(r[2] for r in ok) if ok else math.nan
    return rate, med_t, med_ok_t, med_d


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pairs", type=int, default=50)
    ap.add_argument("--time-limit", type=float, default=20.0)
    ap.add_argument("--worlds", default="doorway,parking")
    ap.add_argument("--methods", default="ours,krrt")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    lines = []
    for wname in args.worlds.split(","):
        spec = WORLDS[wname]
        system = get_model(spec["model"])
        world = world_from_dict(spec["world"])
        checker = Checker(system, world)
        pairs = sample_pairs(spec, checker, args.pairs, args.seed)
        # warm-up: compile the kernels (not timed)
        plan_global(system, pairs[0][0], pairs[0][0] + 1e-3 * (pairs[0][1] - pairs[0][0]), TOL,
                    world=world, engine=ENGINE, time_limit=600)
        for method in args.methods.split(","):
            rows = []
            for k, (a, b) in enumerate(pairs):
                if method == "ours":
                    rows.append(run_ours(system, world, a, b, args.time_limit, args.seed + k))
                else:
                    rows.append(
                        run_kinodynamic(system, checker, a, b, args.time_limit, args.seed + k)
                    )
                print(f"{wname} {method} {k}: ok={rows[-1][0]} t={rows[-1][1]:.2f}s "
                      f"duration={rows[-1][2]:.3g} clearance={rows[-1][3]:.3g}", flush=True)
            rate, med_t, med_ok_t, med_d = summary(rows, args.time_limit)
            lines.append((wname, spec["model"], method, len(rows), rate, med_t, med_ok_t, med_d))
    print()
    header = ("world", "model", "method", "pairs", "success %", "median s (all)",
              "median s (successes)", "median path duration")
    if args.markdown:
        print("| " + " | ".join(header) + " |")
        print("|" + "---|" * len(header))
        for row in lines:
            print(f"| {row[0]} | {row[1]} | {row[2]} | {row[3]} | {row[4]:.0f} | {row[5]:.2f} "
                  f"| {row[6]:.2f} | {row[7]:.3g} |")
    else:
        for row in lines:
            print(*row)


if __name__ == "__main__":
    main()
