"""Published systems and the inputs that broke earlier versions (``cases/README.md``, field/).

Each right value was derived independently of the project (exact sympy with
rationals, published results); the model files are copies in ``tests/data/cases``.
Every case runs through the CLI as a user would, or through the Python API.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import sympy as sp

from nilpotent.core.analysis.filtration import analyze
from nilpotent.core.analysis.singular import singular_set
from nilpotent.core.coordinates.approximation import approximate
from nilpotent.core.model.points import parse_point
from nilpotent.models import load_system

CASES = Path(__file__).parent / "data" / "cases"


def _case(name: str, **params: object):
    return load_system(str(CASES / f"{name}.toml"), params or None)


def _analysis(run_cli, *args: str) -> dict:
    status, out, err = run_cli("analyze", *args, "--json")
    assert status == 0, err
    return json.loads(out)


def test_generic_rank_tiny_determinant(run_cli):
    # det(X1, X2, [X1,X2]) at x2 = 1/10 is -141*10**-14, by hand: not zero
    x1, x2 = sp.symbols("x1 x2")
    cols = sp.Matrix([[1, 0, x2**14], [x1, 1, 0], [1, 0, -14 * x2**13]]).T
    assert cols.det().subs(x2, sp.Rational(1, 10)) == sp.Rational(-141, 10**14)
    j = _analysis(run_cli, str(CASES / "fail-generic-rank.toml"), "--at", "x2=1/10")
    assert j["bracket_generating"] is True and j["regular"] is True
    assert j["growth_vector"] == [2, 3] and j["undetermined"] is None


def test_float_parameters_decide_like_fractions(run_cli):
    want = [2, 3, 4, 4, 5, 5, 6]
    j = _analysis(run_cli, str(CASES / "fail-float-params.toml"), "--at", "theta0=pi/2")
    assert j["growth_vector"] == want and j["bracket_generating"] is True
    exact = analyze(
        _case("fail-float-params", d1=sp.Rational(7, 10), d2=sp.Rational(13, 10),
              d3=sp.Rational(9, 10)),
        (0, 0, sp.pi / 2, 0, 0, 0),
    )
    assert list(exact.growth_vector) == want
    status, out, err = run_cli(
        "approximate", str(CASES / "fail-float-params.toml"), "--at", "theta0=pi/2", "--json"
    )
    assert status == 0, err
    assert json.loads(out)["certificate"]["ok"] is True


def test_martinet_k12_step_13(run_cli):
    j = _analysis(run_cli, str(CASES / "fail-martinet-k12.toml"))
    assert j["bracket_generating"] is True and j["step"] == 13
    assert j["growth_vector"] == [2] * 12 + [3]
    assert j["regular"] is False
    # ad_{X2}^12 X1 = 12! d3 (sign by the convention [X,Y] = DY.X - DX.Y)
    assert [sp.Abs(sp.S(v)) for v in j["frame_values"][2]] == [0, 0, sp.factorial(12)]
    a = approximate(_case("fail-martinet-k12"))
    assert a.certificate.ok and a.filtration.step == 13


def test_an_exhausted_search_is_undetermined_never_negative(run_cli):
    j = _analysis(run_cli, str(CASES / "fail-martinet-k12.toml"), "--max-length", "5")
    # the search up to length 5 stops short of R^3; bracket generation is then proved
    # through the orbit (never "not bracket-generating"), the growth vector stays a prefix
    assert j["bracket_generating"] is True and j["certified_by"]["method"] == "orbit"
    assert j["undetermined"]["max_length"] == 5 and j["growth_vector_known_up_to"] == 5
    assert j["growth_vector"] == [2] * 5 and j["regular"] is False
    status, out, _ = run_cli("analyze", str(CASES / "fail-martinet-k12.toml"),
                             "--max-length", "5")
    assert status == 0 and "known up to bracket length 5" in out and "NO" not in out
    status, out, _ = run_cli("approximate", str(CASES / "fail-martinet-k12.toml"),
                             "--max-length", "5", "--json")
    assert status == 2 and json.loads(out)["error"]["kind"] == "computation-limit"


def test_grushin_singular_locus_is_x_equal_0(run_cli):
    j = _analysis(run_cli, str(CASES / "fail-singular-locus.toml"), "--singular-locus")
    x = sp.Symbol("x")
    assert [sp.S(e).subs(sp.Symbol("x"), x) for e in j["singular_locus_equations"]] == [x]
    g = _analysis(run_cli, str(CASES / "grushin.toml"))
    assert g["growth_vector"] == [1, 2] and g["regular"] is False


def test_hopping_robot_singular_exactly_on_l_equal_minus_d(run_cli):
    for d in (1, 2):
        sys = _case("hopping-robot", d=d)
        locus = singular_set(sys)
        (eq,) = locus.equations
        l_ = next(s for s in eq.free_symbols if s.name == "l")
        assert sp.solve(eq, l_) == [-d]
        f = analyze(sys, parse_point(f"l={-d}", sys))
        assert f.growth_vector == (2, 2, 3) and f.weights == (1, 1, 3) and not f.regular
        assert analyze(sys, parse_point(f"l={-d + 1}", sys)).regular


def test_exponential_methods_as_fast_as_algebraic():
    sys = _case("fail-exp-slow")
    p = parse_point("theta0=pi/2", sys)
    for method in ("exponential", "exponential-1"):
        a = approximate(sys, p, method)
        assert a.filtration.step == 7 and a.certificate.ok


@pytest.mark.slow
def test_car_with_trailers_at_a_singular_configuration_is_never_called_not_generating(run_cli):
    # Jean 1996: the car with n trailers is controllable everywhere; the search at a
    # singular point may stop (budget), but never with a negative verdict.
    j = _analysis(run_cli, "car-trailers:5", "--at", "theta0=pi,theta1=pi/2")
    assert j["bracket_generating"] in (True, None)
    assert j["generic_growth_vector"][-1] == 8


def test_rolling_ball_off_theta_0():
    sys = _case("rolling-ball")
    f = analyze(sys, parse_point("theta=1/2,phi=1/3", sys))
    assert f.growth_vector == (2, 3, 5) and f.weights == (1, 1, 2, 3, 3) and f.step == 3


def test_fire_truck_generic_and_on_the_singular_hypersurface():
    sys = _case("fire-truck")
    assert analyze(sys, parse_point("theta0=1/3", sys)).growth_vector == (3, 5, 6)
    f = analyze(sys, parse_point("theta0=pi/2", sys))
    assert f.growth_vector == (3, 4, 6) and not f.regular


def test_offhooked_trailer():
    sys = _case("offhooked-trailer", a=1, d=1)
    assert analyze(sys, parse_point("theta0=1", sys)).growth_vector == (2, 3, 4)
    on = analyze(sys, parse_point("theta0=pi", sys))
    # the hypersurface theta0 - theta1 = pi is invariant: proved, so "not bracket-generating"
    assert on.bracket_generating is False and on.regular is False
    assert on.invariant_hypersurface is not None
    # a transcendental point off it (sin(pi) is enclosed in a ball around 0 there)
    off = analyze(sys, parse_point("theta0=pi,theta1=1/3", sys))
    assert off.bracket_generating is True and off.growth_vector == (2, 3, 4)
    (eq1, eq2) = singular_set(sys).equations
    th0, th1 = sp.symbols("theta0 theta1")
    for eq in (eq1, eq2):
        e = eq.subs({s: {"theta0": th0, "theta1": th1}[s.name] for s in eq.free_symbols})
        assert sp.simplify(e.subs(th0, th1 + sp.pi)) == 0
        assert sp.simplify(e.subs(th0, th1 + 1)) != 0


@pytest.mark.parametrize(
    ("name", "point", "growth"),
    [
        ("brockett-3", None, (3, 6)),
        ("heisenberg-5", None, (4, 5)),
        ("rolling-disk", None, (2, 3, 4)),
        ("chained-5", "x1=1,x2=2,x3=-1,x4=3,x5=5", (2, 3, 4, 5)),
        ("grushin", None, (1, 2)),
        ("omni-3-swedish", None, (3, 5)),
        ("tiny-scale-1e-18", None, (2, 3)),
    ],
)
def test_published_growth_vectors(name, point, growth):
    sys = _case(name)
    f = analyze(sys, parse_point(point, sys) if point else None)
    assert f.growth_vector == growth
    assert f.bracket_generating is (growth[-1] == sys.n)


def test_chained_form_refuses_linear_coordinates():
    from nilpotent.errors import NotPrivilegedError

    sys = _case("chained-5")
    p = parse_point("x1=1,x2=2,x3=-1,x4=3,x5=5", sys)
    with pytest.raises(NotPrivilegedError):
        approximate(sys, p, "linear")


def test_trident_body_form_at_algebraic_and_transcendental_points(run_cli):
    for at in ("phi1=pi/7,phi2=pi/5", "phi1=1,phi3=1"):
        j = _analysis(run_cli, "trident-snake", "--at", at)
        assert j["growth_vector"] == [3, 6] and j["regular"] is True
    status, out, err = run_cli("approximate", "trident-snake", "--at", "phi1=1,phi3=1", "--json")
    assert status == 0, err
    assert json.loads(out)["certificate"]["ok"] is True


def test_trident_body_form_is_regular_everywhere_with_a_constant_determinant():
    locus = singular_set(load_system("trident-snake"))
    assert locus.empty
    dets = [d for _, d in locus.determinants if d.is_number]
    # |det| = 3*sqrt(3)/2 * r**2 / l**6 with r = l = 1 (the sign depends on the frame order)
    assert sp.simplify(sp.Abs(dets[0]) - 3 * sp.sqrt(3) / 2) == 0


@pytest.mark.parametrize("value", ["1e-300", "1e300", "1e-5"])
def test_trident_tiny_and_huge_leg_length(run_cli, value):
    j = _analysis(run_cli, "trident-snake", "--param", f"l={value}")
    assert j["growth_vector"] == [3, 6] and j["bracket_generating"] is True


def test_hostile_expansions_and_searches_end_within_a_budget(run_cli):
    from nilpotent.core.model.system import ControlSystem
    from nilpotent.errors import ComputationLimitError

    status, out, _ = run_cli("analyze", str(CASES / "multinomial4.toml"), "--json")
    assert status == 2 and json.loads(out)["error"]["kind"] == "computation-limit"
    # the same field built in Python (no model-file grammar): the bracket engine refuses it
    # before expanding 4.6 million terms
    x, y, z, w = sp.symbols("x y z w")
    big = ControlSystem(
        "multinomial4", (x, y, z, w),
        ((1, (x + y + z + w + 1) ** 100, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)),
    )
    with pytest.raises(ComputationLimitError, match="EXPANSION_TERMS_BUDGET"):
        analyze(big)
    status, out, _ = run_cli("analyze", str(CASES / "stall40.toml"), "--max-length", "60",
                             "--json")
    assert status == 2 and "--max-length" in json.loads(out)["error"]["message"]
    j = _analysis(run_cli, str(CASES / "stall40.toml"))
    # x**40: the search stops within its budget; the orbit (the flow of X1 = d/dx, exact)
    # proves bracket generation, the growth vector stays the searched prefix
    assert j["bracket_generating"] is True and j["undetermined"]["max_length"] >= 12
    assert j["certified_by"]["exact_flow"] is True
    assert j["growth_vector"] == [2] * j["growth_vector_known_up_to"]


def test_singular_locus_json_keys(run_cli):
    j = _analysis(run_cli, str(CASES / "hopping-robot.toml"), "--singular-locus")
    assert j["singular_locus"] == "l + 1"
    assert j["singular_locus_equations"] == ["l + 1"]
    assert "l + 1 = 0" in j["singular_locus_statement"]
    assert j["singular_locus_determinants"][0]["frame"] == ["X1", "X2", "[X1,X2]"]


def test_singular_locus_of_a_huge_determinant_is_refused_not_simplified_for_minutes():
    """car-trailers:4's frame determinant expands to millions of characters: the
    trigonometric normal form is refused with the budget named, and the search for an
    invariant hypersurface at a point concludes nothing instead of hanging."""
    from nilpotent.core.analysis.singular import (
        SINGULAR_DETERMINANT_MAX_CHARS,
        invariant_hypersurface,
    )
    from nilpotent.errors import ComputationLimitError
    from nilpotent.models import get_model

    system = get_model("car-trailers:4")
    with pytest.raises(ComputationLimitError, match="SINGULAR_DETERMINANT_MAX_CHARS"):
        singular_set(system, (2, 3, 4, 5, 6, 7))
    assert SINGULAR_DETERMINANT_MAX_CHARS < 5_000_000
    point = [sp.Integer(0)] * system.n
    assert invariant_hypersurface(system, point, (2, 3, 4, 5, 6, 7)) is None
