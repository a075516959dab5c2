"""The trident snake's shortest body path between two star shapes in free space (issue 20).

What is the least xy arc length of the body centre that moves ``trident-snake`` (body-velocity
inputs, r = l = 1) from ``(0, 0, 0, 0, 0, 0)`` to ``(d cos β, d sin β, Δθ, 0, 0, 0)``, with the
joint limits ``|φ_i| ≤ 5π/6`` and no leg touching another, and no obstacle?  Direct optimal
control (CasADi + IPOPT, multiple shooting on ``N`` intervals of ``[0, 1]``, piecewise-constant
body velocities ``(v1, v2, v3)``, RK4 sub-steps), cost

    ``Σ_k h sqrt(v1_k² + v2_k² + ε²) + μ Σ_k h v3_k²``   (``h = 1/N``)

(the body path, smoothed by ``ε``; ``μ`` a small price on turning, which alone costs no body
path, to keep the turning rate bounded), the limits tightened by ``MARGIN`` at every sub-step,
self-collision as ``dist(W_i, leg_j)² ≥ δ²`` for every ordered pair of legs at every node (a
leg's only free end is its wheel ``W``: two legs can start to cross only where a wheel meets
the other leg, since a vertex is ``√3 − 1`` from every point of another leg).  Several starts:
a straight drive (its roll-out), a body-path-free shape (the states on a line, the legs
straight), gait-like guesses (the legs folded towards a settled caster shape on the way), and
optionally the nilpotent steering's plan (``--with-steering``).

Each solution is checked independently: its controls re-simulated by scipy's DOP853
(rtol 1e-11) on the model's fields lambdified from sympy, 40 samples per interval; reported:
the goal error, the least limit margin and self-clearance (:class:`nilpotent.planning.robot.Robot`)
of the samples, the body path (the sum of ``|v| h``, the exact arc length of piecewise-constant
body speed) and its ratio to ``d``.

Usage: ``PYTHONPATH=src python benchmarks/trident_free_ocp.py [--d 3,5,10] [--beta 0,30,60]
[--turn 0,90] [--intervals 80] [--markdown]``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time

import casadi as ca
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from nilpotent.models import get_model
from nilpotent.planning.robot import Robot

ALPHA = (0.0, 2 * math.pi / 3, 4 * math.pi / 3)
LIMIT = 5 * math.pi / 6
MARGIN = 1e-3
DELTA = 0.02
EPS = 1e-2
MU = 1e-4
SUB = 4


def field(q, u, lib):
    """``q̇`` of the body-velocity form (r = l = 1) in CasADi (``lib = ca``) or numpy."""
    th = q[2]
    v1, v2, v3 = u[0], u[1], u[2]
    out = [lib.cos(th) * v1 - lib.sin(th) * v2, lib.sin(th) * v1 + lib.cos(th) * v2, v3]
    for a, p in zip(ALPHA, (q[3], q[4], q[5]), strict=True):
        out.append(v1 * lib.sin(p + a) - v2 * lib.cos(p + a) - (lib.cos(p) + 1) * v3)
    return out


def legs(q, lib):
    """Vertices and wheels ``[(V_i, W_i)]`` (pairs of 2-lists)."""
    out = []
    for a, p in zip(ALPHA, (q[3], q[4], q[5]), strict=True):
        vx, vy = q[0] + lib.cos(q[2] + a), q[1] + lib.sin(q[2] + a)
        out.append(((vx, vy), (vx + lib.cos(q[2] + a + p), vy + lib.sin(q[2] + a + p))))
    return out


def point_segment_sq(p, a, b):
    """Squared distance from ``p`` to the segment ``ab`` (CasADi; ``|ab| = 1``)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    t = (p[0] - a[0]) * dx + (p[1] - a[1]) * dy
    t = ca.fmin(1.0, ca.fmax(0.0, t))
    ex, ey = p[0] - a[0] - t * dx, p[1] - a[1] - t * dy
    return ex * ex + ey * ey


def build(n_int: int):
    x = ca.SX.sym("x", 6)
    u = ca.SX.sym("u", 3)
    h = 1.0 / (n_int * SUB)

    def f(z):
        return ca.vertcat(*field(z, u, ca))

    z, subs = x, []
    for _ in range(SUB):
        k1 = f(z)
        k2 = f(z + h / 2 * k1)
        k3 = f(z + h / 2 * k2)
        k4 = f(z + h * k3)
        z = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        subs.append(z)
    step = ca.Function("step", [x, u], [z, ca.horzcat(*subs)])
    lg = legs(x, ca)
    clear = []
    for i in range(3):
        for j in range(3):
            if i != j:
                clear.append(point_segment_sq(lg[i][1], lg[j][0], lg[j][1]))
    selfc = ca.Function("selfc", [x], [ca.vertcat(*clear)])
    return step, selfc


def solve(step, selfc, n_int, x0, xg, u0, s0, iters=3000, wall=120.0):
    opti = ca.Opti()
    X = opti.variable(6, n_int + 1)
    U = opti.variable(3, n_int)
    hcost = 1.0 / n_int
    speed = ca.sqrt(U[0, :] ** 2 + U[1, :] ** 2 + EPS**2)
    opti.minimize(hcost * ca.sum2(speed) + MU * hcost * ca.sumsqr(U[2, :]))
    nxt, subs = step.map(n_int)(X[:, :n_int], U)
    opti.subject_to(X[:, 0] == x0)
    opti.subject_to(X[:, n_int] == xg)
    opti.subject_to(X[:, 1:] == nxt)
    opti.subject_to(opti.bounded(-LIMIT + MARGIN, subs[3:6, :], LIMIT - MARGIN))
    opti.subject_to(ca.vec(selfc.map(n_int + 1)(X)) >= DELTA**2)
    # at most 0.25 of body displacement / 0.25 rad of turn per interval (RK4 accuracy)
    opti.subject_to(opti.bounded(-0.25 * n_int, U, 0.25 * n_int))
    opti.set_initial(U, u0)
    opti.set_initial(X, s0)
    opti.solver("ipopt", {"print_time": False, "expand": True},
                {"print_level": 0, "max_iter": iters, "tol": 1e-8, "sb": "yes",
                 "max_wall_time": wall})
    try:
        sol = opti.solve()
        stats = sol.stats()
        return np.array(sol.value(U)).reshape(3, n_int), stats["return_status"], stats["iter_count"]
    except RuntimeError:
        stats = opti.stats()
        return None, stats.get("return_status", "failed"), stats.get("iter_count", 0)


def rollout(step, x0, u):
    xs = [np.asarray(x0, float)]
    for k in range(u.shape[1]):
        xs.append(np.array(step(xs[-1], u[:, k])[0]).ravel())
    return np.array(xs).T


def guesses(step, n_int, x0, xg, rng):
    """``[(name, u0 (3, N), states (6, N+1))]``."""
    t = np.linspace(0, 1, n_int + 1)
    d = xg[:2] - x0[:2]
    dist = float(np.hypot(*d))
    out = []
    # 1. straight drive at constant world direction, turning at a constant rate: roll-out
    heading = math.atan2(d[1], d[0])
    th = x0[2] + (xg[2] - x0[2]) * (t[:-1] + 0.5 / n_int)
    u = np.vstack([dist * np.cos(heading - th), dist * np.sin(heading - th),
                   np.full(n_int, xg[2] - x0[2])])
    out.append(("straight", u, rollout(step, x0, u)))
    # 2. the line of states (legs straight), controls of the straight drive
    line = x0[:, None] + (xg - x0)[:, None] * t[None, :]
    out.append(("line", u, line))
    # 3. gait-like: travel in body direction β ∈ {π/3, π, 5π/3} (a leg trailing, the others
    # folded back 2π/3): legs folded over the first fifth, back over the last fifth
    for beta in (math.pi / 3, math.pi, 5 * math.pi / 3):
        # the leg whose vertex is opposite the direction of travel trails straight
        back = (beta + math.pi) % (2 * math.pi)
        i_tr = int(np.argmin([abs(math.remainder(back - a, 2 * math.pi)) for a in ALPHA]))
        fold = np.zeros(3)
        for i in range(3):
            if i != i_tr:
                fold[i] = 2 * math.pi / 3 * np.sign(math.remainder(back - ALPHA[i], 2 * math.pi))
        env = np.clip(np.minimum(t / 0.2, (1 - t) / 0.2), 0, 1)
        states = line.copy()
        # body heading such that body direction β points along the displacement
        th_drive = heading - beta
        th_drive = x0[2] + math.remainder(th_drive - x0[2], 2 * math.pi)
        states[2] = x0[2] + (th_drive - x0[2]) * np.clip(t / 0.2, 0, 1)
        states[2] += (xg[2] - th_drive) * np.clip((t - 0.8) / 0.2, 0, 1)
        states[3:6] = fold[:, None] * env[None, :] * 0.9
        uu = np.vstack([np.full(n_int, dist * math.cos(beta)),
                        np.full(n_int, dist * math.sin(beta)), np.diff(states[2]) * n_int])
        out.append((f"gait{round(math.degrees(beta))}", uu, states))
    # 4. seeded perturbations of the line
    for s in range(2):
        pert = line + rng.normal(0, 0.5, line.shape) * np.sin(np.pi * t)[None, :]
        pert[3:6] = np.clip(pert[3:6], -2, 2)
        out.append((f"random{s}", rng.normal(0, dist, (3, n_int)), pert))
    return out


class Verifier:
    def __init__(self):
        sysm = get_model("trident-snake")
        self.robot = Robot(sysm)
        q = sysm.coordinates
        u = sp.symbols("u1:4")
        rhs = [sum(ui * fi[j] for ui, fi in zip(u, sysm.specialized_fields, strict=True))
               for j in range(6)]
        self.f = sp.lambdify([q, u], rhs, "numpy")

    def check(self, x0, xg, u):
        n_int = u.shape[1]
        h = 1.0 / n_int
        q = np.asarray(x0, float)
        samples = [q]
        for k in range(n_int):
            uk = u[:, k]
            sol = solve_ivp(lambda _t, z, uk=uk: self.f(z, uk), (0, h), q, method="DOP853",
                            rtol=1e-11, atol=1e-12, t_eval=np.linspace(0, h, 41)[1:])
            samples.extend(sol.y.T)
            q = sol.y[:, -1]
        samples = np.array(samples)
        err = float(np.linalg.norm(q - xg))
        margin = float(self.robot.limit_margin(samples).min())
        clear = float(self.robot.self_clearance(samples).min())
        body = float(np.sum(np.hypot(u[0], u[1])) * h)
        xy = float(np.sum(np.hypot(*np.diff(samples[:, :2], axis=0).T)))
        return {"error": err, "limit_margin": margin, "self_clearance": clear, "body": body,
                "xy_samples": xy, "max_abs_phi": float(np.abs(samples[:, 3:]).max()),
                "turn_total": float(np.sum(np.abs(u[2])) * h)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--d", default="3,5,10")
    ap.add_argument("--beta", default="0,30,60")
    ap.add_argument("--turn", default="0,90")
    ap.add_argument("--intervals", type=int, default=80)
    ap.add_argument("--wall", type=float, default=90.0)
    ap.add_argument("--json", default="")
    ap.add_argument("--only", default="")
    args = ap.parse_args(argv)
    ver = Verifier()
    rows = []
    step_cache = {}
    for d in [float(s) for s in args.d.split(",")]:
        n_int = max(args.intervals, int(8 * d))
        if n_int not in step_cache:
            step_cache[n_int] = build(n_int)
        step, selfc = step_cache[n_int]
        for beta in [float(s) for s in args.beta.split(",")]:
            for turn in [float(s) for s in args.turn.split(",")]:
                b, tr = math.radians(beta), math.radians(turn)
                x0 = np.zeros(6)
                xg = np.array([d * math.cos(b), d * math.sin(b), tr, 0, 0, 0])
                rng = np.random.default_rng(0)
                best = None
                for name, u0, s0 in guesses(step, n_int, x0, xg, rng):
                    if args.only and name not in args.only.split(","):
                        continue
                    t0 = time.perf_counter()
                    u, status, its = solve(step, selfc, n_int, x0, xg, u0, s0, wall=args.wall)
                    sec = time.perf_counter() - t0
                    if u is None:
                        print(f"d={d} β={beta} Δθ={turn} {name}: {status} ({its} its, "
                              f"{sec:.1f} s)", file=sys.stderr, flush=True)
                        continue
                    v = ver.check(x0, xg, u)
                    ok = v["error"] < 1e-3 and v["limit_margin"] >= 0 and v["self_clearance"] > 0
                    print(f"d={d} β={beta} Δθ={turn} {name}: {status} {its} its {sec:.1f} s "
                          f"body {v['body']:.3f} ratio {v['body'] / d:.2f} err {v['error']:.1e}"
                          f" margin {v['limit_margin']:.3f} clear {v['self_clearance']:.3f} "
                          f"turn {v['turn_total']:.2f} ok={ok}", file=sys.stderr, flush=True)
                    row = {"d": d, "beta": beta, "turn": turn, "guess": name, "status": status,
                           "iterations": its, "seconds": sec, "ok": ok, **v}
                    rows.append(row)
                    if ok and (best is None or v["body"] < best["body"]):
                        best = row
                        np.save(f"/tmp/trh/trident_ocp_d{d:g}_b{beta:g}_t{turn:g}.npy", u)
                if best:
                    print(f"BEST d={d} β={beta} Δθ={turn}: {best['guess']} body "
                          f"{best['body']:.3f} ratio {best['body'] / d:.2f}", file=sys.stderr,
                          flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
