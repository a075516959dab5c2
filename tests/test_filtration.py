"""Growth vectors, weights, adapted frames, regularity: literature values and invariance."""

from __future__ import annotations

import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from nilpotent.core.analysis.filtration import analyze, singular_locus
from nilpotent.core.lie.brackets import word_length
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ModelError, NotBracketGeneratingError, PointError
from nilpotent.models import get_model

x1, x2, x3, x4, x5 = sp.symbols("x1:6")
x, y, th = sp.symbols("x y theta")

UNICYCLE = ControlSystem("unicycle", (x, y, th), ((sp.cos(th), sp.sin(th), 0), (0, 0, 1)))
HEISENBERG = ControlSystem(
    "heisenberg", (x1, x2, x3), ((1, 0, -x2 / 2), (0, 1, x1 / 2))
)
ENGEL = ControlSystem("engel", (x1, x2, x3, x4), ((1, 0, 0, 0), (0, 1, x1, x3)))
CARTAN = ControlSystem(
    "cartan", (x1, x2, x3, x4, x5), ((1, 0, 0, 0, 0), (0, 1, x1, x1**2 / 2, x1 * x2))
)
MARTINET = ControlSystem("martinet", (x1, x2, x3), ((1, 0, x2**2 / 2), (0, 1, 0)))


def _rank(rows) -> int:
    return sp.Matrix(rows).rank(simplify=True) if rows else 0


def _check_adapted(f):
    """Frame words have lengths = weights and the first n_s values span a space of dim n_s."""
    assert [word_length(w) for w in f.frame] == list(f.weights)
    for n_s in f.growth_vector:
        assert _rank(f.frame_values[:n_s]) == n_s
    assert f.step == len(f.growth_vector)


def test_unicycle():
    f = analyze(UNICYCLE)
    assert f.growth_vector == (2, 3) and f.weights == (1, 1, 2) and f.step == 2
    assert f.frame_names == ("X1", "X2", "[X1,X2]")
    # by hand: X1(0) = e_x, X2(0) = e_theta, [X1,X2](0) = (sin 0, -cos 0, 0)
    assert f.frame_values == ((1, 0, 0), (0, 0, 1), (0, -1, 0))
    assert f.regular and f.bracket_generating and f.exact
    _check_adapted(f)


@pytest.mark.parametrize(
    ("sys", "growth"), [(HEISENBERG, (2, 3)), (ENGEL, (2, 3, 4)), (CARTAN, (2, 3, 5))]
)
def test_classical_growth_vectors(sys, growth):
    f = analyze(sys)
    assert f.growth_vector == growth
    assert f.regular and f.bracket_generating
    assert f.generic_growth_vector == growth
    _check_adapted(f)


def test_cartan_weights_and_frame():
    f = analyze(CARTAN)
    assert f.weights == (1, 1, 2, 3, 3)
    # by hand: [X1,X2] = (0,0,1,x1,x2), [X1,[X1,X2]] = e4, [X2,[X1,X2]] = e5
    assert f.frame_values[2:] == ((0, 0, 1, 0, 0), (0, 0, 0, 1, 0), (0, 0, 0, 0, 1))


def test_martinet_singular_at_origin_regular_elsewhere():
    f = analyze(MARTINET)
    assert f.growth_vector == (2, 2, 3)
    assert f.weights == (1, 1, 3)
    assert not f.regular and f.bracket_generating
    assert f.generic_growth_vector == (2, 3)
    # [X1,X2] = (0,0,-x2) vanishes at 0; [X2,[X1,X2]] = (0,0,-1)
    assert f.frame_names == ("X1", "X2", "[X2,[X1,X2]]")
    assert f.frame_values[2] == (0, 0, -1)
    _check_adapted(f)
    g = analyze(MARTINET, (0, 1, 0))
    assert g.growth_vector == (2, 3) and g.regular and g.weights == (1, 1, 2)


def test_singular_where_a_field_vanishes():
    s = ControlSystem("grushin", (x1, x2), ((1, 0), (0, x1)))
    f = analyze(s)
    assert f.growth_vector == (1, 2) and f.weights == (1, 2)
    assert not f.regular and f.generic_growth_vector == (2,)
    assert analyze(s, (1, 0)).regular


def test_not_bracket_generating_is_reported():
    s = ControlSystem("planes", (x1, x2, x3), ((1, 0, 0), (0, 1, 0)))
    f = analyze(s)
    assert not f.bracket_generating
    assert f.growth_vector == (2,) and f.weights == (1, 1) and f.step == 1
    assert f.regular
    with pytest.raises(NotBracketGeneratingError):
        singular_locus(s, f)


def test_max_length_bounds_the_scan_at_singular_points():
    # X2 = ∂2 + x1^k ∂3 at 0: the first bracket reaching ∂3 is ad_{X1}^k X2 (length k+1),
    # so growth (2, ..., 2, 3) with step k+1; a shorter scan says "not within this length".
    k = 7
    s = ControlSystem("high", (x1, x2, x3), ((1, 0, 0), (0, 1, x1**k)))
    full = analyze(s)
    assert full.bracket_generating and full.step == k + 1 and full.weights == (1, 1, k + 1)
    short = analyze(s, max_length=4)
    # ... and proves bracket generation through the orbit (the flow of X1 = ∂1 leaves x1 = 0)
    assert short.bracket_generating and short.certified_by is not None and short.max_length == 4
    assert short.growth_vector == (2, 2, 2, 2) and short.growth_vector_known_up_to == 4
    assert short.regular is False
    # regular points never need more than the generic step, whatever max_length says
    assert analyze(ENGEL, max_length=2).growth_vector == (2, 3, 4)


def test_invalid_points_and_fields():
    with pytest.raises(PointError):
        analyze(UNICYCLE, (0, 0))
    with pytest.raises(PointError):
        analyze(UNICYCLE, (0, 0, sp.I))
    with pytest.raises(PointError):
        analyze(UNICYCLE, (0, 0, sp.Symbol("a")))
    with pytest.raises(PointError):
        analyze(ControlSystem("pole", (x1, x2), ((1, 0), (0, 1 / x1))), (0, 0))
    with pytest.raises(ModelError):
        analyze(ControlSystem("free", (x1, x2), ((1, 0), (0, sp.Symbol("a")))))


def test_exact_algebraic_and_numeric_points():
    f = analyze(UNICYCLE, (0, 0, sp.pi / 6))
    assert f.exact and f.growth_vector == (2, 3)
    assert f.frame_values[0] == (sp.sqrt(3) / 2, sp.Rational(1, 2), 0)
    # at a transcendental point the full rank is proved by ball arithmetic
    g = analyze(UNICYCLE, (0, 0, sp.Integer(1)))
    assert g.exact and g.growth_vector == (2, 3) and g.undetermined is None


def test_singular_locus():
    # det(X1, X2, [X1,X2]) = -x2 by hand: the locus is {x2 = 0}
    assert singular_locus(MARTINET, analyze(MARTINET, (0, 1, 0))) == x2
    assert sp.simplify(singular_locus(UNICYCLE) - 1) == 0


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_car_trailers_at_origin(k):
    f = analyze(get_model(f"car-trailers:{k}"))
    assert f.growth_vector == tuple(range(2, k + 4))
    assert f.step == k + 2 and f.regular
    _check_adapted(f)


@pytest.mark.parametrize(("k", "step"), [(1, 3), (2, 5), (3, 8)])
def test_car_trailers_perpendicular(k, step):
    # F. Jean (1996): with every trailer perpendicular to the one before, the
    # degree of non-holonomy is a Fibonacci number (3, 5, 8 for 1, 2, 3 trailers).
    sys = get_model(f"car-trailers:{k}")
    point = (0, 0, *(sp.pi / 2 * i for i in range(k + 1)))
    f = analyze(sys, point)
    assert f.step == step and f.growth_vector[-1] == k + 3
    assert f.regular == (k == 1)
    assert f.generic_growth_vector == tuple(range(2, k + 4))
    _check_adapted(f)


# --- invariance under coordinate changes --------------------------------------


def _push_forward(sys, forward, inverse):
    """The system in coordinates y = forward(x): [Z]_y = (dy/dx)[Z]_x evaluated at x(y)."""
    ys = sp.symbols(f"y1:{sys.n + 1}")
    jac = sp.Matrix(forward).jacobian(sys.coordinates)
    back = dict(zip(sys.coordinates, inverse, strict=True))
    fields = []
    for fld in sys.fields:
        comps = jac * sp.Matrix(fld)
        fields.append(tuple(sp.expand(c.subs(back, simultaneous=True)) for c in comps))
    ysub = dict(zip(sys.coordinates, ys, strict=True))
    fields = [tuple(c.subs(ysub, simultaneous=True) for c in f) for f in fields]
    return ControlSystem(sys.name + "-y", ys, tuple(fields))


invertible = st.lists(st.integers(-2, 2), min_size=9, max_size=9).filter(
    lambda v: sp.Matrix(3, 3, v).det() != 0
)


@settings(max_examples=10, deadline=None)
@given(invertible, st.integers(-2, 2), st.integers(-2, 2), st.sampled_from([0, 1]))
def test_growth_vector_invariant_under_coordinate_changes(entries, a, b, which):
    sys, point = [(MARTINET, (0, 0, 0)), (HEISENBERG, (0, 0, 0))][which]
    ref = analyze(sys, point)
    # triangular polynomial change, then a linear one; both fix the origin
    tri = (x1, x2 + a * x1**2, x3 + b * x1 * x2)
    tri_inv_1 = x1
    tri_inv_2 = x2 - a * x1**2
    tri_inv = (tri_inv_1, tri_inv_2, x3 - b * tri_inv_1 * tri_inv_2)
    A = sp.Matrix(3, 3, entries)
    lin = tuple(A * sp.Matrix(tri))
    # inverse: x = tri_inv(A^{-1} y) expressed in x1..x3 standing for y
    z = tuple(A.inv() * sp.Matrix([x1, x2, x3]))
    inv = tuple(e.subs(dict(zip((x1, x2, x3), z, strict=True)), simultaneous=True) for e in tri_inv)
    moved = _push_forward(sys, lin, inv)
    f = analyze(moved, (0, 0, 0))
    assert f.growth_vector == ref.growth_vector
    assert f.regular == ref.regular
    assert f.weights == ref.weights


@pytest.mark.parametrize(
    "third", [x2 * sp.atan2(x2, 2), sp.sqrt(1 + x2**2), sp.cosh(x2)]
)
def test_martinet_like_fields_with_other_functions(third):
    # third = 1 or 0 + x2**2/2 + O(x2**4) (Taylor by hand), so at 0 the filtration is
    # Martinet's: [X1,X2] = -d/dx2 X1 vanishes at 0, [X2,[X1,X2]](0) = (0, 0, -1).
    sys = ControlSystem("martinet-like", (x1, x2, x3), ((1, 0, third), (0, 1, 0)))
    f = analyze(sys)
    assert f.growth_vector == (2, 2, 3) and not f.regular
    assert f.generic_growth_vector == (2, 3)
    assert f.frame_values[2] == (0, 0, -1)


def test_singular_locus_refuses_an_unmanageable_determinant():
    from nilpotent.errors import ComputationLimitError
    from nilpotent.models import get_model

    with pytest.raises(ComputationLimitError, match="characters"):
        singular_locus(get_model("trident-snake-joints"))
