"""The numeric compiler against sympy itself (an independent evaluation), finite
differences for the Jacobians, and its error paths."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from nilpotent.errors import MissingExtraError, ModelError, OptionError
from nilpotent.models import get_model
from nilpotent.numeric import compile_fields, compile_system
from nilpotent.numeric.tableaux import DOP853, TABLEAUX


def _sympy_values(system, point):
    subs = dict(zip(system.coordinates, point, strict=True))
    return np.array(
        [[float(sp.N(f[j].subs(subs), 20)) for f in system.specialized_fields]
         for j in range(system.n)]
    )


@pytest.mark.every_model
def test_field_values_match_sympy(model):
    system = model
    compiled = compile_system(system, backend="numpy")
    rng = np.random.default_rng(1)
    pts = rng.uniform(-1.5, 1.5, (4, system.n))
    values = compiled.field_values(pts)
    assert values.shape == (4, system.n, system.m)
    for b in range(4):
        np.testing.assert_allclose(values[b], _sympy_values(system, pts[b]), atol=1e-13)
    u = rng.normal(size=(4, system.m))
    np.testing.assert_allclose(compiled.rhs(pts, u), np.einsum("bnm,bm->bn", values, u),
                               atol=1e-13)


def test_jacobian_matches_finite_differences():
    system = get_model("trident-snake")
    compiled = compile_system(system)
    rng = np.random.default_rng(2)
    x = rng.uniform(-1, 1, (3, system.n))
    jac = compiled.jacobian(x)  # (B, m, n, n): [b, i, j, k] = dX_i^j / dx_k
    h = 1e-6
    for k in range(system.n):
        e = np.zeros(system.n)
        e[k] = h
        fd = (compiled.field_values(x + e) - compiled.field_values(x - e)) / (2 * h)  # (B, n, m)
        np.testing.assert_allclose(jac[:, :, :, k], np.transpose(fd, (0, 2, 1)), atol=1e-8)


def test_parameters_by_name_and_missing_parameter():
    x, y = sp.symbols("x y")
    a = sp.Symbol("a")
    compiled = compile_fields((x, y), [(a * sp.cos(y), 1)], {"a": 2})
    np.testing.assert_allclose(compiled.field_values([0.0, 0.0])[0, :, 0], [2.0, 1.0])
    with pytest.raises(ModelError, match="a"):
        compile_fields((x, y), [(a * x, 0)])


def test_numba_backend_agrees_with_numpy():
    pytest.importorskip("numba")
    system = get_model("heisenberg")
    rng = np.random.default_rng(3)
    pts = rng.normal(size=(5, system.n))
    u = rng.normal(size=(5, system.m))
    a = compile_system(system, backend="numpy")
    b = compile_system(system, backend="numba")
    np.testing.assert_allclose(b.field_values(pts), a.field_values(pts), atol=1e-15)
    np.testing.assert_allclose(b.rhs(pts, u), a.rhs(pts, u), atol=1e-15)


def test_generated_code_is_cached_by_content(tmp_path, monkeypatch):
    monkeypatch.setenv("NILPOTENT_CACHE", str(tmp_path))
    x, y = sp.symbols("x y")
    one = compile_fields((x, y), [(sp.sin(x) + 7 * y, x)], backend="numpy")
    two = compile_fields((x, y), [(sp.sin(x) + 7 * y, x)], backend="numpy")
    other = compile_fields((x, y), [(sp.sin(x) + 8 * y, x)], backend="numpy")
    assert one.key == two.key != other.key
    one.field_values([1.0, 2.0])
    assert (tmp_path / f"np_{one.key}.py").exists()
    # renaming the coordinates does not change the generated code
    p, q = sp.symbols("p q")
    assert compile_fields((p, q), [(sp.sin(p) + 7 * q, p)]).key == one.key


def test_jax_backend_missing_says_how_to_install(monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "jax" else real(name, *a)
    )
    compiled = compile_system(get_model("unicycle"), backend="jax")
    with pytest.raises(MissingExtraError, match=r"pip install nilpotent\[jax\]"):
        compiled.field_values([0.0, 0.0, 0.0])


def test_bad_backend_and_shapes():
    with pytest.raises(OptionError):
        compile_system(get_model("unicycle"), backend="fortran")
    compiled = compile_system(get_model("unicycle"), backend="numpy")
    with pytest.raises(OptionError):
        compiled.field_values(np.zeros((2, 4)))


def test_dop853_tableau_order_conditions():
    """Quadrature conditions Σ b_i c_i^(k−1) = 1/k (k = 1..8) and consistency of the rows."""
    tab = TABLEAUX["dop853"]
    assert tab is DOP853 and tab.order == 8
    b = np.array(tab.b)
    c = np.array(tab.c)
    for k in range(1, 9):
        assert abs(b @ c ** (k - 1) - 1 / k) < 1e-13
    for s, row in enumerate(tab.a):
        assert len(row) == s
        assert abs(sum(row) - c[s]) < 1e-13
    # second-order condition Σ b_i a_ij c_j = 1/6 and a fourth-order one Σ b_i c_i a_ij c_j = 1/8
    a = np.zeros((tab.stages, tab.stages))
    for s, row in enumerate(tab.a):
        a[s, : len(row)] = row
    assert abs(b @ a @ c - 1 / 6) < 1e-13
    assert abs((b * c) @ a @ c - 1 / 8) < 1e-13
    # error estimators are differences of consistent weights: they sum to 0
    assert abs(sum(tab.e3)) < 1e-13 and abs(sum(tab.e5)) < 1e-13


def test_jax_source_is_valid_python_using_jax_numpy():
    """The JAX code is printed by sympy's JaxPrinter; check it without needing jax."""
    import ast

    from nilpotent.numeric.compile import _jax_source, _prepare

    compiled = compile_system(get_model("trident-snake"))
    text = _jax_source(_prepare(compiled.fields, compiled.n), "trident")
    tree = ast.parse(text)
    names = {f.name for f in tree.body if isinstance(f, ast.FunctionDef)}
    assert names == {"fields", "rhs"}
    assert "jax.numpy.sin" in text and "math." not in text and "numpy.sin" in text


def test_compiled_system_pickles_without_its_modules():
    import pickle

    compiled = compile_system(get_model("unicycle"), backend="numpy")
    compiled.field_values([0.0, 0.0, 0.0])  # loads the generated module
    again = pickle.loads(pickle.dumps(compiled))
    assert again.key == compiled.key and again.fields == compiled.fields
    np.testing.assert_array_equal(again.field_values([[1.0, 2.0, 0.5]]),
                                  compiled.field_values([[1.0, 2.0, 0.5]]))
