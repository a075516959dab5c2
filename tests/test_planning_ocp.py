"""``--refine ocp``: a plan refined by direct optimal control of the true system (CasADi).

Checked independently of the product: the refined segments (their JSON) are
re-simulated by ``tests/replay.py`` (scipy's DOP853 on the sympy fields); the
Heisenberg lengths are compared with Dido's closed-form distance (an arc of angle
φ with ``|x₃|/r² = (φ − sin φ)/(8 sin²(φ/2))``, ``d = rφ/(2 sin(φ/2))``), which every
admissible motion exceeds; the sympy → CasADi translation is compared with sympy's own
numerical evaluation.
"""

from __future__ import annotations

import importlib.util
import itertools
import json
import math
import sys

import numpy as np
import pytest
import sympy as sp

import nilpotent.cli.cmd_plan  # noqa: F401  (registers the command)
from closed_forms import heisenberg_distance
from nilpotent.core.model.outline import Limits
from nilpotent.errors import MissingExtraError, OptionError
from nilpotent.models import get_model
from nilpotent.planning import plan
from nilpotent.planning.controls import constant_segment
from nilpotent.planning.geodesic import control_length
from nilpotent.planning.global_planner import plan_global
from nilpotent.planning.ocp import INTERVALS, check_refine, refine_segments, to_casadi
from nilpotent.planning.verify import Checker
from replay import resimulate

# the `ocp` extra (part of the `test` extra); the missing-extra tests need no CasADi
needs_casadi = pytest.mark.skipif(importlib.util.find_spec("casadi") is None,
                                  reason='needs pip install "nilpotent[ocp]"')


#: Piecewise-constant controls on N intervals approximate the geodesic (a circular arc of
#: total angle φ ≤ 2π, turned at constant rate) to second order in the angle per interval
#: α = φ/N: the inscribed polygon's length is L·sin(α/2)/(α/2) = L(1 − α²/24 + …).  The
#: bound allows 4× that leading term at the worst angle 2π (the area the polygon misses is
#: made up by a change of the same order).
DISCRETISATION = 4 * (2 * math.pi / INTERVALS) ** 2 / 24


def segment_dicts(segments) -> list[dict]:
    return [s.to_dict() for s in segments]


@needs_casadi
def test_translation_agrees_with_sympy() -> None:
    import casadi as ca

    x, y = sp.symbols("x y")
    exprs = [
        sp.sin(x) * sp.cos(y) - sp.tan(x) / 3, sp.exp(x) * sp.log(2 + y**2),
        sp.sqrt(1 + x**2) ** 3, sp.atan(x) + sp.atan2(y, x - 2), sp.sinh(x) - sp.cosh(y),
        sp.tanh(x * y) + sp.pi * sp.E, x ** sp.Rational(3, 2) + abs(y) * sp.sign(y),
        1 / sp.cos(y) + sp.Max(x, y) - sp.Min(x, 2 * y), (x + 1) ** (y / 5),
    ]
    xs, ys = ca.SX.sym("x"), ca.SX.sym("y")
    rng = np.random.default_rng(3)
    for expr in exprs:
        fn = ca.Function("f", [xs, ys], [to_casadi(expr, {x: xs, y: ys})])
        for _ in range(5):
            a, b = rng.uniform(0.1, 1.2, size=2)
            want = float(expr.subs({x: a, y: b}).evalf(30))
            assert float(fn(a, b)) == pytest.approx(want, rel=1e-12, abs=1e-12), expr


@needs_casadi
def test_translation_refuses_what_it_cannot_express() -> None:
    import casadi as ca

    x, p = sp.symbols("x p")
    with pytest.raises(OptionError, match="no coordinate"):
        to_casadi(x * p, {x: ca.SX.sym("x")})
    with pytest.raises(OptionError, match="cannot translate"):
        to_casadi(sp.gamma(x), {x: ca.SX.sym("x")})
    # text is never parsed here (it reaches the fields only through the expression grammar)
    with pytest.raises(TypeError, match="not str"):
        to_casadi("x", {x: ca.SX.sym("x")})  # type: ignore[arg-type]


@needs_casadi
def test_heisenberg_refined_length_is_the_closed_form_distance() -> None:
    h = get_model("heisenberg")
    goal = (0.5, 0.3, 0.4)
    warm = plan(h, (0, 0, 0), goal)  # loops: far from the shortest
    segs, info = refine_segments(Checker(h), (0, 0, 0), goal, warm.segments, 1e-8)
    assert info.applied, info.reason
    states = resimulate(h, (0, 0, 0), segment_dicts(segs))
    assert np.linalg.norm(states[-1] - np.array(goal)) <= 1e-8
    d = heisenberg_distance(*goal)
    length = control_length(segs)
    assert length <= control_length(warm.segments)
    assert d * (1 - 1e-9) <= length <= d * (1 + DISCRETISATION)


@needs_casadi
def test_a_shortest_plan_is_not_replaced() -> None:
    """The geodesic plan of Heisenberg is already the shortest (its approximation is the
    system): the piecewise-constant refinement is longer, so the plan stays as it is."""
    h = get_model("heisenberg")
    goal = (0.2, -0.4, 0.3)
    best = plan(h, (0, 0, 0), goal, objective="length")
    segs, info = refine_segments(Checker(h), (0, 0, 0), goal, best.segments, 1e-8)
    assert not info.applied and "not shorter" in info.reason
    assert segs == list(best.segments)


X1 = sp.Symbol("x1")


@needs_casadi
@pytest.mark.parametrize("limits", [
    Limits((("x1", -0.25, 0.25),)),
    Limits(relative=(("x1^2", X1**2, 0.0, 0.0625),)),  # the same strip, as a relative limit
], ids=["box", "relative"])
def test_limits_are_kept(limits) -> None:
    """A vertical Heisenberg goal whose shortest motion (a circle of diameter d/π ≈ 0.8)
    leaves the strip |x1| ≤ 0.25.  Warm start: a rectangle in the strip enclosing the area
    x3 = 0.5 (x3 = ½∮ x1 dx2 − x2 dx1), length 3.3; the refined motion keeps to the strip,
    so it is longer than d, and shorter than the rectangle."""
    h = get_model("heisenberg")
    goal = (0.0, 0.0, 0.5)
    lo, hi = -0.25, 0.25
    checker = Checker(h, limits=limits)
    rectangle = [constant_segment(u) for u in
                 ((0.2, 0.0), (0.0, 1.25), (-0.4, 0.0), (0.0, -1.25), (0.2, 0.0))]
    assert np.linalg.norm(resimulate(h, (0, 0, 0), segment_dicts(rectangle))[-1] - goal) < 1e-12
    segs, info = refine_segments(checker, (0, 0, 0), goal, rectangle, 1e-8)
    assert info.applied, info.reason
    states = resimulate(h, (0, 0, 0), segment_dicts(segs))
    assert np.linalg.norm(states[-1] - np.array(goal)) <= 1e-8
    assert lo <= states[:, 0].min() and states[:, 0].max() <= hi
    assert np.all(checker.valid(states))
    assert heisenberg_distance(*goal) * (1 + DISCRETISATION) < control_length(segs) < 3.3


@needs_casadi
@pytest.mark.slow
def test_global_plan_refined_reaches_the_goal_and_is_shorter() -> None:
    system, goal = get_model("unicycle"), (0.3, 0.2, 0.5)
    start = (0.0,) * system.n
    g = plan_global(system, start, goal, refine="ocp")
    ref = g.refinement
    assert ref is not None and ref.applied, ref
    data = json.loads(json.dumps(g.to_json(), allow_nan=False))
    states = resimulate(system, start, data["segments"])
    assert np.linalg.norm(states[-1] - np.array(goal)) <= 1e-8
    assert data["length"] <= ref.length_before
    assert data["refinement"]["applied"] is True
    checker = Checker(system)
    assert np.all(checker.valid(states))


def test_missing_casadi_names_the_extra(monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "casadi", None)
    with pytest.raises(MissingExtraError, match=r'pip install "nilpotent\[ocp\]"'):
        plan_global(get_model("unicycle"), (0, 0, 0), (0.1, 0, 0), refine="ocp")
    check_refine("none")  # no refinement needs nothing


def test_cli_missing_casadi_and_unknown_value(run_cli, monkeypatch) -> None:
    status, stdout, _ = run_cli("plan", "unicycle", "--to", "x=0.1", "--refine", "bogus",
                                "--json")
    assert status == 2 and json.loads(stdout)["error"]["kind"] == "option"
    monkeypatch.setitem(sys.modules, "casadi", None)
    status, stdout, _ = run_cli("plan", "unicycle", "--to", "x=0.1", "--refine", "ocp",
                                "--json")
    assert status == 2
    err = json.loads(stdout)["error"]
    assert err["kind"] == "missing-extra" and "nilpotent[ocp]" in err["message"]


@needs_casadi
def test_a_refinement_that_misses_the_tolerance_is_refused() -> None:
    """A tolerance below what any re-simulation meets (1e-17: under the rounding of the
    goal's coordinates): the refined controls are refused and the plan stays, with why."""
    h = get_model("heisenberg")
    goal = (0.5, 0.3, 0.4)
    warm = plan(h, (0, 0, 0), goal)
    segs, info = refine_segments(Checker(h), (0, 0, 0), goal, warm.segments, 1e-17)
    assert not info.applied and "miss the goal" in info.reason
    assert info.length_refined is not None and info.length_refined < info.length_before
    assert segs == list(warm.segments)


@needs_casadi
def test_a_refined_motion_through_an_obstacle_is_refused() -> None:
    """Obstacles are not constraints of the optimal control problem, only of the
    verification: the car's straight drive (the shortest motion) through a pillar is
    found, refused as not admissible, and the plan is kept unchanged."""
    from nilpotent.planning.world import world_from_dict

    car = get_model("car")
    world = world_from_dict({"name": "pillar", "bounds": {"x": [-3.0, 9.0], "y": [-4.0, 4.0]},
                             "obstacles": [{"disc": {"center": [3.0, 0.0], "radius": 0.3}}]})
    warm = [constant_segment((3.0, 0.0)), constant_segment((3.0, 0.0))]
    goal = (6.0, 0.0, 0.0, 0.0)
    segs, info = refine_segments(Checker(car, world), (0, 0, 0, 0), goal, warm, 1e-8)
    assert not info.applied and "not admissible" in info.reason and "obstacle" in info.reason
    assert segs == warm
    assert info.length_refined == pytest.approx(6.0, rel=1e-6)  # the straight drive


@needs_casadi
def test_a_refinement_that_spends_the_time_limit_keeps_the_plan(monkeypatch) -> None:
    """A refinement that runs until the hard deadline (as its own verification may) and is
    stopped there: the plan found before it is returned, verified, not a time-limit error
    (it used to be re-verified after the refinement, with no time left)."""
    import time

    from nilpotent.planning import budget, ocp

    def slow(*args, **kwargs):
        while budget.seconds_left(hard=True) > 0:
            time.sleep(0.05)
        budget.check("refining (test)", True)  # raises ComputationLimitError
        raise AssertionError("the budget did not stop the refinement")

    monkeypatch.setattr(ocp, "refine_segments", slow)
    h = get_model("heisenberg")
    goal = (0.2, 0.1, 0.05)
    g = plan_global(h, (0, 0, 0), goal, time_limit=4.0, refine="ocp")
    assert g.refinement is not None and not g.refinement.applied
    assert "time limit" in g.refinement.reason
    data = json.loads(json.dumps(g.to_json(), allow_nan=False))
    states = resimulate(h, (0, 0, 0), data["segments"])
    assert np.linalg.norm(states[-1] - np.array(goal)) <= 1e-8


def test_a_limit_violation_below_the_printed_digits_says_by_how_much() -> None:
    # y = 0.2 + 1e-13 against y <= 0.2: "0.2 outside [0, 0.2]" alone reads as no violation
    checker = Checker(get_model("unicycle"), limits=Limits((("y", 0.0, 0.2),)))
    why = checker.why_invalid(np.array([0.0, 0.2 + 1e-13, 0.0]))
    assert "outside [0, 0.2] (by 1e-13)" in why
    assert "(by" not in checker.why_invalid(np.array([0.0, 0.5, 0.0]))  # 0.5 shows it


@needs_casadi
def test_no_controls_to_refine_says_the_start_is_within_tol() -> None:
    # a start within --tol of a different goal: the plan has no segments; start and goal
    # do not coincide, so the reason must not say they do
    h = get_model("heisenberg")
    segs, info = refine_segments(Checker(h), (0, 0, 0), (0.1, 0, 0), [], 0.5)
    assert segs == [] and not info.applied
    assert "within tol" in info.reason and "coincide" not in info.reason


@needs_casadi
def test_uniform_input_weights_scale_the_refined_length() -> None:
    """With every weight ``c`` the metric is ``c`` times the standard one: the refined
    Heisenberg length is ``c`` times Dido's closed-form distance."""
    from nilpotent.planning.ocp import OcpRefine

    h = get_model("heisenberg")
    goal = (0.5, 0.3, 0.4)
    warm = plan(h, (0, 0, 0), goal)
    segs, info = refine_segments(Checker(h), (0, 0, 0), goal, warm.segments, 1e-8,
                                 options=OcpRefine(input_weights=(2.0, 2.0)))
    assert info.applied, info.reason
    d = heisenberg_distance(*goal)
    assert info.length_refined is not None
    assert 2 * d * (1 - 1e-9) <= info.length_refined <= 2 * d * (1 + DISCRETISATION)
    assert info.length_refined == pytest.approx(2 * control_length(segs), rel=1e-9)
    assert info.to_json()["input_weights"] == [2.0, 2.0]


def test_bad_refinement_options_are_option_errors() -> None:
    from nilpotent.planning.ocp import OcpRefine

    for bad in ({"starts": 0}, {"starts": 10**6}, {"reversal_cost": -1.0},
                {"reversal_cost": float("nan")}, {"input_weights": (1.0, 0.0)},
                {"input_weights": (1.0, float("inf"))}, {"input_weights": ()},
                {"smooth": "yes"}):
        with pytest.raises(OptionError):
            OcpRefine(**bad)  # type: ignore[arg-type]
    with pytest.raises(OptionError, match="2 inputs"):
        OcpRefine(input_weights=(1.0, 1.0, 1.0)).weights(2)


@needs_casadi
def test_a_reversal_cost_needs_a_drive_input() -> None:
    from nilpotent.planning.ocp import OcpRefine

    h = get_model("heisenberg")
    warm = plan(h, (0, 0, 0), (0.1, 0.0, 0.1))
    with pytest.raises(OptionError, match="no drive input"):
        refine_segments(Checker(h), (0, 0, 0), (0.1, 0.0, 0.1), warm.segments, 1e-8,
                        options=OcpRefine(reversal_cost=1.0))


@pytest.mark.slow
@needs_casadi
def test_car_with_cheap_steering_and_several_starts_is_near_reeds_shepp() -> None:
    """The car shifted sideways by 1 (Reeds–Shepp optimum of radius 1 from OMPL): with the
    steering rate weighted 0.1 and 4 starts, the re-simulated refined rear-axle path
    ``∫|v| dt`` is within 1.25× the Reeds–Shepp length (the warm plan: about 8×)."""
    ob = pytest.importorskip("ompl.base")
    from nilpotent.planning.ocp import OcpRefine

    car = get_model("car")
    checker = Checker(car)
    goal = (0.0, 1.0, 0.0, 0.0)
    warm = plan(car, (0, 0, 0, 0), goal, objective="length")
    segs, info = refine_segments(checker, (0, 0, 0, 0), goal, warm.segments, 1e-6,
                                 options=OcpRefine(input_weights=(1.0, 0.1), starts=4))
    assert info.applied, info.reason
    states = resimulate(car, (0, 0, 0, 0), segment_dicts(segs))
    assert np.linalg.norm(states[-1] - np.array(goal)) <= 1e-6
    drive = sum(abs(s.inputs[0].constant) * s.duration for s in segs)
    space = ob.ReedsSheppStateSpace(1.0)
    a, b = space.allocState(), space.allocState()
    a.setXY(0.0, 0.0), a.setYaw(0.0), b.setXY(0.0, 1.0), b.setYaw(0.0)
    rs = space.distance(a, b)
    assert drive <= 1.25 * rs, (drive, rs)


# --- the command line: the refinement's options ----------------------------------------


@pytest.mark.parametrize("args, message", [
    (["--input-weights", "u2=1/10"], "--input-weights needs --refine ocp"),
    (["--refine-starts", "2"], "--refine-starts needs --refine ocp"),
    (["--reversal-cost", "1"], "--reversal-cost needs --refine ocp"),
    (["--refine-smooth"], "--refine-smooth needs --refine ocp"),
    (["--refine", "ocp", "--input-weights", "u3=1"], "unknown input 'u3'"),
    (["--refine", "ocp", "--input-weights", "u2=0"], "a weight must be a positive number"),
    (["--refine", "ocp", "--input-weights", "-1"], "a weight must be a positive number"),
    (["--refine", "ocp", "--input-weights", "u1=1,u1=2"], "u1 given twice"),
    (["--refine", "ocp", "--input-weights", "u1="], "a weight is missing"),
    (["--refine", "ocp", "--input-weights", "w"], "--input-weights: unknown name 'w'"),
    (["--refine", "ocp", "--refine-starts", "0"], "--refine-starts"),
    (["--refine", "ocp", "--refine-starts", "33"], "--refine-starts"),
    (["--refine", "ocp", "--reversal-cost", "-1"], "--reversal-cost"),
    (["--refine", "ocp", "--reversal-cost", "1"], "no drive input"),
    (["--refine", "ocp", "--reversal-cost", "0"], "no drive input"),
    (["--refine", "ocp", "--input-weights", "1e-7"], "from 1e-06 to 1e+06"),
    (["--refine", "ocp", "--input-weights", "u1=1e308"], "from 1e-06 to 1e+06"),
])
def test_cli_refinement_options_are_checked_before_any_work(run_cli, args, message) -> None:
    """Each bad value (and each option without ``--refine ocp``, which would be ignored)
    is an option (or expression) error naming it, exit 2, on the Heisenberg system (no
    drive input)."""
    status, stdout, stderr = run_cli("plan", "heisenberg", "--to", "x3=1/10", *args, "--json")
    assert status == 2, stdout
    err = json.loads(stdout)["error"]
    assert err["kind"] in ("option", "expression") and message in err["message"], err
    assert "Traceback" not in stderr


def test_cli_most_refine_starts_is_the_library_s() -> None:
    from nilpotent.cli.plan_options import MAX_REFINE_STARTS
    from nilpotent.planning.ocp import MAX_STARTS

    assert MAX_REFINE_STARTS == MAX_STARTS
    from nilpotent.cli import plan_options
    from nilpotent.planning import ocp

    assert (plan_options.MIN_WEIGHT, plan_options.MAX_WEIGHT) == (ocp.MIN_WEIGHT, ocp.MAX_WEIGHT)


@needs_casadi
def test_a_common_factor_of_the_weights_changes_nothing() -> None:
    """Weights ``(c, c)`` for ``c`` = 1e-6, 1, 1e6 give the same refined controls (their
    unweighted lengths agree to 1e-9) and weighted lengths ``c`` times the unweighted."""
    from nilpotent.planning.ocp import OcpRefine

    h = get_model("heisenberg")
    goal = (0.5, 0.3, 0.4)
    warm = plan(h, (0, 0, 0), goal)
    lengths = []
    for c in (1e-6, 1.0, 1e6):
        segs, info = refine_segments(Checker(h), (0, 0, 0), goal, warm.segments, 1e-8,
                                     options=OcpRefine(input_weights=(c, c)))
        assert info.applied, info.reason
        assert info.length_refined == pytest.approx(c * control_length(segs), rel=1e-9)
        lengths.append(control_length(segs))
    assert max(lengths) - min(lengths) <= 1e-9 * max(lengths)


@needs_casadi
def test_cli_input_weights_and_starts_reach_the_refinement(run_cli) -> None:
    """``--input-weights 2`` on the Heisenberg system: the refined length (in the weighted
    metric) is twice Dido's closed-form distance; the options are reported; the plan is
    re-simulated independently to the goal."""
    goal = (0.5, 0.3, 0.4)
    status, stdout, stderr = run_cli(
        "plan", "heisenberg", "--to", "x1=1/2,x2=3/10,x3=2/5", "--refine", "ocp",
        "--input-weights", "2", "--refine-starts", "2", "--seed", "7", "--time-limit", "900",
        "--json")
    assert status == 0, stderr
    data = json.loads(stdout)
    ref = data["refinement"]
    assert ref["applied"] is True, ref
    assert ref["input_weights"] == [2.0, 2.0] and ref["starts"] == 2 == ref["starts_run"]
    assert ref["candidates"] >= 1 and ref["reversal_cost"] == 0.0
    d = heisenberg_distance(*goal)
    assert 2 * d * (1 - 1e-9) <= ref["length_refined"] <= 2 * d * (1 + DISCRETISATION)
    q = resimulate(get_model("heisenberg"), data["from"], data["segments"])
    assert np.linalg.norm(q[-1] - np.array(goal)) <= 1e-7


@needs_casadi
def test_cli_reversal_cost_on_a_vehicle_is_reported(run_cli) -> None:
    """``--reversal-cost`` on the unicycle: the refinement's cost is its length plus C
    times the drive reversals of the controls it kept (counted here from the segments)."""
    status, stdout, stderr = run_cli(
        "plan", "unicycle", "--to", "x=1/2,y=1/5,theta=1/5", "--refine", "ocp",
        "--reversal-cost", "1.5", "--time-limit", "900", "--json")
    assert status == 0, stderr
    data = json.loads(stdout)
    ref = data["refinement"]
    assert ref["reversal_cost"] == 1.5 and ref["applied"] is True, ref
    # the drive reversals counted here from the segments: sign changes of u1's constants,
    # values below 1e-6 of the largest having no sign (the interface's definition)
    drive = [s["inputs"][0]["constant"] for s in data["segments"]]
    signs = [np.sign(v) for v in drive if abs(v) > 1e-6 * max(map(abs, drive))]
    reversals = sum(a != b for a, b in itertools.pairwise(signs))
    assert ref["cost_refined"] == pytest.approx(ref["length_refined"] + 1.5 * reversals,
                                                rel=1e-9)
    assert ref["cost_refined"] < ref["cost_before"]


# --- smooth controls (cosine series) ------------------------------------------------------


@needs_casadi
def test_smooth_heisenberg_controls_are_one_segment_at_the_closed_form_length() -> None:
    """``smooth``: one segment of cosine-series inputs whose length is Dido's distance to
    1e-3 (a truncated series of the geodesic's sinusoidal inputs), re-simulated
    independently to the goal."""
    from nilpotent.planning.ocp import OcpRefine

    h = get_model("heisenberg")
    goal = (0.5, 0.3, 0.4)
    warm = plan(h, (0, 0, 0), goal)
    segs, info = refine_segments(Checker(h), (0, 0, 0), goal, warm.segments, 1e-8,
                                 options=OcpRefine(smooth=True))
    assert info.applied and info.controls == "cosine series", (info.reason, info.smooth_reason)
    assert len(segs) == 1 and segs[0].omega == pytest.approx(math.pi)
    d = heisenberg_distance(*goal)
    assert d * (1 - 1e-9) <= control_length(segs) <= d * (1 + 1e-3)
    states = resimulate(h, (0, 0, 0), segment_dicts(segs))
    assert np.linalg.norm(states[-1] - np.array(goal)) <= 1e-7
    assert info.to_json()["controls"] == "cosine series"


@needs_casadi
@pytest.mark.slow
def test_smooth_car_keeps_its_steering_limit_and_re_times_with_two_stops() -> None:
    """The car with smooth refined controls: re-simulated independently, within
    ``|φ| ≤ atan 0.6`` and at the goal; re-timed under speed and acceleration bounds it
    rests only at its ends and where the drive input reverses (inputs continuous)."""
    from nilpotent.planning.ocp import OcpRefine
    from nilpotent.planning.timing import input_reversals

    car = get_model("car")
    goal = (0.5, 0.5, 0.8, 0.0)
    g = plan_global(car, (0, 0, 0, 0), goal, 1e-8, objective="length", time_limit=900,
                    refine=OcpRefine(input_weights=(1.0, 0.1), smooth=True),
                    max_speed=[1.0, math.inf], max_accel=[2.0, 4.0])
    assert g.refinement is not None and g.refinement.applied, g.refinement
    assert g.refinement.controls == "cosine series", g.refinement.smooth_reason
    assert len(g.plan.segments) == 1
    states = resimulate(car, (0, 0, 0, 0), segment_dicts(g.plan.segments), samples=2000)
    assert np.linalg.norm(states[-1] - np.array(goal)) <= 1e-6
    assert np.abs(states[:, 3]).max() <= math.atan(0.6) + 1e-9
    timed = g.timed
    assert timed is not None
    assert len(timed.stops) <= 2 + sum(input_reversals(g.plan.segments))
    u = timed.inputs
    assert np.all(np.abs(np.diff(u, axis=0)) / np.diff(timed.times)[:, None]
                  <= np.array([2.0, 4.0]) * 1.05)


@needs_casadi
def test_cli_human_output_compares_the_same_metric(run_cli) -> None:
    """The printed refinement line names the weighted metric and gives the refined length
    in it (the JSON's ``length_refined``), not the plan's unweighted length."""
    args = ("plan", "heisenberg", "--to", "x1=1/2,x2=3/10,x3=2/5", "--refine", "ocp",
            "--input-weights", "u1=1/10", "--time-limit", "900")
    status, out, err = run_cli(*args)
    assert status == 0, err
    status, js, err = run_cli(*args, "--json")
    ref = json.loads(js)["refinement"]
    text = " ".join(out.split())  # the console wraps long lines
    line = text[text.index("refinement ocp"):text.index("goal reached")]
    assert "weighted length (weights 0.1, 1)" in line
    assert f"-> {ref['length_refined']:.6g}" in line and "starts 1 of 1" in line
