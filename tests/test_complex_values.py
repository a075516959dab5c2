"""Values that are not real are never turned into real numbers.

A field whose value at a point has a non-zero imaginary part (the square root
of a negative number, ``log`` of a negative number, ``asin(2)``…) must come out
NaN from every numeric path (numpy, numba, the scipy and heyoka engines, the
outline of the planner), or be refused with a clear error; the certified
evaluators refuse it.  The reference values are independent: ``math.sqrt`` and
sympy/mpmath evaluation of the exact expression at exact points.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import symengine as se
import sympy as sp
from hypothesis import example, given, settings
from hypothesis import strategies as st

from nilpotent.core.decide.evaluation import Evaluator, NotEvaluable, SymbolicEvaluator
from nilpotent.core.model.expressions import ExpressionError, parse_expression
from nilpotent.core.model.modelfile import system_from_dict
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ModelError, NilpotentError
from nilpotent.numeric import compile_fields, compile_system, integrate
from nilpotent.numeric.compile import numba_available
from nilpotent.numeric.engines.base import Status
from nilpotent.numeric.engines.heyoka_engine import heyoka_available
from nilpotent.numeric.signals import piecewise_constant
from nilpotent.planning.robot import _real_or_nan

x, y, z = sp.symbols("x y z")
ISSUE = sp.sqrt(-(x**2 + y**2 + z**2))

needs_numba = pytest.mark.skipif(not numba_available(), reason="numba not installed")
needs_heyoka = pytest.mark.skipif(not heyoka_available(), reason="heyoka not installed")


def _no_complex_warning():
    """A context turning numpy's ComplexWarning (an imaginary part dropped) into an error."""
    ctx = warnings.catch_warnings()
    ctx.__enter__()
    warnings.simplefilter("error", np.exceptions.ComplexWarning)
    return ctx


def _issue_system() -> ControlSystem:
    return ControlSystem("sqrt-negative", (x, y, z), ((ISSUE, 0, 0), (0, 1, 0)))


# --- the issue's field --------------------------------------------------------------
@pytest.mark.parametrize("backend", ["numpy", pytest.param("numba", marks=needs_numba)])
def test_issue_field_is_nan_off_the_origin_and_zero_at_it(backend):
    c = compile_fields((x, y, z), ((ISSUE, 0, 0), (0, 1, 0)), name="issue", backend=backend)
    pts = np.array([[1.0, 2.0, 3.0], [0.0, 0.0, 0.0], [-0.5, 0.0, 0.0], [0.0, 0.0, 1e-3]])
    ctx = _no_complex_warning()
    try:
        with np.errstate(invalid="ignore"):
            vals = c.field_values(pts)[:, 0, 0]
            rhs = c.rhs(pts, np.array([1.0, 0.0]))[:, 0]
    finally:
        ctx.__exit__(None, None, None)
    # exact: I*sqrt(14), 0, I/2, I/1000
    assert np.isnan(vals[[0, 2, 3]]).all()
    assert vals[1] == 0.0
    assert np.isnan(rhs[[0, 2, 3]]).all() and rhs[1] == 0.0
    # the other field is untouched
    with np.errstate(invalid="ignore"):
        assert (c.field_values(pts)[:, 1, 1] == 1.0).all()


def test_issue_jacobian_is_not_a_real_number_off_the_origin():
    c = compile_fields((x, y, z), ((ISSUE, 0, 0),), name="issue-jac", backend="numpy")
    ctx = _no_complex_warning()
    try:
        with np.errstate(invalid="ignore", divide="ignore"):
            jac = c.jacobian(np.array([[1.0, 2.0, 3.0]]))
    finally:
        ctx.__exit__(None, None, None)
    # d/dx sqrt(-(x²+y²+z²)) = -x / sqrt(-(…)): imaginary at (1, 2, 3)
    assert np.isnan(jac[0, 0, 0, :]).all()


ENGINES = [
    "scipy",
    # compiling a system's numba integrators takes 20-30 s with a cold cache
    pytest.param("numba", marks=[needs_numba, pytest.mark.slow]),
    pytest.param("heyoka", marks=needs_heyoka),
]


@pytest.mark.parametrize("engine", ENGINES)
def test_every_engine_stops_non_finite_outside_the_domain(engine):
    c = compile_system(_issue_system())
    sig = piecewise_constant(np.array([[1.0, 0.0]]), [0.25])
    with np.errstate(all="ignore"):
        sol = integrate(c, np.array([[1.0, 2.0, 3.0], [0.3, 0.0, 0.0]]), sig, engine=engine)
    assert (sol.status == Status.NON_FINITE).all()


# --- a field with an open domain: sqrt(1 - x**2) ------------------------------------
def _disc_system() -> ControlSystem:
    return ControlSystem("half-disc", (x, y), ((1, 0), (0, sp.sqrt(1 - x**2))))


@pytest.mark.parametrize("backend", ["numpy", pytest.param("numba", marks=needs_numba)])
def test_sqrt_one_minus_x_squared_values(backend):
    c = compile_fields((x, y), ((1, 0), (0, sp.sqrt(1 - x**2))), name="disc", backend=backend)
    xs = np.array([-2.0, -1.0 - 1e-9, -0.75, 0.0, 0.3, 1.0, 1.5])
    pts = np.stack([xs, np.zeros_like(xs)], axis=1)
    with np.errstate(invalid="ignore"):
        vals = c.field_values(pts)[:, 1, 1]
    for xv, v in zip(xs, vals, strict=True):
        if abs(xv) > 1:
            assert math.isnan(v), (xv, v)
        else:
            assert v == pytest.approx(math.sqrt(1 - xv * xv), rel=1e-15, abs=0)


@pytest.mark.parametrize("engine", ENGINES)
def test_sqrt_one_minus_x_squared_integrated(engine):
    c = compile_system(_disc_system())
    sig = piecewise_constant(np.array([[0.0, 1.0]]), [0.5])
    with np.errstate(all="ignore"):
        sol = integrate(c, np.array([[0.6, 0.0], [1.5, 0.0]]), sig, engine=engine)
    # inside: x stays 0.6, y grows at the constant rate sqrt(1 - 0.36) = 0.8
    assert sol.status[0] == Status.SUCCESS
    assert sol.final[0, 0] == pytest.approx(0.6, abs=1e-12)
    assert sol.final[0, 1] == pytest.approx(0.5 * math.sqrt(1 - 0.36), rel=1e-9)
    # outside: no number
    assert sol.status[1] == Status.NON_FINITE


# --- fields that are not real anywhere: refused ------------------------------------
@pytest.mark.parametrize("field", [sp.sqrt(-x**2), sp.sqrt(-sp.exp(y)), sp.sqrt(-2) * x,
                                   sp.acosh(0) * x, sp.log(-2) + x,
                                   sp.Integer(-8) ** sp.Rational(1, 3) * x])
def test_a_field_with_the_imaginary_unit_is_refused_by_the_model(field):
    with pytest.raises(ModelError, match=r"field X1\[x\] is not real"):
        ControlSystem("imaginary", (x, y), ((field, 1),))


def test_a_parameter_value_making_a_field_imaginary_is_refused():
    p = sp.Symbol("p")
    ok = ControlSystem("param", (x, y), ((sp.sqrt(p * x**2), 1),), (("p", 1),))
    with pytest.raises(ModelError, match=r"field X1\[x\] is not real"):
        ok.with_parameters({"p": -1})
    with pytest.raises(ModelError, match=r"field X1\[x\] is not real"):
        system_from_dict({"coordinates": ["x", "y"], "parameters": {"p": -2},
                          "fields": [{"x": "sqrt(p*x**2)", "y": "1"}]})


def test_model_text_with_a_complex_constant_is_refused():
    names = {"x": x}
    # (-8)**(1/3) is sympy's principal cube root 2*(-1)**(1/3) = 1 + I*sqrt(3), not -2
    for text in ["sqrt(-1)*x", "(-2)**(1/2)*x", "log(-2)*x", "acosh(0)*x", "(-8)**(1/3)*x",
                 "x + (-1/2)**(3/2)"]:
        with pytest.raises(ExpressionError):
            parse_expression(text, names)
    for text in ["sqrt(-1)*x", "(-8)**(1/3)*x"]:
        with pytest.raises(NilpotentError, match=r"complex|not real"):
            system_from_dict({"coordinates": ["x"], "fields": [{"x": text}]})
    # real roots stay: 8**(1/3) is 2, (-8)**2 is 64
    s = system_from_dict({"coordinates": ["x"], "fields": [{"x": "8**(1/3)*x + (-8)**2"}]})
    assert s.fields[0][0] == 2 * x + 64


@pytest.mark.parametrize("field", [sp.I * x, sp.sqrt(-x**2), sp.asin(2) * x, sp.acos(3) + x])
def test_compiling_a_non_real_field_is_an_error(field):
    # compile_fields takes sympy directly (no ControlSystem check before it)
    with pytest.raises(ModelError, match=r"not (a )?real"):
        compile_fields((x,), ((field,),), name="direct", backend="numpy").field_values([[1.0]])


# --- the planner's outline --------------------------------------------------------
def test_outline_values_with_an_imaginary_part_are_nan():
    v = np.array([1.0 + 0j, 2.0 + 1e-300j, -3.0 + 0j])
    out = _real_or_nan(v)
    assert out.dtype == np.float64
    assert out[0] == 1.0 and math.isnan(out[1]) and out[2] == -3.0
    assert _real_or_nan(2.5) == 2.5
    assert math.isnan(_real_or_nan(1j))


# --- the certified evaluators -----------------------------------------------------
S = se.Symbol("s")


@pytest.mark.parametrize(("expr", "value"), [
    (se.sqrt(-S), 2), (S ** se.Rational(1, 3), -8), (se.asin(S), 2), (se.acos(S), -3),
    (se.log(S), -1), (se.I * S, 1),
])
def test_symbolic_evaluator_refuses_complex_values(expr, value):
    with pytest.raises(NotEvaluable, match="complex"):
        SymbolicEvaluator({S: se.Integer(value)}).value(expr)


@pytest.mark.parametrize(("expr", "value", "exact"), [
    (se.sqrt(-S), 0, 0), (se.sqrt(-S), -4, 2), (S ** se.Rational(1, 3), 8, 2),
    (se.asin(S), 1, se.pi / 2),
])
def test_symbolic_evaluator_keeps_real_values(expr, value, exact):
    assert se.expand(SymbolicEvaluator({S: se.Integer(value)}).value(expr) - exact) == 0


@pytest.mark.parametrize(("expr", "value"), [
    (se.sqrt(-S), 2), (se.asin(S), 2), (se.acos(S), -3), (se.log(S), -1), (se.I * S, 1),
])
def test_ball_evaluator_refuses_complex_values(expr, value):
    from flint import arb

    with pytest.raises(NotEvaluable, match="complex"):
        Evaluator({S: arb(value)}, exact=False).value(expr)


# --- random points: NaN exactly where the exact value is not real -------------------
FAMILY = (
    ISSUE,
    sp.sqrt(1 - x**2),
    sp.log(x - y),
    sp.asin(x / 2),
    sp.acos(y - 1),
    sp.acosh(x),
    sp.atanh(x / 2),
    (x - 1) ** sp.Rational(3, 2),
    (y + z) ** sp.Rational(1, 3),
    x * sp.sqrt(z - y) + 1,
    sp.sqrt(x * y - z) * sp.cos(z),
)


def _exact(e: sp.Expr, point: tuple[sp.Rational, ...]) -> tuple[float, float] | None:
    """(real, imaginary) parts of the exact value (mpmath, 30 digits); ``None`` if not finite."""
    v = e.subs(dict(zip((x, y, z), point, strict=True)))
    if v.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        return None
    re, im = sp.N(v, 30).as_real_imag()
    return float(re), float(im)


def _real_arithmetic(e: sp.Expr, point: tuple[sp.Rational, ...]) -> float | None:
    """The value in real arithmetic: NaN if some subexpression is not real; ``None`` at a pole.

    ``x*sqrt(z - y) + 1`` at ``x = 0, z < y`` is exactly 1, but its part
    ``sqrt(z - y)`` is not real: real arithmetic (the engines') has no value there.
    """
    exact = _exact(e, point)
    if exact is None:
        return None
    for part in sp.preorder_traversal(e):
        if isinstance(part, sp.Expr) and part.free_symbols:
            sub = _exact(part, point)
            if sub is None:
                return None
            if sub[1] != 0:
                return math.nan
    return exact[0] if exact[1] == 0 else math.nan


@pytest.fixture(scope="module")
def family_engines():
    """Each engine's evaluation of the family, compiled once: name → (floats (3,) → (K,))."""
    system = ControlSystem("family", (x, y, z), tuple((e, 0, 0) for e in FAMILY))
    out = {}
    np_sys = compile_fields(system.coordinates, system.fields, name="family", backend="numpy")
    out["numpy"] = lambda p: np_sys.field_values(p[None, :])[0, 0, :]
    if numba_available():
        nb_sys = compile_fields(system.coordinates, system.fields, name="family",
                                backend="numba")
        out["numba"] = lambda p: nb_sys.field_values(p[None, :])[0, 0, :]
    if heyoka_available():
        import heyoka as hy

        from nilpotent.numeric.engines.heyoka_engine import _convert

        hv = list(hy.make_vars("q0", "q1", "q2"))
        smap = dict(zip(sp.symbols("q0:3", real=True), hv, strict=True))
        cf = hy.cfunc([_convert(hy, np_sys, row[0], smap) for row in np_sys.fields], hv)
        out["heyoka"] = lambda p: cf(p)
    return out


eighths = st.integers(min_value=-24, max_value=24)  # k/8: exact in floating point


@settings(max_examples=40, deadline=None)
@given(ints=st.tuples(eighths, eighths, eighths))
@example(ints=(0, 0, 0)).via("the issue's field is the real 0 at the origin")
@example(ints=(8, 16, 24)).via("the issue's point (1, 2, 3)")
@example(ints=(0, 0, -1)).via("x*sqrt(z - y) + 1 at x = 0: exactly 1, but a part is not real")
def test_engines_are_nan_exactly_where_the_value_is_not_real(family_engines, ints):
    """NaN wherever the exact value is not real; else NaN exactly where some part is not
    real (real arithmetic), else the exact value to 1e-12."""
    point = tuple(sp.Rational(k, 8) for k in ints)
    floats = np.array([k / 8 for k in ints])
    with np.errstate(all="ignore"):
        values = {name: fn(floats) for name, fn in family_engines.items()}
    for k, e in enumerate(FAMILY):
        exact = _exact(e, point)
        if exact is None:
            continue  # a pole (log 0, atanh 1): not the subject here
        expected = _real_arithmetic(e, point)
        assert expected is not None
        for name, vals in values.items():
            got = float(vals[k])
            if exact[1] != 0:  # the value is not real: never a number
                assert math.isnan(got), (name, e, point, exact, got)
            if math.isnan(expected):
                assert math.isnan(got), (name, e, point, exact, got)
            else:
                assert math.isclose(got, expected, rel_tol=1e-12, abs_tol=1e-12), (
                    name, e, point, exact, got)


def test_generated_code_holds_no_imaginary_unit_and_still_shares_subexpressions():
    from nilpotent.numeric.compile import _jacobian_source, _numba_source, _numpy_source

    shared = sp.sin(x * y + z)
    c = compile_fields((x, y, z), ((ISSUE * shared, shared**2, 0),), name="shared",
                       backend="numpy")
    prep = c._prepared
    texts = [_numpy_source(prep, "shared"), _jacobian_source(c.fields, 3, "shared")]
    if numba_available():
        texts.append(_numba_source(prep, "shared"))
    for text in texts:
        assert "1j" not in text and "I" not in text
    assert prep.replacements  # the common sin(...) is computed once


def test_an_outline_with_an_imaginary_centre_is_refused():
    raw = {
        "name": "imaginary-disc", "coordinates": ["x", "y"], "parameters": {"p": -1},
        "fields": [{"x": "1"}, {"y": "1"}],
        "geometry": {"discs": [{"center": ["x + sqrt(p)", "y"], "radius": "0.1"}]},
    }
    # sqrt(p) = I: the centre x + I is no point of the plane (its real part would be x)
    with pytest.raises(ModelError, match=r"geometry\.discs\[0\].* is not real"):
        system_from_dict(raw)
    raw["parameters"] = {"p": 4}
    assert system_from_dict(raw).geometry is not None
