"""Independent re-simulation of a plan's JSON segments (scipy's DOP853 on the model's
fields, compiled by sympy's lambdify: nothing of the product's compiler or engines),
shared by the planning tests."""

from __future__ import annotations

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp


def resimulate(system, start, segments, samples: int = 120):
    """Dense samples (N, n) of the true system under JSON segments (scipy DOP853)."""
    mat = sp.lambdify([system.coordinates], sp.Matrix(system.specialized_fields).T, "numpy")
    x = np.asarray(start, dtype=float)
    out = [x[None, :]]
    for seg in segments:
        omega = seg["omega"]

        def u(t, seg=seg, omega=omega):
            return np.array([
                inp["constant"]
                + sum(a * np.cos((k + 1) * omega * t) for k, a in enumerate(inp["cos"]))
                + sum(b * np.sin((k + 1) * omega * t) for k, b in enumerate(inp["sin"]))
                for inp in seg["inputs"]
            ])

        def rhs(t, z, u=u):
            return np.asarray(mat(z), dtype=float) @ u(t)

        ts = np.linspace(0, seg["duration"], samples)
        sol = solve_ivp(rhs, (0, seg["duration"]), x, method="DOP853", rtol=1e-12,
                        atol=1e-13, t_eval=ts)
        assert sol.success
        out.append(sol.y.T[1:])
        x = sol.y[:, -1]
    return np.vstack(out)
