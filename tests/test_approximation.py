"""Nilpotent approximation: properties re-derived with plain sympy, free nilpotent
dimensions (Witt), invariance under coordinate changes, singular points, and a
certificate that fails on deliberately broken approximations."""

from __future__ import annotations

import dataclasses

import hypothesis.strategies as st
import pytest
import symengine as se
import sympy as sp
from hypothesis import HealthCheck, given, settings

from conftest import model_point
from nilpotent.core.analysis.filtration import analyze
from nilpotent.core.coordinates.approximation import approximate, certify
from nilpotent.core.coordinates.privileged import METHODS
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import NotPrivilegedError, OptionError
from nilpotent.models import get_model
from polynomial_systems import (
    base_system,
    change_coordinates,
    changed_systems,
    free_nilpotent,
    growth_vector_at,
    right_normed_brackets,
    span_dimension,
    weighted_parts,
    witt_dimension,
)


def independent_checks(sys: ControlSystem, a) -> None:
    """Re-derive the approximation's defining properties with plain sympy."""
    y, w, r = a.names, a.weights, a.filtration.step
    lam = sp.Symbol("lam", positive=True)
    dil = {v: lam**wj * v for v, wj in zip(y, w, strict=True)}
    for f in a.fields:  # homogeneous of degree -1
        for c, wj in zip(f, w, strict=True):
            assert sp.expand(c.xreplace(dil) - lam ** (wj - 1) * c) == 0
    # nilpotent of step r: brackets of length r+1 vanish, some of length r do not (and are constant)
    assert right_normed_brackets(a.fields, y, r + 1) == []
    top = right_normed_brackets(a.fields, y, r)
    assert top and all(sp.Matrix(b).free_symbols == set() for b in top)
    # growth vector of X̂ at 0 equals the growth vector of X at p (both by sympy brackets)
    assert growth_vector_at(a.fields, y, (0,) * len(y), r) == growth_vector_at(
        sys.specialized_fields, sys.coordinates, a.point, r + 2
    )
    # X̂_i(p) = X_i(p) in the model coordinates
    at = dict(zip(sys.coordinates, a.point, strict=True))
    for fx, f in zip(a.fields_x, sys.specialized_fields, strict=True):
        assert [
            sp.simplify(u.xreplace(at) - v.xreplace(at)) for u, v in zip(fx, f, strict=True)
        ] == [0] * sys.n


@pytest.mark.parametrize("method", ["auto", "algebraic", "exponential", "exponential-1"])
@pytest.mark.every_model
def test_certificate_and_independent_checks(model, method):
    sys = model
    a = approximate(sys, model_point(model), method)
    assert a.certificate.ok, a.certificate.failures()
    assert a.certificate.nilpotent_step == a.filtration.step
    independent_checks(sys, a)


def test_trident_step_2_with_constant_brackets():
    """Step 2 (not 1): [X̂_i, X̂_j] are the constant fields of the frame, length-3 brackets vanish."""
    a = approximate(get_model("trident-snake"))
    assert a.coordinates.method == "linear" and a.certificate.nilpotent_step == 2
    assert len(right_normed_brackets(a.fields, a.names, 2)) == 6  # ± [X̂i,X̂j], i ≠ j
    assert right_normed_brackets(a.fields, a.names, 3) == []


@pytest.mark.parametrize(("m", "r"), [(2, 1), (2, 2), (2, 3), (2, 4), (3, 2)])
def test_free_nilpotent_dimensions(m, r):
    """The Lie algebra of X̂ has the free nilpotent dimension Σ_k Witt(m, k)."""
    sys = free_nilpotent(m, r)
    a = approximate(sys)
    assert a.certificate.ok
    expected_growth = tuple(
        sum(witt_dimension(m, k) for k in range(1, s + 1)) for s in range(1, r + 1)
    )
    assert a.certificate.growth_vector_at_0 == expected_growth
    brackets = [b for k in range(1, r + 1) for b in right_normed_brackets(a.fields, a.names, k)]
    assert span_dimension(brackets, a.names) == expected_growth[-1]
    assert right_normed_brackets(a.fields, a.names, r + 1) == []


@pytest.mark.parametrize("name", ["heisenberg", "engel", "martinet", "free-2-4", "free-3-2"])
def test_nilpotent_homogeneous_system_approximates_to_itself(name):
    sys = free_nilpotent(int(name[5]), int(name[7])) if name.startswith("free") else get_model(name)
    a = approximate(sys)
    assert a.fields_x == sys.specialized_fields
    assert a.as_system("x").fields == sys.specialized_fields


def test_martinet_singular_point():
    a = approximate(get_model("martinet"))
    assert not a.filtration.regular
    assert a.certificate.growth_vector_at_0 == (2, 2, 3) and a.weights == (1, 1, 3)
    assert a.certificate.nilpotent_step == 3 and a.certificate.ok


def test_linear_refused_where_not_privileged():
    e = get_model("engel")
    x1, x2, x3, _ = e.coordinates
    sys = change_coordinates(e, [0, 0, x1 * x2, x1**2 + x2 * x3])
    with pytest.raises(NotPrivilegedError, match="y4 has order 2 but weight 3"):
        approximate(sys, None, "linear")
    assert approximate(sys).coordinates.method == "algebraic"


def test_car_trailers_5_needs_algebraic_coordinates():
    a = approximate(get_model("car-trailers:5"))
    assert a.coordinates.method == "algebraic"
    assert a.certificate.ok and a.certificate.nilpotent_step == 7


# --- invariance under coordinate changes; an independent recomputation ----------------------

def fields_in_y_by_sympy(sys: ControlSystem, a) -> list[list[sp.Expr]]:
    """[X_i]_y = (∂y/∂x)(x(y)) X_i(x(y)), exactly, with plain sympy (polynomial systems)."""
    c = a.coordinates
    J = sp.Matrix(c.forward).jacobian(sys.coordinates)
    sub = dict(zip(sys.coordinates, c.inverse, strict=True))
    return [
        [sp.expand(e) for e in (J * sp.Matrix(f)).xreplace(sub)] for f in sys.specialized_fields
    ]


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(changed_systems(), st.sampled_from(["auto", "algebraic", "exponential"]))
def test_changed_systems(case, method):
    name, sys = case
    a = approximate(sys, None, method)
    assert a.filtration.growth_vector == analyze(base_system(name)).growth_vector
    assert a.certificate.ok, a.certificate.failures()
    # independent: the whole approximation recomputed from the exact fields in y
    for f, hat in zip(fields_in_y_by_sympy(sys, a), a.fields, strict=True):
        for j, (e, h) in enumerate(zip(f, hat, strict=True)):
            parts = weighted_parts(e, a.names, a.weights)
            assert min(parts, default=a.weights[j]) >= a.weights[j] - 1
            assert sp.expand(parts.get(a.weights[j] - 1, 0) - h) == 0


@settings(max_examples=10, deadline=None)
@given(st.sampled_from(["engel", "cartan", "free-2-3"]), st.data())
def test_higher_order_perturbations_do_not_change_the_approximation(name, data):
    """Adding terms of weighted degree ≥ w_j to component j changes nothing in X̂."""
    sys = base_system(name)
    a0 = approximate(sys)
    x, w = sys.coordinates, a0.weights
    fields = []
    for f in sys.specialized_fields:
        new = list(f)
        j = data.draw(st.sampled_from(range(sys.n)))
        k = data.draw(st.sampled_from(range(sys.n)))
        c = data.draw(st.integers(-3, 3))
        power = -(-w[j] // w[k])  # smallest p with p·w_k ≥ w_j
        new[j] = new[j] + c * x[k] ** power
        fields.append(tuple(new))
    a1 = approximate(ControlSystem("perturbed", x, tuple(fields)))
    assert a1.filtration.weights == w
    assert a1.fields == a0.fields


# --- the certificate fails on broken approximations --------------------------------------------


def broken(a, i, j, expr):
    fields = [list(f) for f in a.fields]
    fields[i][j] = expr
    return dataclasses.replace(a, fields=tuple(tuple(f) for f in fields))


def test_certificate_detects_a_dropped_term():
    a = approximate(get_model("engel"))
    assert a.fields[1][3] != 0
    bad = certify(broken(a, 1, 3, sp.Integer(0)))  # drop the y4-component of X̂2
    assert not bad.remainder_order_ok and min(bad.remainder_orders) == -1
    assert bad.nilpotent_step == 2 and bad.growth_vector_at_0 == (2, 3)
    assert not bad.ok


def test_certificate_detects_a_term_of_wrong_degree():
    a = approximate(get_model("engel"))
    y1, y2, y3, _y4 = a.names
    bad = certify(broken(a, 1, 3, a.fields[1][3] + y1 * y2 * y3))
    assert not bad.homogeneous and not bad.ok
    bad = certify(broken(a, 1, 3, a.fields[1][3] + y1))  # wrong degree and too low: order -2
    assert not bad.homogeneous and not bad.remainder_order_ok


def test_certificate_detects_a_wrong_jacobian():
    """Substituting y(x) into the components without the Jacobian is caught."""
    e = get_model("engel")
    x1, x2, x3, _ = e.coordinates
    a = approximate(change_coordinates(e, [0, 0, x1 * x2, x1**2 + x2 * x3]))
    sub = dict(zip(a.names, a.coordinates.forward, strict=True))
    naive = tuple(tuple(sp.expand(c.xreplace(sub)) for c in f) for f in a.fields)
    bad = certify(dataclasses.replace(a, fields_x=naive))
    assert not bad.pushforward_ok and not bad.ok
    assert certify(a).ok


def test_certificate_detects_a_non_nilpotent_step():
    a = approximate(get_model("heisenberg"))
    _y1, _y2, y3 = a.names
    bad = certify(broken(a, 0, 1, a.fields[0][1] + y3))  # y3 has weight 2: X̂1 gains degree +1 term
    assert not bad.homogeneous and bad.nilpotent_step != 2 and not bad.ok


def test_certificate_detects_wrong_orders():
    """Linear maps put in place of the algebraic ones: the recomputed orders show it."""
    e = get_model("engel")
    x1, x2, x3, _ = e.coordinates
    a = approximate(change_coordinates(e, [0, 0, x1 * x2, x1**2 + x2 * x3]))
    ident = a.coordinates.forward_poly[0].__class__
    n = 4
    lin = tuple(ident.variable(n, k) for k in range(n))
    c = dataclasses.replace(a.coordinates, forward_poly=lin, inverse_poly=lin)
    bad = certify(dataclasses.replace(a, coordinates=c), recompute_orders=True)
    assert bad.orders == (1, 1, 2, 2) and not bad.privileged and not bad.ok
    assert certify(a, recompute_orders=True).privileged


# --- output ---------------------------------------------------------------------------------


def test_outputs():
    a = approximate(get_model("unicycle"))
    text = str(a)
    assert "X̂1" in text and "∂y" in text and "certificate" in text
    tex = a.to_latex()
    assert tex.startswith("\\begin{align*}") and "\\hat X_{2}" in tex and "\\partial_{y_{3}}" in tex
    s = a.as_system("y")
    assert s.coordinates == a.names and s.fields == a.fields
    with pytest.raises(OptionError):
        a.as_system("z")


def test_numeric_on_request_matches_exact():
    sys = get_model("trident-snake")
    exact, flt = approximate(sys), approximate(sys, numeric=True)
    assert not exact.coordinates.numeric and flt.coordinates.numeric
    assert flt.certificate.ok and not flt.certificate.exact and "floating point" in str(flt)
    for fe, ff in zip(exact.fields, flt.fields, strict=True):
        for a, b in zip(fe, ff, strict=True):
            diff = sp.expand(a - b)
            assert (
                all(abs(c) < 1e-12 for c in sp.Poly(diff, *exact.names).coeffs())
                if diff != 0
                else True
            )


def test_methods_registry_and_unknown_method():
    assert set(METHODS) == {"linear", "algebraic", "exponential", "exponential-1"}
    with pytest.raises(OptionError):
        approximate(get_model("unicycle"), None, "magic")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["car-trailers:5", "car-trailers:6"])
def test_long_trailer_chains_are_certified(name):
    """Issue 3's largest cases (their speed targets: ``benchmarks/approximation.py``)."""
    a = approximate(get_model(name))
    assert a.certificate.ok and a.certificate.nilpotent_step == int(name[-1]) + 2


def _bracket_se(X, Y, ys):
    """[X, Y] = DY·X − DX·Y for symengine polynomial fields (an independent evaluation)."""
    return tuple(
        se.expand(
            sum((xk * yj.diff(v) for xk, v in zip(X, ys, strict=True)), se.Integer(0))
            - sum((yk * xj.diff(v) for yk, v in zip(Y, ys, strict=True)), se.Integer(0))
        )
        for xj, yj in zip(X, Y, strict=True)
    )


@pytest.mark.slow
@pytest.mark.parametrize("k", [7, 8])
def test_car_trailers_approximation_properties(k):
    """Issue 13's largest approximations (speed: ``benchmarks/approximation.py``), by properties.

    Checked independently of the certificate: each field of the approximation is
    homogeneous of degree −1 under the dilations (so every bracket of length L is
    homogeneous of degree −L, and vanishes for L > max w: nilpotent of step ≤ r),
    and the brackets of the frame words at 0 reach the growth vector (2, 3, ..., K + 3)
    of the system at the origin (Jean 1996), length by length (a bracket of length L
    has at 0 components only where w_j = L, so no more is possible).
    """
    a = approximate(get_model(f"car-trailers:{k}"))
    n, w = k + 3, a.weights
    assert a.filtration.growth_vector == tuple(range(2, k + 4))
    assert w == (1, 1, *range(2, k + 3))
    ys = [se.Symbol(str(s)) for s in a.names]
    lam = se.Symbol("lam")
    dil = {y: lam**wj * y for y, wj in zip(ys, w, strict=True)}
    fields = [tuple(se.S(c) for c in f) for f in a.fields]
    for f in fields:
        for c, wj in zip(f, w, strict=True):
            assert se.expand(c.xreplace(dil) - lam ** (wj - 1) * c) == 0
    memo: dict = {}

    def field(word):
        if word not in memo:
            memo[word] = (
                fields[word - 1]
                if isinstance(word, int)
                else _bracket_se(field(word[0]), field(word[1]), ys)
            )
        return memo[word]

    zero = {y: 0 for y in ys}
    values = [[sp.S(c.xreplace(zero)) for c in field(word)] for word in a.filtration.frame]
    for length in range(1, max(w) + 1):
        rows = [v for v, wj in zip(values, w, strict=True) if wj <= length]
        assert sp.Matrix(rows).rank() == sum(1 for wj in w if wj <= length)
    cert = a.certificate
    assert cert.ok and cert.nilpotent_step == k + 2 and cert.growth_vector_at_0 == tuple(
        range(2, k + 4)
    )
    assert len(a.fields_x) == 2 and all(len(f) == n for f in a.fields_x)
