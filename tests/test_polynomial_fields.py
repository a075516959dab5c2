"""Fields as polynomials in coordinates and atoms: brackets, exact values, balls, free test.

Every value is compared with an independent computation: the bracket by plain
sympy (``DY·X − DX·Y`` with ``sympy.diff``) evaluated at 60 digits, or a hand
derivation; growth vectors with the literature.
"""

from __future__ import annotations

import pytest
import sympy as sp
from flint import arb, fmpq
from hypothesis import Phase, given, settings
from hypothesis import strategies as st

from nilpotent.core.analysis.filtration import analyze
from nilpotent.core.decide.spans import Decision, Span
from nilpotent.core.lie.brackets import bracket, format_word
from nilpotent.core.lie.polynomial_fields import polynomial_fields
from nilpotent.core.lie.word_values import WordValues
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import NilpotentError
from nilpotent.models import get_model

x, y, z = sp.symbols("x y z")
# every kind of atom: sin/cos pair, tan, exp, log, sqrt (rational power), 1/b, atan,
# atan2, asin, sinh/cosh, tanh, and a constant (pi)
ELEMENTARY = ControlSystem(
    "elementary",
    (x, y, z),
    (
        (1, sp.sin(y) * sp.exp(x / 2), sp.log(2 + x**2) + sp.atan(y) / (3 + z**2)),
        (
            sp.sqrt(5 + y**2) + sp.pi * z,
            sp.tan(x / 3) - sp.atan2(y, 4 + x),
            sp.asin(y / 4) + sp.tanh(z) * sp.cosh(x) + sp.sinh(y),
        ),
    ),
)

WORDS = [1, 2, (1, 2), (1, (1, 2)), (2, (1, 2)), (1, (1, (1, 2))), (2, (2, (1, 2)))]


def _sympy_field(sys: ControlSystem, word):
    if isinstance(word, int):
        return tuple(sys.specialized_fields[word - 1])
    return bracket(_sympy_field(sys, word[0]), _sympy_field(sys, word[1]), sys.coordinates)


def _reference(sys, word, point, digits=60):
    env = dict(zip(sys.coordinates, point, strict=True))
    return [sp.N(e.subs(env), digits) for e in _sympy_field(sys, word)]


@pytest.mark.parametrize("word", WORDS, ids=format_word)
@pytest.mark.parametrize("prec", [64, 200])
def test_balls_enclose_the_sympy_bracket_at_an_irrational_point(word, prec):
    point = (sp.Rational(1, 3), sp.Rational(-2, 7), sp.Rational(5, 11))
    assert polynomial_fields(ELEMENTARY) is not None
    at = WordValues(ELEMENTARY, point, symbolic=False)
    assert at.exact(word) is None  # sin(-2/7) is irrational
    balls = at.balls(word, prec)
    for b, ref in zip(balls, _reference(ELEMENTARY, word, point), strict=True):
        assert b.is_finite()
        assert b.contains(arb(str(ref))) or abs(float(b.mid()) - float(ref)) < 1e-40
        # the enclosure is tight: relative radius well below 2^-(prec/2)
        assert float(b.rad()) <= 2.0 ** (-prec // 2) * max(1.0, abs(float(ref)))


@pytest.mark.parametrize("k", [1, 2, 3])
def test_exact_values_at_rational_atoms_match_sympy(k):
    """At theta_i = i*pi/2 every atom is rational (cos(pi/2) = 0): exact values, no balls."""
    sys = get_model(f"car-trailers:{k}").specialized()
    point = (0, 0, *(sp.pi / 2 * i for i in range(k + 1)))
    at = WordValues(sys, point, symbolic=False)
    for word in WORDS:
        exact = at.exact(word)
        assert exact is not None
        env = dict(zip(sys.coordinates, point, strict=True))
        ref = [sp.nsimplify(sp.simplify(e.subs(env))) for e in _sympy_field(sys, word)]
        assert [sp.Rational(int(q.p), int(q.q)) for q in exact] == ref


def test_free_point_finds_polynomial_identities_only():
    """[X2,[X2,X1]] = -X1 for the car (a polynomial identity): dependent at the free point.

    With X2 = d/dtheta0 and X1 built from sin/cos of theta0 - theta1: by hand,
    d^2/dtheta0^2 maps cos -> -cos and sin -> -sin in every component of X1.
    """
    sys = get_model("car-trailers:2").specialized()
    at = WordValues(sys, (sp.Rational(1, 5),) * sys.n, symbolic=False)
    x1, x2x2x1 = at.free(1), at.free((2, (2, 1)))
    assert x1 is not None and x2x2x1 is not None
    assert [-q for q in x1] == x2x2x1
    span = Span(probabilistic=True)
    assert span.add(at.vector(1)) is Decision.INDEPENDENT
    assert span.add(at.vector((2, (2, 1)))) is Decision.DEPENDENT


def test_dependence_through_sin2_plus_cos2_is_left_to_the_balls():
    """X2 = (0, 1, sin^2 + cos^2) equals X3 = (0, 1, 1) everywhere, not as polynomials in atoms.

    The free test must not decide it (it sees two independent vectors); the balls
    at the random point then find the dependence: the span of X1, X2, X3 is 2.
    """
    sys = ControlSystem(
        "pythagoras", (x, y, z),
        ((1, 0, 0), (0, 1, sp.sin(x) ** 2 + sp.cos(x) ** 2), (0, 1, 1)),
    )
    f = analyze(sys)
    assert f.generic_growth_vector == (2,)
    assert f.bracket_generating is False


def test_unsupported_functions_keep_the_expression_path():
    """A symbolic exponent has no atom rule: no polynomial form, the analysis still works."""
    sys = ControlSystem("exponent", (x, y, z), ((1, 0, 2 ** (x + y)), (0, 1, 0)))
    assert polynomial_fields(sys) is None
    f = analyze(sys)
    assert f.growth_vector == (2, 3)  # [X1,X2] = (0, 0, -log(2) 2^(x+y)), nonzero
    assert sp.simplify(f.frame_values[2][2] + sp.log(2)) == 0


def test_pole_of_an_atom_is_a_point_error():
    from nilpotent.errors import PointError

    sys = ControlSystem("pole", (x, y, z), ((1, 0, 1 / y), (0, 1, 0)))
    with pytest.raises(PointError):
        analyze(sys, (0, 0, 0))


def test_car_with_four_trailers_all_perpendicular_has_fibonacci_step():
    """F. Jean (1996): with every trailer perpendicular to the one before, the degree of
    nonholonomy of the car with K trailers is the Fibonacci number F_{K+3}: 3, 5, 8, 13.

    (The expression path stopped at its size budget here and could only prove bracket
    generation through the orbit.)
    """
    k = 4
    sys = get_model(f"car-trailers:{k}")
    f = analyze(sys, (0, 0, *(sp.pi / 2 * i for i in range(k + 1))))
    assert f.step == 13 and f.growth_vector[-1] == k + 3
    assert f.bracket_generating and f.regular is False
    assert f.growth_vector_known_up_to is None and f.undetermined is None


@pytest.mark.slow
def test_car_with_nine_trailers_at_the_origin():
    """Sørdalen (1993), Laumond: the car with K trailers converts to the chained form at
    configurations where no two consecutive bodies are perpendicular, so its growth vector
    there is (2, 3, ..., K + 3): one new direction per bracket length, step K + 2.
    For K = 9: n = 12, step 11; the adapted frame is ad_{X1}^j X2, j = 0..10, with X1.
    """
    k = 9
    f = analyze(get_model(f"car-trailers:{k}"))
    assert f.growth_vector == tuple(range(2, k + 4))
    assert f.step == k + 2 and f.weights == (1, 1, *range(2, k + 3))
    assert f.regular and f.bracket_generating and f.exact
    assert f.generic_growth_vector == f.growth_vector
    # the frame values form a basis (exact rationals at the origin)
    assert sp.Matrix(f.frame_values).det() != 0


def test_exact_values_are_fmpq():
    at = WordValues(get_model("car-trailers:1").specialized(), (0, 0, 0, 0), symbolic=False)
    vals = at.exact((1, 2))
    assert vals is not None and all(isinstance(q, fmpq) for q in vals)
    # [X1,X2](0) = -dX1/dtheta0 at 0 = (sin 0, -cos 0, 0, -cos(0)/d1) by hand
    assert vals == [0, -1, 0, -1]


@pytest.mark.parametrize(
    ("model", "point"),
    [
        ("trident-snake", "x=1/3,theta=1/5,phi1=1,phi2=-1/2"),
        ("trident-snake-joints", "x=1/2,y=1/3"),
        ("car-trailers:3", "theta1=pi/2,theta2=pi,theta3=3*pi/2"),
        ("car-trailers:3", "theta0=1/3,theta1=-1/4,theta2=1/7,theta3=1"),
        ("car-trailers:2", "theta1=pi/3"),
        ("martinet", "x2=0"),
        ("engel", "x1=1/3,x2=-2"),
    ],
)
def test_the_expression_path_gives_the_same_analysis(model, point, monkeypatch):
    """A second method: the same analysis with the polynomial form switched off."""
    import nilpotent.core.lie.word_values as word_values
    from nilpotent.core.model.points import parse_point

    fast = analyze(get_model(model), parse_point(point, get_model(model)))
    monkeypatch.setattr(word_values, "polynomial_fields", lambda sys: None)
    slow = analyze(get_model(model), parse_point(point, get_model(model)))
    assert fast.to_json() == slow.to_json()


_PIECES = [
    sp.Integer(1), x, y * z, sp.sin(x), sp.cos(y - z), sp.exp(z / 2), 1 / (2 + x**2),
    sp.sqrt(3 + y**2), sp.atan(x), sp.tanh(y), x**2 * sp.sin(z),
]


@settings(max_examples=40, deadline=None, phases=[Phase.reuse, Phase.generate])
@given(
    st.lists(st.lists(st.tuples(st.integers(-3, 3), st.sampled_from(_PIECES)), min_size=1,
                      max_size=2), min_size=6, max_size=6),
    st.tuples(*[st.integers(-4, 4)] * 3),
)
def test_random_elementary_systems_agree_with_the_expression_path(terms, point):
    """Random fields from elementary pieces: both paths give the same analysis.

    ``max_length=4`` bounds the search at singular points (no time budget involved).
    """
    import nilpotent.core.lie.word_values as word_values

    comps = [sum((c * e for c, e in comp), sp.Integer(0)) for comp in terms]
    sys = ControlSystem("random", (x, y, z), (tuple(comps[:3]), tuple(comps[3:])))
    p = tuple(sp.Rational(v, 3) for v in point)
    try:
        fast = analyze(sys, p, max_length=4).to_json()
    except NilpotentError as exc:
        fast = type(exc).__name__
    original = word_values.polynomial_fields
    word_values.polynomial_fields = lambda sys: None
    try:
        slow = analyze(ControlSystem("random", (x, y, z), sys.fields), p, max_length=4).to_json()
    except NilpotentError as exc:
        slow = type(exc).__name__
    finally:
        word_values.polynomial_fields = original
    if isinstance(fast, dict) and isinstance(slow, dict):
        assert fast["generic_growth_vector"] == slow["generic_growth_vector"]
        slow_unsure = (slow["undetermined"] or {}).get("undetermined_words", {})
        fast_unsure = (fast["undetermined"] or {}).get("undetermined_words", {})
        if slow_unsure:
            # exact values where the expression path had only balls (sin(0) = 0): the
            # polynomial path decides more, never differently
            for k, words in fast_unsure.items():
                assert set(words) <= set(slow_unsure.get(k, []))
            if slow["bracket_generating"] is not None:
                assert fast["bracket_generating"] == slow["bracket_generating"]
            return
        # the highest ball precision tried is a diagnostic: exact rationals need none
        for j in (fast, slow):
            if j["undetermined"] is not None:
                j["undetermined"].pop("precision_bits")
    assert fast == slow
