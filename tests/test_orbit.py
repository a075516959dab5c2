"""Bracket generation certified along the orbit (``nilpotent.core.analysis.orbit``).

Independent checks: the end box of a certificate must contain the end point of
the flow computed by scipy's ``solve_ivp`` (a separate integrator); the car with
``K`` trailers is bracket-generating everywhere (Jean 1996), so every singular
configuration must be certified; the offhooked trailer with ``a = d = 1`` has the
invariant hypersurface ``theta0 - theta1 = pi`` (every field is tangent to it: by
hand, ``X1(theta0 - theta1) = -sin(theta0 - theta1)`` and
``X2(theta0 - theta1) = 1 + cos(theta0 - theta1)`` vanish there), so no point of it
may ever be certified.
"""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from nilpotent.core.analysis.filtration import analyze
from nilpotent.core.analysis.orbit import certify_by_orbit
from nilpotent.core.model.points import parse_point
from nilpotent.core.model.system import ControlSystem
from nilpotent.models import get_model, load_system

CASES = Path(__file__).parent / "data" / "cases"


def _flow_end(sys: ControlSystem, point, flows) -> np.ndarray:
    """The end point of the flows by scipy (rtol 1e-12), independent of the certificate."""
    x = np.array([float(v) for v in point])
    for i, t in flows:
        f = sp.lambdify(sys.coordinates, list(sys.specialized_fields[i - 1]), "numpy")
        sol = solve_ivp(lambda _s, y, f=f: np.array(f(*y), dtype=float), (0.0, float(t)), x,
                        rtol=1e-12, atol=1e-14)
        x = sol.y[:, -1]
    return x


def _assert_in_box(cert, end: np.ndarray) -> None:
    for (lo, hi), v in zip(cert.box, end, strict=True):
        assert float(lo) - 1e-9 <= v <= float(hi) + 1e-9


def test_car_with_5_trailers_at_the_case_point_is_bracket_generating(run_cli):
    # the full search at the point now ends (brackets as polynomials in atoms): the
    # brackets span R^8 there, with a step within Jean's bound F_{K+3} = F_8 = 21
    status, out, err = run_cli(
        "analyze", "car-trailers:5", "--at", "theta0=pi,theta1=pi/2", "--json")
    assert status == 0, err
    j = json.loads(out)
    assert j["bracket_generating"] is True and j["growth_vector"][-1] == 8
    assert j["certified_by"] is None and j["step"] <= 21 and j["regular"] is False
    # a search stopped short (--max-length 9) is completed through the orbit
    status, out, err = run_cli(
        "analyze", "car-trailers:5", "--at", "theta0=pi,theta1=pi/2", "--max-length", "9",
        "--json")
    assert status == 0, err
    j = json.loads(out)
    assert j["bracket_generating"] is True
    cert = j["certified_by"]
    assert cert["method"] == "orbit" and len(cert["frame"]) == 8
    # the growth vector stays the proved prefix: it does not reach n = 8
    known = j["growth_vector_known_up_to"]
    assert known is not None and len(j["growth_vector"]) == known
    assert j["growth_vector"][-1] < 8 and j["step"] == known
    assert j["weights"] == sorted(j["weights"]) and len(j["weights"]) == j["growth_vector"][-1]
    assert "known up to bracket length" in j["undetermined"]["reason"]
    status, out, _ = run_cli("analyze", "car-trailers:5", "--at", "theta0=pi,theta1=pi/2",
                             "--max-length", "9")
    assert status == 0 and "orbit theorem" in out and "known up to bracket length" in out


def _trailer_point(k: int, diffs: list[sp.Expr]) -> list[sp.Expr]:
    """x = y = 0, theta0 = 1/3, theta_{i+1} = theta_i - diffs[i] (cyclically)."""
    thetas = [sp.Rational(1, 3)]
    for i in range(k):
        thetas.append(thetas[-1] - diffs[i % len(diffs)])
    return [sp.Integer(0), sp.Integer(0), *thetas]


@pytest.mark.parametrize(
    ("k", "diffs"),
    [
        (2, [sp.Rational(1, 5), sp.pi / 2]),
        (3, [sp.pi / 2, -sp.pi / 2]),
        (4, [sp.Rational(-2, 7), sp.pi / 2, sp.pi / 2]),
        (5, [-sp.pi / 2]),
        (6, [sp.pi / 2, sp.Integer(0)]),
    ],
)
def test_singular_configurations_of_the_car_with_trailers_are_certified(k, diffs):
    sys = get_model(f"car-trailers:{k}")
    p = _trailer_point(k, diffs)
    cert = certify_by_orbit(sys, p)
    assert cert is not None and len(cert.frame) == sys.n
    _assert_in_box(cert, _flow_end(sys, p, cert.flows))


@pytest.mark.parametrize(
    "point", ["theta0=pi", "theta0=pi+1/3,theta1=1/3", "x=2,y=-1,theta0=-1/2,theta1=-1/2-pi"])
def test_offhooked_trailer_on_its_invariant_hypersurface_is_never_certified(point):
    sys = load_system(str(CASES / "offhooked-trailer.toml"), {"a": 1, "d": 1})
    p = parse_point(point, sys)
    assert certify_by_orbit(sys, p, time_budget=5.0) is None
    f = analyze(sys, p)
    assert f.bracket_generating is not True and f.certified_by is None
    if point == "theta0=pi":  # there the hypersurface itself is found (exact values)
        assert f.bracket_generating is False


def test_an_exact_translation_leaves_the_grushin_singular_line():
    x, y = sp.symbols("x y")
    grushin = ControlSystem("grushin", (x, y), ((1, 0), (0, x)))
    cert = certify_by_orbit(grushin, [sp.Integer(0), sp.Integer(0)])
    assert cert is not None and cert.exact  # X1 = d/dx: the flow is x + t
    (i, t), = cert.flows
    assert i == 1 and t != 0
    lo, hi = (Fraction(v) for v in cert.box[0])
    assert lo <= t <= hi and hi - lo < Fraction(1, 10**12)


def test_points_the_search_decides_do_not_use_the_orbit():
    x1, x2, x3 = sp.symbols("x1 x2 x3")
    martinet = ControlSystem("martinet", (x1, x2, x3), ((1, 0, x2**2 / 2), (0, 1, 0)))
    f = analyze(martinet)
    assert f.growth_vector == (2, 2, 3) and f.regular is False
    assert f.certified_by is None and f.growth_vector_known_up_to is None
    assert f.to_json()["certified_by"] is None
