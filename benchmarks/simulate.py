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
(b1) the numba engine (adaptive DOP853, scipy's step control) for comparison.

Both end points are checked against a tight reference (solve_ivp at rtol 1e-13
on a subset): the batched engine must be within 1e-9; the ratio on the last line compares equal
tolerances (wall-clock rates, the same process).  The start-up time
(imports + loading the compiled kernels from the on-disk cache) is measured in a
fresh subprocess.  The last line is ``simulate: <N> trajectories/s, <R>x solve_ivp``.

Usage: ``python benchmarks/simulate.py [--n 10000] [--baseline 200] [--threads K]``.
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


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=10_000, help="trajectories (batched engine)")
    parser.add_argument("--baseline", type=int, default=200, help="solve_ivp subset size")
    parser.add_argument("--threads", type=int, default=None, help="numba threads")
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
    t0 = time.perf_counter()
    c0 = time.process_time()
    result = integrate(compiled, x0, inputs, rtol=1e-10, atol=1e-12, threads=args.threads)
    t_ours = time.perf_counter() - t0
    cpu_ours = time.process_time() - c0
    rate_ours = args.n / t_ours

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
    print(f"simulate: {rate_ours:.0f} trajectories/s, {rate_ours / rate_base:.0f}x solve_ivp")


if __name__ == "__main__":
    main()
