"""Local nilpotent models at float points: first-order approximation, brackets, singularities."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from nilpotent.errors import PlanningError, SingularPointError
from nilpotent.models import get_model
from nilpotent.planning.local_model import numeric_model, symbolic_model
from nilpotent.planning.nilpotent import bracket_matrix

POINTS = {
    "trident-snake": (0.3, -0.2, 0.7, 0.4, -0.5, 0.9),
    "trident-snake-paper": (0.1, 0.2, -0.3, 0.2, 0.1, -0.4),
    "unicycle": (0.5, -1.0, 2.0),
}


def sympy_fields(system):
    params = {sp.Symbol(k): v for k, v in system.parameters}
    return [sp.Matrix(f).xreplace(params) for f in system.fields]


@pytest.mark.parametrize("name", sorted(POINTS))
def test_numeric_model_is_a_first_order_approximation(name):
    """In y, ``X_i − X̂_i`` has order ≥ 0: component j is O(ε^{w_j}) at y = δ_ε(v)."""
    system = get_model(name)
    p = np.array(POINTS[name])
    model = numeric_model(system, p)
    tri = model.nilpotent
    fields = [sp.lambdify([system.coordinates], f, "numpy") for f in sympy_fields(system)]
    # y-components of X_i at x(y): dy/dx · X_i(x), dy/dx = A (linear coordinates)
    a = np.array([model.forward(p + e) - model.forward(p) for e in np.eye(system.n)]).T
    rng = np.random.default_rng(0)
    v = rng.uniform(-1, 1, size=system.n)
    w = np.array(tri.weights, dtype=float)
    for i, f in enumerate(fields):
        errs = []
        for eps in (1e-2, 1e-3):
            y = tri.dilate(v, eps)
            true = a @ np.asarray(f(model.inverse(y)), dtype=float).reshape(-1)
            approx = tri.field_values(y)[:, i]
            errs.append(np.abs(true - approx) / eps**w)
        # bounded as ε → 0 (it would grow like 1/ε for a term of too low order)
        assert np.all(errs[1] <= 2 * errs[0] + 1e-6)


@pytest.mark.parametrize("name", sorted(POINTS))
def test_brackets_of_the_model_are_those_of_the_system(name):
    """``F·[X̂_a, X̂_b](0) = [X_a, X_b](p)`` (``[X,Y] = DY·X − DX·Y``, sympy independently)."""
    system = get_model(name)
    p = np.array(POINTS[name])
    model = numeric_model(system, p)
    f = np.array([model.inverse(e) - model.inverse(0 * e) for e in np.eye(system.n)]).T
    mats = sympy_fields(system)
    jac = [m.jacobian(system.coordinates) for m in mats]
    at = dict(zip(system.coordinates, p, strict=True))
    cols = []
    for a_ in range(system.m):
        for b in range(a_ + 1, system.m):
            br = jac[b] * mats[a_] - jac[a_] * mats[b]
            cols.append([float(sp.N(c.subs(at))) for c in br])
    assert np.allclose(f @ bracket_matrix(model.nilpotent), np.array(cols).T, atol=1e-10)


def test_numeric_model_agrees_with_the_core_approximation_at_the_origin():
    """Same growth and the same brackets at 0 up to the (different) frames: compare
    the brackets pushed back to model coordinates."""
    system = get_model("unicycle")
    num = numeric_model(system, (0, 0, 0))
    sym = symbolic_model(system, system.origin())
    assert num.nilpotent.weights == sym.nilpotent.weights

    def pushed(model):
        f = np.array([model.inverse(e) - model.inverse(0 * e) for e in np.eye(3)]).T
        return f @ bracket_matrix(model.nilpotent)

    assert np.allclose(pushed(num), pushed(sym), atol=1e-12)


def test_numeric_model_refuses_step_3_and_singular_points():
    with pytest.raises(PlanningError, match="step"):
        numeric_model(get_model("engel"), (0, 0, 0, 0))
    with pytest.raises(SingularPointError):
        numeric_model(get_model("martinet"), (0, 0, 0))


def test_numeric_model_refuses_a_frame_of_subnormal_size():
    # theta' = 1e-320 u2: growth (2,3) in exact arithmetic, but the adapted frame's
    # inverse (~1e320) overflows a double; a clear PlanningError, never a NaN model
    # (NaN reached LAPACK, which printed on stdout and failed as LinAlgError, exit 70)
    from nilpotent.core.model.modelfile import system_from_dict

    tiny = system_from_dict({
        "name": "tiny-turn",
        "coordinates": ["x", "y", "theta"],
        "fields": [{"x": "cos(theta)", "y": "sin(theta)"}, {"theta": "1e-320"}],
    })
    with pytest.raises(PlanningError, match="double precision"):
        numeric_model(tiny, (0.0, 0.0, 0.0))
