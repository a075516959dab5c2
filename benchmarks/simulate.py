"""Benchmark: bracket-motion trajectories of the trident snake per second.

10,000 trajectories of ``trident-snake`` (body-velocity inputs, r = l = 1), one
period of the bracket input ``u_1 = −Aω sin ωt, u_2 = Aω cos ωt`` with random
amplitudes ``A ∈ [0.01, 0.3]`` and random start points ``|q0_k| ≤ 0.1``:

(a) baseline: :func:`scipy.integrate.solve_ivp` (DOP853, rtol 1e-10, atol 1e-12)
    in a Python loop with a sympy-``lambdify`` right-hand side; timed on a subset
    and extrapolated (the script says so);
(b) ours: :func:`nilpotent.numeric.integrate` with ``engine="auto"`` (heyoka's
    Taylor method in SIMD batches when heyoka is installed, as it is by
    default; else numba) at the same tolerances, over the whole batch;
(b1) the numba engine (adaptive DOP853, scipy's step control) for comparison;
(c) a hand-written heyoka baseline: the trident snake's fields written out by
    hand as heyoka expressions, the amplitude a runtime parameter,
    ``taylor_adaptive_batch`` at ``heyoka.recommended_simd_size()``, ONE thread,
    the same tolerance as (b) (heyoka's ``tol = min(rtol, atol) = 1e-12``), on
    the same motions; its end points must agree with (b)'s to 1e-12.

(b) and (c) are timed ``--repeat`` times each, alternately, and the best rate of
each is reported (the machine may be shared: the best run is the one least
disturbed).

Both end points are checked against a tight reference (solve_ivp at rtol 1e-13
on a subset): the batched engine must be within 1e-9; the ratio on the last line compares equal
tolerances (wall-clock rates, the same process).  The start-up time
(imports + loading the compiled kernels from the on-disk cache) is measured in a
fresh subprocess.  The last line is
``simulate: <N> trajectories/s, <R>x solve_ivp, <Q>x heyoka-1-thread``.

Usage: ``python benchmarks/simulate.py [--n 10000] [--baseline 200] [--threads K]
[--repeat 15]`` (``--threads``: numba's threads and the heyoka engine's; default
numba's setting, and for heyoka one more than the cores, the engine's default).
One timed run of (b) or (c) takes ~30 ms, so 15 alternate repeats cost under a
second and make the best of each much less sensitive to a shared machine.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time

import numpy as np

STARTUP = """
import time
t0 = time.perf_counter()
import numpy as np
from nilpotent.models import get_model
from nilpotent.numeric import compile_system, bracket_inputs, integrate
cs = compile_system(get_model("trident-snake"))
r = integrate(cs, np.zeros((2, 6)), bracket_inputs(3, 1, 2, [0.1, 0.2]), engine="auto")
print(time.perf_counter() - t0, time.process_time(), r.engine)
"""

STARTUP_HEYOKA = STARTUP.replace('engine="auto"', 'engine="heyoka"')


class HandWritten:
    """(c): the trident snake's bracket motion written out by hand for heyoka, one thread.

    ``dx/dt = u1 X1 + u2 X2`` (X3's input is 0) with ``u1 = −A sin t``,
    ``u2 = A cos t`` (ω = 1), ``A = par[0]``; calling it integrates every motion
    over one period in SIMD batches of ``heyoka.recommended_simd_size()`` and
    returns the ``(N, 6)`` end points.
    """

    def __init__(self, x0: np.ndarray, amps: np.ndarray, period: float, tol: float) -> None:
        import heyoka as hy

        x, y, th, p1, p2, p3 = hy.make_vars("x", "y", "th", "p1", "p2", "p3")
        amp, t = hy.par[0], hy.time
        u1, u2 = -amp * hy.sin(t), amp * hy.cos(t)
        c6, c3 = np.pi / 6, np.pi / 3
        rhs = [
            u1 * hy.cos(th) - u2 * hy.sin(th),
            u1 * hy.sin(th) + u2 * hy.cos(th),
            hy.expression(0.0),
            u1 * hy.sin(p1) - u2 * hy.cos(p1),
            u1 * hy.cos(p2 + c6) + u2 * hy.sin(p2 + c6),
            -u1 * hy.sin(p3 + c3) + u2 * hy.cos(p3 + c3),
        ]
        self.batch_size = bs = int(hy.recommended_simd_size())
        self.ta = hy.taylor_adaptive_batch(list(zip([x, y, th, p1, p2, p3], rhs, strict=True)),
                                           np.zeros((6, bs)), tol=tol, pars=np.zeros((1, bs)))
        self.x0, self.amps, self.period = x0, amps, period

    def __call__(self) -> np.ndarray:
        ta, bs, n = self.ta, self.batch_size, self.amps.size
        state, par, zero = ta.state, ta.pars, np.zeros(bs)
        out = np.empty((n, 6))
        for lo in range(0, n, bs):
            hi = min(lo + bs, n)
            state[:] = 0.0
            par[:] = 0.0
            state[:, : hi - lo] = self.x0[lo:hi].T
            par[0, : hi - lo] = self.amps[lo:hi]
            ta.set_time(zero)
            ta.propagate_until(self.period)
            out[lo:hi] = state[:, : hi - lo].T
        return out


def hand_written_heyoka(x0: np.ndarray, amps: np.ndarray, period: float,
                        tol: float) -> HandWritten:
    """The baseline (c), compiled and run once (warm-up)."""
    hand = HandWritten(x0, amps, period, tol)
    hand()
    return hand


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=10_000, help="trajectories (batched engine)")
    parser.add_argument("--baseline", type=int, default=200, help="solve_ivp subset size")
    parser.add_argument("--threads", type=int, default=None,
                        help="threads of the engines (default: the engines' own)")
    parser.add_argument("--repeat", type=int, default=15, help="timed runs of (b) and (c)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    import sympy as sp
    from scipy.integrate import solve_ivp

    from nilpotent.models import get_model
    from nilpotent.numeric import bracket_inputs, compile_system, integrate

    system = get_model("trident-snake").specialized()
    rng = np.random.default_rng(args.seed)
    amps = rng.uniform(0.01, 0.3, args.n)
    x0 = rng.uniform(-0.1, 0.1, (args.n, system.n))
    omega = 1.0
    period = 2 * np.pi / omega

    # (a) solve_ivp + lambdify, Python loop over a subset
    q = sp.Matrix(system.coordinates)
    u = sp.symbols(f"u1:{system.m + 1}")
    rhs_expr = system.field_matrix() * sp.Matrix(u)
    f_lamb = sp.lambdify((q, u), list(rhs_expr), "numpy")

    def solve_one(x_init: np.ndarray, amp: float, rtol: float, atol: float) -> np.ndarray:
        def fun(t: float, x: np.ndarray) -> np.ndarray:
            uu = (-amp * omega * np.sin(omega * t), amp * omega * np.cos(omega * t), 0.0)
            return np.asarray(f_lamb(x, uu), dtype=float)

        sol = solve_ivp(fun, (0.0, period), x_init, method="DOP853", rtol=rtol, atol=atol)
        return sol.y[:, -1]

    nb = min(args.baseline, args.n)
    t0 = time.perf_counter()
    c0 = time.process_time()
    base_final = np.array([solve_one(x0[k], amps[k], 1e-10, 1e-12) for k in range(nb)])
    t_base = time.perf_counter() - t0
    cpu_base = time.process_time() - c0
    rate_base = nb / t_base
    print(
        f"(a) solve_ivp DOP853 rtol=1e-10 + lambdify, Python loop: {nb} trajectories in "
        f"{t_base:.2f} s -> {rate_base:,.0f} trajectories/s, {nb / cpu_base:,.0f} per "
        f"CPU-second (timed on {nb}, extrapolated to {args.n}: {args.n / rate_base:.1f} s)"
    )

    # (b) ours, engine chosen automatically (heyoka when installed, as by default)
    compiled = compile_system(system)
    inputs = bracket_inputs(system.m, 1, 2, amps, omega=omega, periods=1)
    warm = integrate(compiled, x0[:64], bracket_inputs(system.m, 1, 2, amps[:64]),
                     threads=args.threads)  # loads (or compiles) the engine's code
    hand = hand_written_heyoka(x0, amps, period, tol=1e-12)

    best_ours = best_hand = (np.inf, np.inf)
    for _ in range(max(1, args.repeat)):
        t0 = time.perf_counter()
        c0 = time.process_time()
        result = integrate(compiled, x0, inputs, rtol=1e-10, atol=1e-12, threads=args.threads)
        best_ours = min(best_ours, (time.perf_counter() - t0, time.process_time() - c0))
        t0 = time.perf_counter()
        c0 = time.process_time()
        hand_final = hand()
        best_hand = min(best_hand, (time.perf_counter() - t0, time.process_time() - c0))
    t_ours, cpu_ours = best_ours
    t_hand, cpu_hand = best_hand
    rate_ours = args.n / t_ours
    rate_hand = args.n / t_hand
    # accuracy against a tight reference on a subset
    nref = min(100, args.n)
    ref = np.array([solve_one(x0[k], amps[k], 1e-13, 1e-15) for k in range(nref)])
    err_ours = np.abs(result.final[:nref] - ref).max()
    print(
        f"(b) nilpotent.numeric.integrate, engine=auto -> {result.engine} (warm-up "
        f"{warm.engine}), rtol=1e-10 atol=1e-12: {args.n} trajectories in {t_ours:.3f} s -> "
        f"{rate_ours:,.0f} trajectories/s, {args.n / cpu_ours:,.0f} per CPU-second "
        f"({(args.n / cpu_ours) / (nb / cpu_base):.0f}x solve_ivp per CPU-second); "
        f"mean steps {result.steps.mean():.1f}; all ok: {result.all_ok}; "
        f"end-point error {err_ours:.2e}"
    )

    from nilpotent.numeric.engines.heyoka_engine import default_workers

    gap = np.abs(result.final - hand_final).max()
    print(
        f"(c) hand-written heyoka (fields as heyoka expressions, amplitude a runtime "
        f"parameter, taylor_adaptive_batch x{hand.batch_size}, 1 thread, tol 1e-12): "
        f"{rate_hand:,.0f} trajectories/s, {args.n / cpu_hand:,.0f} per CPU-second; "
        f"(b) used {args.threads or default_workers()} threads: "
        f"{rate_ours / rate_hand:.2f}x (c) wall, "
        f"{(args.n / cpu_ours) / (args.n / cpu_hand):.2f}x (c) per CPU-second; "
        f"end points (b) vs (c) max {gap:.1e} apart (required <= 1e-12: "
        f"{'yes' if gap <= 1e-12 else 'NO'})"
    )

    # (b1) the numba engine (adaptive DOP853, scipy's step control) for comparison
    import numba

    integrate(compiled, x0[:64], bracket_inputs(system.m, 1, 2, amps[:64]), engine="numba",
              threads=args.threads)
    t0 = time.perf_counter()
    c0 = time.process_time()
    nres = integrate(compiled, x0, inputs, rtol=1e-10, atol=1e-12, engine="numba",
                     threads=args.threads)
    t_nb = time.perf_counter() - t0
    cpu_nb = time.process_time() - c0
    err_nb = np.abs(nres.final[:nref] - ref).max()
    print(
        f"(b1) engine=numba, adaptive DOP853 rtol=1e-10, {numba.get_num_threads()} threads "
        f"({numba.threading_layer()}): {args.n / t_nb:,.0f} trajectories/s, "
        f"{args.n / cpu_nb:,.0f} per CPU-second "
        f"({(args.n / cpu_nb) / (nb / cpu_base):.0f}x solve_ivp per CPU-second); "
        f"mean accepted steps {nres.steps.mean():.1f}; end-point error {err_nb:.2e}"
    )
    err_base = np.abs(base_final[: min(nb, nref)] - ref[: min(nb, nref)]).max()
    print(
        f"max end-point error vs solve_ivp rtol=1e-13 on {nref}: ours {err_ours:.2e}, "
        f"solve_ivp rtol=1e-10 {err_base:.2e} (required <= 1e-9: "
        f"{'yes' if err_ours <= 1e-9 else 'NO'})"
    )

    # start-up in a fresh process (kernels from the on-disk cache)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [os.path.join(os.path.dirname(__file__), "..", "src"), env.get("PYTHONPATH", "")]
    )
    out = subprocess.run([sys.executable, "-c", STARTUP], capture_output=True, text=True,
                         env=env, check=True)
    startup, startup_cpu, engine = out.stdout.split()
    print(f"start-up (imports + cached kernels + 2 trajectories, fresh process): "
          f"{float(startup):.2f} s wall, {float(startup_cpu):.2f} s CPU (engine {engine})")
    from nilpotent.numeric.engines.heyoka_engine import heyoka_available

    if heyoka_available():
        out = subprocess.run([sys.executable, "-c", STARTUP_HEYOKA], capture_output=True,
                             text=True, env=env, check=True)
        startup, startup_cpu, engine = out.stdout.split()
        print(f"start-up with engine=heyoka (imports + compile, heyoka's on-disk cache, "
              f"fresh process): {float(startup):.2f} s wall, {float(startup_cpu):.2f} s CPU")
    print("note: the machine is shared; timings are noisy")
    print(f"simulate: {rate_ours:.0f} trajectories/s, {rate_ours / rate_base:.0f}x solve_ivp, "
          f"{rate_ours / rate_hand:.2f}x heyoka-1-thread")


if __name__ == "__main__":
    main()
