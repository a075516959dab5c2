"""Benchmark of plan quality: lengths against the exact sub-Riemannian distance, and speed.

Heisenberg (``heisenberg`` model: ``ẋ₃ = (x₁u₂ − x₂u₁)/2``), seeded random goals
(normal directions, sizes uniform in [0.1, 2]); the exact distance is Dido's
closed form (an arc of angle φ with ``|x₃|/r² = (φ − sin φ)/(8 sin²(φ/2))``,
``d = rφ/(2 sin(φ/2))``), implemented here independently of the product.

* ``reach``: today's local steering (``steer_nilpotent``, straight segment + loops);
* ``length``: the shortest-geodesic steering (``method="geodesic"``);
* ``shooting``: the named baseline, ``scipy.optimize.minimize`` (SLSQP) on a
  direct-shooting discretisation (16 piecewise-constant controls, the Heisenberg
  flow of each piece exact by hand), minimising ``Σ‖u_k‖²`` under the endpoint
  constraint, from the straight line plus a seeded perturbation;

each as a warm local steering call (median time over the goals, after one warm-up
call), and the length / exact distance ratio.  Then whole plans
(:func:`nilpotent.planning.plan`, both objectives) on the true model: Heisenberg
(ratio to the exact distance) and the trident snake (ratio to the geodesic
distance of its free (3,6) approximation at the start, ``lower_bound``).

The ``car`` (x, y, θ, φ; step 3), obstacle-free, as ``nilpotent plan car`` runs it
(:func:`~nilpotent.planning.global_planner.plan_global`, the model's steering limit
``|φ| ≤ atan 0.6``, turning radius ≥ 1): the lateral shift ``y = 1`` and seeded goals
(``x, y`` uniform in [−1.5, 1.5], ``θ`` in [−π/2, π/2], ``φ = 0``), both objectives,
against the Reeds–Shepp optimum of radius 1 (OMPL's ``ReedsSheppStateSpace``): the
rear-axle path length ``∫|v| dt`` (``v`` the drive input) and the sub-Riemannian
length ``∫‖(v, φ̇)‖ dt``, the reversals of ``v`` (sign changes) against those of the
Reeds–Shepp path (sign changes of its motion along the heading, sampled), CPU and
wall seconds per plan.

The step-2 boundary problem itself (:func:`~nilpotent.planning.geodesic.shortest_geodesic`,
warm calls, CPU and wall milliseconds) is timed against the named baseline
``previous multi-start LM`` (:func:`previous_multistart_length`: the solver before
the closed forms, the Van Loan block exponential and five starts), run in the same
process: Heisenberg (ratio to the exact distance), the trident snake's free (3,6)
approximation at the start (ratio to the baseline's length, and how often the
baseline found nothing), and (3,6) goals with ``x ⊥ w`` in random orientations,
whose distance is Dido's (the projection on the plane ⊥ ``w`` is no longer).

Last, ``--ocp N`` (default 5; 0 skips it): the refinement by direct optimal control of
the true system (``refine="ocp"``, :mod:`nilpotent.planning.ocp`, CasADi + IPOPT) of
N warm-start plans per model (see :func:`ocp_section`).

Usage: ``PYTHONPATH=src python benchmarks/plan_quality.py [--goals 20] [--trident 5]
[--car 8] [--only-car] [--ocp 5]``.
"""

from __future__ import annotations

import argparse
import itertools
import math
import statistics
import time

import numpy as np
import sympy as sp
from scipy.optimize import brentq, minimize

from nilpotent.models import get_model
from nilpotent.planning import TriangularSystem, plan, steer_nilpotent
from nilpotent.planning.geodesic import (
    Step2Structure,
    _first_guess,
    _lm,
    _starts,
    _van_loan_integrals,
    control_length,
    shortest_geodesic,
)
from nilpotent.planning.local_model import numeric_model


def heisenberg_distance(x1: float, x2: float, x3: float) -> float:
    r, z = math.hypot(x1, x2), abs(x3)
    if r == 0:
        return math.sqrt(4 * math.pi * z)
    if z == 0:
        return r
    q = z / r**2
    phi = brentq(lambda p: (p - math.sin(p)) / (8 * math.sin(p / 2) ** 2) - q,
                 1e-9, 2 * math.pi - 1e-12, xtol=1e-15)
    return r * phi / (2 * math.sin(phi / 2))


def shooting(goal: np.ndarray, k: int, rng: np.random.Generator) -> float:
    """Length of the SLSQP direct-shooting solution (piecewise constant, k pieces)."""

    def end(flat: np.ndarray) -> np.ndarray:
        u = flat.reshape(k, 2)
        h = np.vstack([np.zeros(2), np.cumsum(u, axis=0) / k])[:-1]
        z = np.sum(h[:, 0] * u[:, 1] - h[:, 1] * u[:, 0]) / (2 * k)
        return np.array([*(h[-1] + u[-1] / k), z])

    guess = np.tile(goal[:2], (k, 1)) + 0.3 * rng.normal(size=(k, 2))
    res = minimize(lambda f: float(np.sum(f**2)) / k, guess.ravel(), method="SLSQP",
                   constraints={"type": "eq", "fun": lambda f: end(f) - goal},
                   options={"maxiter": 300, "ftol": 1e-12})
    if np.max(np.abs(end(res.x) - goal)) > 1e-8:
        return math.inf
    return float(np.sum(np.linalg.norm(res.x.reshape(k, 2), axis=1)) / k)


def timed(fn, *args, **kwargs):
    t = time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - t


def summary(name: str, ratios: list[float], seconds: list[float]) -> str:
    return (f"| {name} | {statistics.median(ratios):.4f} | {max(ratios):.4f} | "
            f"{1e3 * statistics.median(seconds):.2f} |")


def reeds_shepp(goal: np.ndarray, radius: float = 1.0) -> tuple[float, int]:
    """Length and reversals of the Reeds–Shepp optimum from the origin (OMPL)."""
    from ompl import base as ob

    space = ob.ReedsSheppStateSpace(radius)
    a, b, c = space.allocState(), space.allocState(), space.allocState()
    a.setX(0.0), a.setY(0.0), a.setYaw(0.0)
    b.setX(float(goal[0])), b.setY(float(goal[1])), b.setYaw(float(goal[2]))
    pts = []
    for t in np.linspace(0.0, 1.0, 2001):
        space.interpolate(a, b, float(t), c)
        pts.append((c.getX(), c.getY(), c.getYaw()))
    q = np.array(pts)
    d = np.diff(q[:, :2], axis=0)
    along = d[:, 0] * np.cos(q[:-1, 2]) + d[:, 1] * np.sin(q[:-1, 2])
    signs = np.sign(along[np.abs(along) > 1e-9])
    return float(space.distance(a, b)), int(np.sum(signs[1:] != signs[:-1]))


def drive_profile(segments) -> tuple[float, int]:
    """``∫|v| dt`` (rear-axle path length) and sign changes of the drive input ``v``."""
    path, values = 0.0, []
    for seg in segments:
        t = np.linspace(0.0, seg.duration, 2001)
        v = seg.values(t)[0]
        path += float(np.sum(np.abs(v[1:]) + np.abs(v[:-1])) * (t[1] - t[0]) / 2)
        values.append(v)
    v = np.concatenate(values) if values else np.zeros(1)
    signs = np.sign(v[np.abs(v) > 1e-6 * max(1e-300, float(np.max(np.abs(v))))])
    return path, int(np.sum(signs[1:] != signs[:-1]))


def car_benchmark(count: int, seed: int, ocp_starts: int = 0) -> None:
    """The car against Reeds–Shepp: ``reach`` and ``length`` plans, and with ``ocp_starts``
    the ``length`` plan refined by direct optimal control as ``nilpotent plan car
    --objective length --refine ocp --input-weights u2=1/10 --refine-starts N`` runs it."""
    from nilpotent.planning.global_planner import plan_global
    from nilpotent.planning.ocp import OcpRefine

    rng = np.random.default_rng(seed)
    goals = [np.array([0.0, 1.0, 0.0, 0.0])]
    goals += [np.array([*rng.uniform(-1.5, 1.5, 2), rng.uniform(-math.pi / 2, math.pi / 2), 0.0])
              for _ in range(count - 1)]
    car = get_model("car")
    print("\n## car, obstacle-free, against Reeds–Shepp (radius 1)")
    print("| goal (x, y, θ) | objective | path ∫abs(v) | RS length | path/RS | SR length | "
          "reversals | RS reversals | CPU s | wall s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    rows = ["reach", "length"] + (["length + ocp"] if ocp_starts else [])
    ratios: dict[str, list[float]] = {row: [] for row in rows}
    excess: dict[str, list[int]] = {row: [] for row in rows}
    refine = OcpRefine(input_weights=(1.0, 0.1), starts=max(1, ocp_starts), seed=seed)
    for g in goals:
        rs_len, rs_rev = reeds_shepp(g)
        for objective in rows:
            t_cpu, t_wall = time.process_time(), time.perf_counter()
            try:
                res = plan_global(car, (0.0,) * 4, tuple(g),
                                  objective="reach" if objective == "reach" else "length",
                                  refine=refine if objective == "length + ocp" else "none",
                                  time_limit=240.0)
            except Exception as exc:
                print(f"| {g[0]:.2f}, {g[1]:.2f}, {g[2]:.2f} | {objective} | failed: "
                      f"{type(exc).__name__} | {rs_len:.3f} | | | | {rs_rev} | | |")
                continue
            cpu, wall = time.process_time() - t_cpu, time.perf_counter() - t_wall
            path, rev = drive_profile(res.plan.segments)
            ratios[objective].append(path / rs_len)
            excess[objective].append(rev - rs_rev)
            print(f"| {g[0]:.2f}, {g[1]:.2f}, {g[2]:.2f} | {objective} | {path:.3f} | "
                  f"{rs_len:.3f} | {path / rs_len:.2f} | {res.plan.length:.3f} | {rev} | "
                  f"{rs_rev} | {cpu:.1f} | {wall:.1f} |", flush=True)
    for objective, r in ratios.items():
        if r:
            print(f"\n{objective}: path/RS median {statistics.median(r):.2f}, max {max(r):.2f} "
                  f"({len(r)} of {len(goals)} goals planned); reversals over RS's: at most "
                  f"{max(excess[objective])}")

class _VanLoanStructure(Step2Structure):
    """The structure with the endpoint integrals of the previous solver (block exponential)."""

    def endpoints(self, y0: np.ndarray, u0: np.ndarray, lam: np.ndarray) -> np.ndarray:
        omega = np.einsum("bk,kij->bij", lam, self.skew)
        u_int, mm = _van_loan_integrals(omega, u0)
        h, v = list(self.h_index), list(self.v_index)
        out = np.tile(y0.astype(u0.dtype), (u0.shape[0], 1))
        out[:, h] += u_int @ self.b.T
        out[:, v] += np.einsum("kil,l,bi->bk", self.a, y0[h], u_int)
        out[:, v] += np.einsum("kij,bij->bk", self.t, mm)
        return out


def previous_multistart_length(st: Step2Structure, goal: np.ndarray) -> float:
    """Baseline: the previous solver from 0 (Van Loan integrals; Heisenberg-type systems from
    the closed-form arc, others from the five general starts); ``inf`` if none converged."""
    old = _VanLoanStructure(st.h_index, st.v_index, st.b, st.a, st.t, st.skew)
    weights = np.ones(goal.size)
    weights[list(st.v_index)] = 2.0
    scale = float(np.max(np.abs(goal) ** (1 / weights)))
    ug, zero = goal / scale**weights, np.zeros(goal.size)
    first = _first_guess(old, zero, ug) if st.m == 2 else None
    finals, errs = _lm(old, zero, ug, first) if first is not None else ([], [])
    if not any(e <= 1e-12 for e in errs):
        finals, errs = _lm(old, zero, ug, np.array(_starts(old, zero, ug)))
    lengths = [np.linalg.norm(p[: st.m]) for p, e in zip(finals, errs, strict=True) if e <= 1e-12]
    return scale * float(min(lengths)) if lengths else math.inf


def _clock(fn, *args):
    cpu, wall = time.process_time(), time.perf_counter()
    out = fn(*args)
    return out, time.process_time() - cpu, time.perf_counter() - wall


def step2_geodesic_speed(rng: np.random.Generator, count: int) -> None:
    """Rows: warm ``shortest_geodesic`` against the previous multi-start LM, same goals."""
    y = sp.symbols("y1 y2 y3")
    heis = Step2Structure.from_triangular(
        TriangularSystem.from_fields(((1, 0, -y[1] / 2), (0, 1, y[0] / 2)), y, (1, 1, 2)))
    tri = Step2Structure.from_triangular(
        numeric_model(get_model("trident-snake"), np.zeros(6)).nilpotent)
    z = sp.symbols("z1:7")  # the free (3,6) group: v̇_ab = (h_a u_b − h_b u_a)/2
    free_st = Step2Structure.from_triangular(TriangularSystem.from_fields(
        [[1, 0, 0, -z[1] / 2, -z[2] / 2, 0], [0, 1, 0, z[0] / 2, 0, -z[2] / 2],
         [0, 0, 1, 0, z[0] / 2, z[1] / 2]], z, (1, 1, 1, 2, 2, 2)))
    cases = []
    hg = [rng.normal(size=3) * rng.uniform(0.1, 2.0) for _ in range(count)]
    cases.append(("heisenberg", heis, hg, [heisenberg_distance(*g) for g in hg]))
    model = numeric_model(get_model("trident-snake"), np.zeros(6))
    cases.append(("trident-snake (3,6), box 0.15", tri,
                  [model.forward(rng.uniform(-0.15, 0.15, size=6)) for _ in range(count)], None))
    perp = []
    for _ in range(count):  # x ⊥ w: rotate (r, 0, 0), (0, 0, a); v = (w₃, −w₂, w₁)
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        r, a = rng.uniform(0.05, 2.0), rng.uniform(-2.0, 2.0)
        x, w = q @ np.array([r, 0, 0]), q @ np.array([0, 0, a])
        perp.append((np.array([*x, w[2], -w[1], w[0]]), heisenberg_distance(r, 0, a)))
    cases.append(("free (3,6), x ⊥ w", free_st, [g for g, _ in perp], [d for _, d in perp]))
    print("\n## step-2 boundary problem (warm `shortest_geodesic` calls)")
    print("| system | solver | median length/ref | max length/ref | failed | "
          "median CPU ms | max CPU ms | median wall ms |")
    print("|---|---|---|---|---|---|---|---|")
    for name, st, goals, exact in cases:
        zero = np.zeros(goals[0].size)
        shortest_geodesic(st, zero, goals[0])
        previous_multistart_length(st, goals[0])  # warm-up
        new = [_clock(lambda g, st=st, zero=zero: shortest_geodesic(st, zero, g).length, g)
               for g in goals]
        old = [_clock(previous_multistart_length, st, g) for g in goals]
        refs = exact if exact is not None else [o[0] for o in old]
        ref_name = "exact" if exact is not None else "previous"
        for solver, rows in (("shortest_geodesic", new), ("previous multi-start LM", old)):
            ok = [(r[0] / d, r[1], r[2]) for r, d in zip(rows, refs, strict=True)
                  if math.isfinite(r[0]) and math.isfinite(d)]
            failed = sum(not math.isfinite(r[0]) for r in rows)
            ratios = [o[0] for o in ok]
            print(f"| {name} | {solver} | {statistics.median(ratios):.6f} ({ref_name}) | "
                  f"{max(ratios):.6f} | {failed}/{len(rows)} | "
                  f"{1e3 * statistics.median(r[1] for r in rows):.2f} | "
                  f"{1e3 * max(r[1] for r in rows):.2f} | "
                  f"{1e3 * statistics.median(r[2] for r in rows):.2f} |")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--goals", type=int, default=20)
    ap.add_argument("--trident", type=int, default=5)
    ap.add_argument("--car", type=int, default=8)
    ap.add_argument("--only-car", action="store_true")
    ap.add_argument("--seed", type=int, default=19)
    ap.add_argument("--ocp", type=int, default=5)
    ap.add_argument("--car-ocp-starts", type=int, default=4,
                    help="IPOPT starts of the car's refined row (0: no such row)")
    args = ap.parse_args()
    if args.only_car:
        car_benchmark(args.car, args.seed, args.car_ocp_starts)
        return
    rng = np.random.default_rng(args.seed)
    goals = [rng.normal(size=3) * rng.uniform(0.1, 2.0) for _ in range(args.goals)]
    y = sp.symbols("y1 y2 y3")
    heis = TriangularSystem.from_fields(((1, 0, -y[1] / 2), (0, 1, y[0] / 2)), y, (1, 1, 2))
    dist = [heisenberg_distance(*g) for g in goals]

    print("## local steering, Heisenberg (warm calls)")
    print("| method | median length/d | max length/d | median ms/call |")
    print("|---|---|---|---|")
    for method in ("step2", "geodesic"):
        steer_nilpotent(heis, np.zeros(3), goals[0], method=method)  # warm-up
        ratios, secs = [], []
        for g, d in zip(goals, dist, strict=True):
            s, dt = timed(steer_nilpotent, heis, np.zeros(3), g, method=method)
            assert s.error < 1e-10
            ratios.append(control_length(s.segments) / d)
            secs.append(dt)
        print(summary("reach (loops)" if method == "step2" else "length (geodesic)", ratios,
                      secs))
    ratios, secs = [], []
    for g, d in zip(goals, dist, strict=True):
        length, dt = timed(shooting, g, 16, rng)
        ratios.append(length / d)
        secs.append(dt)
    print(summary("baseline: SLSQP direct shooting (16 pieces)", ratios, secs))
    step2_geodesic_speed(np.random.default_rng(args.seed + 1), max(args.goals, 20))

    print("\n## whole plans (true model, re-simulated)")
    print("| model | objective | median length/bound | max length/bound | median s/plan |")
    print("|---|---|---|---|---|")
    h = get_model("heisenberg")
    plan(h, (0, 0, 0), goals[0])  # warm-up (compiles)
    for objective in ("reach", "length"):
        ratios, secs = [], []
        for g, d in zip(goals, dist, strict=True):
            p, dt = timed(plan, h, (0, 0, 0), g, objective=objective)
            ratios.append(p.length / d)
            secs.append(dt)
        print(f"| heisenberg | {objective} | {statistics.median(ratios):.4f} | "
              f"{max(ratios):.4f} | {statistics.median(secs):.3f} |")
    if args.trident:
        tri = get_model("trident-snake")
        tgoals = [rng.uniform(-0.15, 0.15, size=6) for _ in range(args.trident)]
        plan(tri, (0,) * 6, tgoals[0])
        for objective in ("reach", "length"):
            ratios, secs = [], []
            for g in tgoals:
                p, dt = timed(plan, tri, (0,) * 6, g, objective=objective)
                fields = p.length_fields[0]
                ratios.append(fields["length"] / fields["lower_bound"])
                secs.append(dt)
            print(f"| trident-snake | {objective} | {statistics.median(ratios):.4f} | "
                  f"{max(ratios):.4f} | {statistics.median(secs):.3f} |")
    if args.car:
        car_benchmark(args.car, args.seed, args.car_ocp_starts)
    if args.ocp:
        ocp_section(goals[: args.ocp], dist[: args.ocp], args.ocp, args.seed)


def reversals(segments) -> int:
    """Sign changes of the drive input ``u1`` (constant segments: one value each)."""
    signs = [np.sign(s.inputs[0].constant) for s in segments if s.inputs[0].constant != 0]
    return sum(a != b for a, b in itertools.pairwise(signs))


def ocp_cases(goals, dist, count: int, seed: int):
    """``(model, label, system, goal, warm plan, exact distance or None)`` per case: the
    Heisenberg goals (warm start: the loops, ``reach``), seeded unicycle goals and the
    trident snake's small goals (warm start: ``--objective length``), and the car shifted
    sideways by 1 (warm start: the global plan, the route ``nilpotent plan car`` takes)."""
    from nilpotent.planning.global_planner import plan_global

    rng = np.random.default_rng(seed + 1)
    h = get_model("heisenberg")
    for g, d in zip(goals, dist, strict=True):
        yield "heisenberg", "reach", h, tuple(g), plan(h, (0, 0, 0), g).segments, d
    uni = get_model("unicycle")
    for _ in range(count):
        g = tuple(rng.uniform(-0.5, 0.5, size=3))
        yield "unicycle", "length", uni, g, plan(uni, (0, 0, 0), g, objective="length").segments, \
            None
    car = get_model("car")
    g = (0.0, 1.0, 0.0, 0.0)
    yield "car (y=1)", "reach, global", car, g, plan_global(car, (0,) * 4, g).plan.segments, None
    tri = get_model("trident-snake")
    for _ in range(max(1, count // 2)):
        g = tuple(rng.uniform(-0.15, 0.15, size=6))
        yield "trident-snake", "length", tri, g, \
            plan(tri, (0,) * 6, g, objective="length").segments, None


def ocp_section(goals, dist, count: int, seed: int) -> None:
    """``refine="ocp"``: length before/after, ratio to the exact distance (Heisenberg) or
    to ``lower_bound`` (the approximation's distance, :func:`length_report`), time of the
    refinement (IPOPT, endpoint correction and verification; the warm plan not counted)."""
    from nilpotent.planning.length import length_report
    from nilpotent.planning.ocp import refine_segments
    from nilpotent.planning.verify import Checker

    print("\n## refinement by direct optimal control (--refine ocp), true models")
    print("| model | warm start | length before | length after | ratio before | ratio after "
          "| bound | applied | s/refinement |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, label, system, goal, warm, d in ocp_cases(goals, dist, count, seed):
        start = (0.0,) * system.n
        (segs, info), dt = timed(refine_segments, Checker(system), start, goal, warm, 1e-8)
        before, after = control_length(warm), control_length(segs)
        bound = d if d is not None else length_report(system, start, goal, segs)[0][
            "lower_bound"]
        kind = "exact d" if d is not None else ("lower_bound" if bound else "none")
        rb = f"{before / bound:.4f}" if bound else "-"
        ra = f"{after / bound:.4f}" if bound else "-"
        extra = ""
        if system.name == "car":
            from nilpotent.planning.simulation import simulate_path  # rear-axle path vs RS

            _, states = simulate_path(system, start, segs, 50)
            path = float(np.sum(np.linalg.norm(np.diff(states[:, :2], axis=0), axis=1)))
            extra = f" (rear-axle path {path:.3f}, {reversals(segs)} reversals; RS 2.64)"
        print(f"| {name} | {label} | {before:.4f} | {after:.4f}{extra} | {rb} | {ra} | {kind} "
              f"| {info.applied} | {dt:.2f} |")


if __name__ == "__main__":
    main()
