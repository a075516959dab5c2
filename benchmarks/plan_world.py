"""Benchmark of planning among obstacles: our global planners side by side with OMPL's.

Worlds (seeded random start/goal pairs, each admissible):

* ``doorway`` — the trident snake (r = l = 1, default joint limits
  ``|φ_i| ≤ 5π/6``) crosses a wall through a 4.6 wide doorway;
* ``corridor``, ``slalom``, ``clutter`` — the trident snake along a corridor 4.4 wide,
  through a slalom of two walls with passages 4 wide, and across a room of pillars with
  passages 4 wide (issue 20: passages 3.5–4.5);
* ``parking`` — ``car-trailers:1`` parks in a slot 3.6 long and 0.8 deep between two parked
  cars (``examples/worlds/parking.toml``); ``parking2`` — the same with ``car-trailers:2``;
* ``car-parking`` — the built-in ``car`` (x, y, θ, φ; outline of ``car_outline``) in the
  same parking world; ``corner`` — the ``car`` turning the L corridor 1.5 wide of
  ``examples/worlds/corner.toml``.

Methods, same time budget per query, same pairs:

* ``ours``: :func:`nilpotent.planning.global_planner.plan_global` (OMPL RRTConnect path +
  nilpotent steering + subdivision, ``--planner rrtconnect``); success = a plan returned
  (verified: re-simulated, admissible, within ``TOL``);
* ``rrtstar``: the same with ``planner="rrtstar"`` (OMPL RRT* under the ball–box cost,
  :mod:`nilpotent.planning.optimal_planner`);
* ``guide`` (``car``, ``car-trailers:1`` and ``:2`` only): the same with
  ``planner="reeds-shepp"`` (an OMPL Reeds–Shepp path lifted to the car's configurations,
  its legs driven exactly piece by piece, :mod:`nilpotent.planning.guide`; for one trailer,
  the path of the trailer as a car, :mod:`nilpotent.planning.trailer_guide`; for two, the
  lattice search over exact motions, :mod:`nilpotent.planning.trailer_lattice`); every
  method prints the reason of a failure on stderr;
* ``tocp`` (``trident-snake`` only): the same with ``planner="trident-ocp"`` (RRTConnect's
  path, each piece driven by direct optimal control of the body path,
  :mod:`nilpotent.planning.trident_ocp`);
* ``rs`` (``car`` only): OMPL RRT* in ``ReedsSheppStateSpace(rmin)`` (``rmin`` the model's
  parameter), the same validity check (the car's outline with ``φ = 0``) at the
  resolution of OMPL's default; it runs the whole budget (anytime) and the time reported
  is that of its first solution; success = an exact solution;
* ``krrt``: OMPL's kinodynamic RRT (``ompl.control.RRT``; SST has no constructor in the
  PyPI OMPL 2.0 bindings) with piecewise constant controls in ``[-1, 1]^m`` propagated by
  our compiled integrator, the same validity checker; success = within ``KIN_GOAL``.

Measured per success, on an independent dense re-simulation of the controls (scipy
DOP853 on the lambdified fields, 60 samples per segment; the Reeds–Shepp path
interpolated at 0.01): ``xy length`` (the path of the rear axle, or of the trident's
centre), ``reversals`` (sign changes of the drive speed along the heading; vehicles),
``body/holonomic`` (the trident's centre path against the xy length of the holonomic
waypoint path), ``max hitch`` (``max |θ_{i−1} − θ_i|``, degrees) and ``self-collisions``
(plans with a sample whose bodies touch, by the checker's self-clearance on the
re-simulated samples).

Prints a table (``--markdown`` for benchmarks/RESULTS.md).  ``--quick``: one pair per
world, 10 s each, the worlds ``corner,car-parking,corridor,parking,parking2`` and methods
``ours,rrtstar,rs`` (a few minutes).  The compiled kernels are built by a warm-up plan
before timing.

Usage: ``PYTHONPATH=src python benchmarks/plan_world.py [--pairs 50] [--time-limit 20]
[--worlds doorway,parking] [--methods ours,rrtstar,guide,tocp,rs,krrt] [--quick] [--markdown]``.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from nilpotent.errors import NilpotentError
from nilpotent.models import get_model
from nilpotent.numeric.integrate import integrate
from nilpotent.numeric.signals import Signal
from nilpotent.planning.global_planner import plan_global
from nilpotent.planning.local_model import compiled_system
from nilpotent.planning.verify import Checker
from nilpotent.planning.world import World, load_world, world_from_dict

TOL = 1e-6
KIN_GOAL = 0.1
ENGINE = "numba"
PI = math.pi


def _trident(world: dict, start_x: tuple, goal_x: tuple, y: tuple) -> dict:
    return {"model": "trident-snake", "world": world,
            "start": [start_x, y, (-PI, PI), (0, 0), (0, 0), (0, 0)],
            "goal": [goal_x, y, (-PI, PI), (0, 0), (0, 0), (0, 0)]}


PARKING = {
    "name": "parking",
    "bounds": {"x": [-4.0, 6.0], "y": [-1.2, 2.5]},
    "obstacles": [
        {"polygon": [[-4.0, -1.2], [6.0, -1.2], [6.0, -1.0], [-4.0, -1.0]]},
        {"polygon": [[-4.0, -1.0], [-0.8, -1.0], [-0.8, -0.2], [-4.0, -0.2]]},
        {"polygon": [[2.8, -1.0], [6.0, -1.0], [6.0, -0.2], [2.8, -0.2]]},
    ],
}

WORLDS = {
    "doorway": _trident(
        {"name": "doorway", "bounds": {"x": [-6.0, 10.0], "y": [-5.0, 5.0]},
         "obstacles": [{"polygon": [[1.7, -5.0], [2.3, -5.0], [2.3, -2.3], [1.7, -2.3]]},
                       {"polygon": [[1.7, 2.3], [2.3, 2.3], [2.3, 5.0], [1.7, 5.0]]}]},
        (-4.0, -1.0), (5.0, 8.0), (-3.0, 3.0)),
    "corridor": _trident(
        {"name": "corridor", "bounds": {"x": [-6.0, 14.0], "y": [-2.2, 2.2]}, "obstacles": []},
        (-4.0, -2.0), (8.0, 11.0), (-0.2, 0.2)),
    "slalom": _trident(
        {"name": "slalom", "bounds": {"x": [-6.0, 16.0], "y": [-4.0, 4.0]},
         "obstacles": [{"polygon": [[2.0, -4.0], [2.6, -4.0], [2.6, 0.0], [2.0, 0.0]]},
                       {"polygon": [[7.0, 0.0], [7.6, 0.0], [7.6, 4.0], [7.0, 4.0]]}]},
        (-4.0, -2.0), (10.0, 13.0), (-1.5, 1.5)),
    "clutter": _trident(
        {"name": "clutter", "bounds": {"x": [-6.0, 12.0], "y": [-6.0, 6.0]},
         "obstacles": [{"disc": {"center": c, "radius": 0.8}}
                       for c in ([1.0, -2.8], [1.0, 2.8], [6.0, -5.6], [6.0, 0.0],
                                 [6.0, 5.6])]},
        (-4.0, -2.0), (9.0, 10.5), (-2.0, 2.0)),
    "parking": {
        "model": "car-trailers:1", "world": PARKING,
        "start": [(-2.5, 1.0), (0.6, 1.5), (-0.3, 0.3), (-0.3, 0.3)],
        "goal": [(1.6, 1.8), (-0.6, -0.5), (-0.05, 0.05), (-0.05, 0.05)],
    },
    "parking2": {
        "model": "car-trailers:2", "world": PARKING,
        "start": [(-2.0, 1.0), (0.6, 1.5), (-0.3, 0.3), (-0.3, 0.3), (-0.3, 0.3)],
        "goal": [(2.0, 2.2), (-0.6, -0.5), (-0.05, 0.05), (-0.05, 0.05), (-0.05, 0.05)],
    },
    "car-parking": {
        "model": "car", "world": PARKING,
        "start": [(-2.5, 1.0), (0.6, 1.5), (-0.3, 0.3), (0, 0)],
        "goal": [(0.0, 2.0), (-0.6, -0.5), (-0.05, 0.05), (0, 0)],
    },
    "corner": {
        "model": "car", "world": "corner",
        "start": [(0.8, 3.0), (0.5, 1.0), (-0.3, 0.3), (0, 0)],
        "goal": [(6.0, 6.5), (4.0, 6.0), (PI / 2 - 0.3, PI / 2 + 0.3), (0, 0)],
    },
}

QUICK_WORLDS = "corner,car-parking,corridor,parking,parking2"


def world_of(spec: dict) -> World:
    w = spec["world"]
    return load_world(w) if isinstance(w, str) else world_from_dict(w)


def sample_pairs(spec: dict, checker: Checker, count: int, seed: int) -> list[tuple]:
    """``count`` admissible (start, goal) pairs; trailer angles are drawn relative to the
    one ahead (``θ_i = θ_{i−1} + δ_i``)."""
    rng = np.random.default_rng(seed)

    def draw(box: list[tuple[float, float]]) -> np.ndarray:
        while True:
            q = np.array([rng.uniform(lo, hi) if hi > lo else lo for lo, hi in box])
            if spec["model"].startswith("car-trailers"):
                for i in range(3, len(q)):
                    q[i] = q[i - 1] + q[i]
            if checker.valid(q[None, :])[0]:
                return q

    return [(draw(spec["start"]), draw(spec["goal"])) for _ in range(count)]


def row(ok: bool, seconds: float, *, duration: float = math.nan, xy: float = math.nan,
        reversals: float = math.nan, ratio: float = math.nan, hitch: float = math.nan,
        selfcol: bool = False) -> dict:
    return {"ok": ok, "t": seconds, "duration": duration, "xy": xy, "reversals": reversals,
            "ratio": ratio, "hitch": hitch, "selfcol": selfcol}


def resimulate(system, start, segments, samples: int = 60) -> tuple[np.ndarray, np.ndarray]:
    """States (N, n) and drive inputs (N,) under the segments (scipy DOP853, lambdified)."""
    mat = sp.lambdify([system.coordinates], sp.Matrix(system.specialized_fields).T, "numpy")
    x = np.asarray(start, dtype=float)
    states, drive = [x[None, :]], [np.zeros(1)]
    for seg in segments:
        def u(t, seg=seg):
            return seg.values(np.atleast_1d(t))[:, 0]

        ts = np.linspace(0, seg.duration, samples)
        sol = solve_ivp(lambda t, z, u=u: np.asarray(mat(z), dtype=float) @ u(t),
                        (0, seg.duration), x, method="DOP853", rtol=1e-10, atol=1e-12,
                        t_eval=ts)
        states.append(sol.y.T[1:])
        drive.append(seg.values(ts)[0][1:])
        x = sol.y[:, -1]
    return np.vstack(states), np.concatenate(drive)


def sign_changes(v: np.ndarray) -> int:
    big = float(np.abs(v).max()) if v.size else 0.0
    signs = np.sign(v[np.abs(v) > 1e-6 * big]) if big > 0 else np.array([])
    return int(np.count_nonzero(np.diff(signs)))


def xy_length(q: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(q[:, :2], axis=0), axis=1).sum())


def run_ours(system, world: World, checker: Checker, start, goal, budget: float, seed: int,
             planner: str) -> dict:
    t = time.perf_counter()
    try:
        g = plan_global(system, start, goal, TOL, world=world, time_limit=budget, seed=seed,
                        engine=ENGINE, planner=planner)
    except NilpotentError as e:
        print(f"  {planner} failed: {e}", file=sys.stderr)
        return row(False, time.perf_counter() - t)
    seconds = time.perf_counter() - t
    q, drive = resimulate(system, start, g.plan.segments)
    name = system.name
    vehicle = name == "car" or name.startswith("car-trailers")
    holonomic = xy_length(np.array(g.waypoints))
    hitch = math.nan
    if name.startswith("car-trailers"):
        hitch = math.degrees(float(np.abs(np.diff(q[:, 2:], axis=1)).max()))
    selfish = checker.robot.has_self_collision  # type: ignore[attr-defined]
    selfcol = bool(selfish and not np.all(checker.self_clearance(q) > 0))
    return row(True, seconds, duration=g.plan.duration, xy=xy_length(q),
               reversals=sign_changes(drive) if vehicle else math.nan,
               ratio=xy_length(q) / holonomic if holonomic > 0 else math.nan,
               hitch=hitch, selfcol=selfcol)


def run_reeds_shepp(system, checker: Checker, start, goal, budget: float, seed: int) -> dict:
    """OMPL RRT* in ReedsSheppStateSpace(rmin), the car's outline with φ = 0."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    ou.RNG.setSeed(seed + 1)
    rmin = float(dict(system.parameters)["rmin"])
    space = ob.ReedsSheppStateSpace(rmin)
    bounds = ob.RealVectorBounds(2)
    assert checker.world is not None and checker.world.bounds is not None
    for axis in range(2):
        bounds.setLow(axis, float(checker.world.bounds[axis][0]))
        bounds.setHigh(axis, float(checker.world.bounds[axis][1]))
    space.setBounds(bounds)
    si = ob.SpaceInformation(space)

    def as_q(state) -> np.ndarray:
        return np.array([state.getX(), state.getY(), state.getYaw(), 0.0])

    si.setStateValidityChecker(lambda s: bool(checker.valid(as_q(s)[None, :])[0]))
    si.setStateValidityCheckingResolution(0.005)
    si.setup()
    s, g = space.allocState(), space.allocState()
    for st, q in ((s, start), (g, goal)):
        st.setX(float(q[0]))
        st.setY(float(q[1]))
        st.setYaw(float(q[2]))
    pdef = ob.ProblemDefinition(si)
    pdef.setStartAndGoalStates(s, g)
    pdef.setOptimizationObjective(ob.PathLengthOptimizationObjective(si))
    planner = og.RRTstar(si)
    planner.setProblemDefinition(pdef)
    planner.setup()
    t0 = time.perf_counter()
    first = None
    while time.perf_counter() - t0 < budget:
        planner.solve(min(0.25, budget - (time.perf_counter() - t0)))
        if first is None and pdef.hasExactSolution():
            first = time.perf_counter() - t0
    if first is None:
        return row(False, time.perf_counter() - t0)
    path = pdef.getSolutionPath()
    path.interpolate(max(2, int(path.length() / 0.01)))
    q = np.array([as_q(path.getState(i)) for i in range(path.getStateCount())])
    d = np.diff(q[:, :2], axis=0)
    along = d[:, 0] * np.cos(q[:-1, 2]) + d[:, 1] * np.sin(q[:-1, 2])
    planner.clear()
    return row(True, first, xy=xy_length(q), reversals=sign_changes(along))


def run_kinodynamic(system, checker: Checker, start, goal, budget: float, seed: int) -> tuple:
    from ompl import base as ob
    from ompl import control as oc
    from ompl import util as ou

    from nilpotent.planning.holonomic_path import box

    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    ou.RNG.setSeed(seed + 1)
    n, m = system.n, system.m
    compiled = compiled_system(system)
    lo, hi = box(checker, np.asarray(start), np.asarray(goal))
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
        return row(False, seconds)
    path = setup.getSolutionPath()
    duration = float(sum(path.getControlDurations()))
    return row(True, seconds, duration=duration)


def median(values: list[float]) -> float:
    vals = [v for v in values if not math.isnan(v)]
    return statistics.median(vals) if vals else math.nan


def summary(rows: list[dict], budget: float) -> dict:
    """Success rate (a plan within the budget: later counts as a failure), median time of
    all queries, and medians over the successes."""
    ok = [r for r in rows if r["ok"] and r["t"] <= budget]
    return {
        "success": 100.0 * len(ok) / len(rows) if rows else math.nan,
        "t_all": median([r["t"] for r in rows]),
        "t_ok": median([r["t"] for r in ok]),
        "xy": median([r["xy"] for r in ok]),
        "reversals": median([r["reversals"] for r in ok]),
        "max_reversals": max((r["reversals"] for r in ok if not math.isnan(r["reversals"])),
                             default=math.nan),
        "ratio": median([r["ratio"] for r in ok]),
        "hitch": max((r["hitch"] for r in ok if not math.isnan(r["hitch"])),
                     default=math.nan),
        "selfcol": sum(1 for r in ok if r["selfcol"]),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pairs", type=int, default=50)
    ap.add_argument("--time-limit", type=float, default=20.0)
    ap.add_argument("--worlds", default="doorway,parking")
    ap.add_argument("--methods", default="ours,krrt")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--quick", action="store_true",
                    help="one pair per world, 10 s, worlds " + QUICK_WORLDS
                         + ", methods ours,rrtstar,rs (unless given)")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    given = {a.split("=")[0] for a in sys.argv[1:]}
    if args.quick:
        args.pairs = args.pairs if "--pairs" in given else 1
        args.time_limit = args.time_limit if "--time-limit" in given else 10.0
        args.worlds = args.worlds if "--worlds" in given else QUICK_WORLDS
        args.methods = args.methods if "--methods" in given else "ours,rrtstar,rs"
    lines = []
    for wname in args.worlds.split(","):
        spec = WORLDS[wname]
        system = get_model(spec["model"])
        world = world_of(spec)
        checker = Checker(system, world)
        pairs = sample_pairs(spec, checker, args.pairs, args.seed)
        # warm-up: compile the kernels (not timed)
        plan_global(system, pairs[0][0], pairs[0][0] + 1e-3 * (pairs[0][1] - pairs[0][0]), TOL,
                    world=world, engine=ENGINE, time_limit=600)
        for method in args.methods.split(","):
            if (method == "rs" and system.name != "car") or (
                    method == "guide" and spec["model"] not in ("car", "car-trailers:1",
                                                           "car-trailers:2")) or (
                    method == "tocp" and spec["model"] != "trident-snake"):
                continue
            rows = []
            for k, (a, b) in enumerate(pairs):
                seed = args.seed + k
                if method in ("ours", "rrtstar", "guide", "tocp"):
                    planner = {"ours": "rrtconnect", "rrtstar": "rrtstar",
                               "guide": "reeds-shepp", "tocp": "trident-ocp"}[method]
                    rows.append(run_ours(system, world, checker, a, b, args.time_limit, seed,
                                         planner))
                elif method == "rs":
                    rows.append(run_reeds_shepp(system, checker, a, b, args.time_limit, seed))
                else:
                    rows.append(run_kinodynamic(system, checker, a, b, args.time_limit, seed))
                r = rows[-1]
                print(f"{wname} {method} {k}: ok={r['ok']} t={r['t']:.2f}s xy={r['xy']:.3g} "
                      f"reversals={r['reversals']} ratio={r['ratio']:.3g} "
                      f"hitch={r['hitch']:.3g} selfcol={r['selfcol']}", flush=True)
            lines.append((wname, spec["model"], method, len(rows),
                          summary(rows, args.time_limit)))
    print()
    header = ("world", "model", "method", "pairs", "success %", "median s (all)",
              "median s (ok)", "median xy length", "median reversals (max)",
              "median body/holonomic", "max hitch °", "self-colliding plans")
    fmt = "{:.3g}".format
    if args.markdown:
        print("| " + " | ".join(header) + " |")
        print("|" + "---|" * len(header))
    for w, model, method, count, s in lines:
        cells = [w, model, method, str(count), f"{s['success']:.0f}", f"{s['t_all']:.2f}",
                 f"{s['t_ok']:.2f}", fmt(s["xy"]),
                 f"{fmt(s['reversals'])} ({fmt(s['max_reversals'])})", fmt(s["ratio"]),
                 fmt(s["hitch"]), str(s["selfcol"])]
        print("| " + " | ".join(cells) + " |" if args.markdown else " ".join(cells))


if __name__ == "__main__":
    main()
