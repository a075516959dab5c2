"""Iterative steering of true systems: goals reached, checked by an independent simulation.

The oracle re-simulates the returned segments with scipy's solve_ivp (DOP853,
rtol 1e-13) on the model's fields lambdified by sympy, independently of the
planner's integrator and of its nilpotent models.
"""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from nilpotent.errors import OptionError, PlanningError, SingularPointError
from nilpotent.models import get_model
from nilpotent.planning import Plan, Segment, plan


def resimulate(system, start, segments) -> np.ndarray:
    params = {sp.Symbol(k): v for k, v in system.parameters}
    mat = sp.lambdify(
        [system.coordinates], sp.Matrix(system.fields).T.xreplace(params), "numpy"
    )
    x = np.asarray(start, dtype=float)
    for seg in segments:
        def rhs(t, z, seg=seg):
            return np.asarray(mat(z), dtype=float) @ seg.values(t)

        sol = solve_ivp(rhs, (0, seg.duration), x, method="DOP853", rtol=1e-13, atol=1e-14)
        x = sol.y[:, -1]
    return x


# (model, homogeneous distance of the goals, number of goals, engine): the trident
# snake uses the compiled engine (the default); the others scipy, so that the suite
# compiles no kernel for them
CASES = [
    ("trident-snake", 0.3, 3, "auto"),
    ("trident-snake-paper", 0.3, 2, "scipy"),
    ("unicycle", 0.3, 3, "scipy"),
    ("engel", 0.3, 2, "scipy"),
    ("car-trailers:1", 0.2, 2, "scipy"),
    pytest.param("car-trailers:2", 0.1, 1, "scipy", marks=pytest.mark.slow),
]


def random_goal(system, distance: float, rng) -> np.ndarray:
    """A goal at homogeneous distance ``distance`` from the origin.

    ``y = δ_d(v)`` with ``v`` uniform on the unit quasi-sphere
    ``max_j |v_j|^{1/w_j} = 1`` in privileged coordinates at the origin, then
    ``x(y)``.  (Goals drawn in ``x`` directly are far in the weight-r
    directions: ``|x_j| = 0.03`` is at distance ``0.03^{1/4} ≈ 0.4`` when
    ``w_j = 4``.)
    """
    from nilpotent.planning.local_model import BUILDERS, choose_builder

    model = BUILDERS[choose_builder(system, system.origin())](system, system.origin())
    tri = model.nilpotent
    v = rng.uniform(-1.0, 1.0, size=tri.n)
    v = tri.dilate(v, 1.0 / tri.quasi_norm(v))
    return model.inverse(tri.dilate(v, distance))


@pytest.mark.parametrize(("name", "scale", "count", "engine"), CASES)
def test_random_goals_reached_to_1e8(name, scale, count, engine):
    system = get_model(name)
    rng = np.random.default_rng(11)
    start = np.zeros(system.n)
    for _ in range(count):
        goal = random_goal(system, scale, rng)
        p = plan(system, start, goal, tol=1e-9, engine=engine)
        assert p.converged and p.error <= 1e-9
        if p.anchor == "current":
            assert p.iterations[-1].error == pytest.approx(p.error)
        reached = resimulate(system, start, p.segments)
        assert np.linalg.norm(reached - goal) <= 1e-8


def test_trident_from_a_generic_start_and_parameters():
    system = get_model("trident-snake", {"r": sp.Rational(1, 2), "l": sp.Rational(3, 2)})
    start = np.array([0.3, -0.2, 0.5, 0.1, -0.3, 0.2])
    goal = start + np.array([0.05, 0.1, -0.08, 0.1, 0.05, -0.1])
    p = plan(system, start, goal, engine="scipy")
    assert np.linalg.norm(resimulate(system, start, p.segments) - goal) <= 1e-8


def test_errors_decrease_superlinearly_on_the_trident():
    system = get_model("trident-snake")
    goal = np.array([0.05, -0.04, 0.03, 0.08, -0.06, 0.05])
    p = plan(system, np.zeros(6), goal, tol=1e-10)
    errors = [p.initial_error] + [it.error for it in p.iterations]
    assert all(b < a for a, b in itertools.pairwise(errors))
    # order > 1: the ratios of successive errors shrink
    ratios = [b / a for a, b in itertools.pairwise(errors)]
    assert ratios[-1] < ratios[0] / 10


def test_anchors_agree_on_reaching_the_goal():
    system = get_model("unicycle")
    goal = np.array([0.1, 0.05, -0.2])
    for anchor in ("current", "goal", "start"):
        p = plan(system, np.zeros(3), goal, anchor=anchor, engine="scipy")
        assert p.anchor == anchor
        assert np.linalg.norm(resimulate(system, np.zeros(3), p.segments) - goal) <= 1e-8


def test_plan_json_is_the_interface_schema():
    system = get_model("unicycle")
    p = plan(system, (0, 0, 0), (sp.Rational(1, 10), 0, 0), engine="scipy")
    data = json.loads(json.dumps(p.to_json(), allow_nan=False))
    assert data["schema"] == "nilpotent/plan@1"
    for key in ("model", "coordinates", "from", "to", "reached", "error", "iterations",
                "segments"):
        assert key in data
    assert data["to"] == [0.1, 0.0, 0.0]
    segs = [Segment.from_dict(s) for s in data["segments"]]
    assert np.linalg.norm(resimulate(system, data["from"], segs) - np.array(data["to"])) <= 1e-8
    for seg in data["segments"]:
        assert set(seg) == {"duration", "omega", "inputs"}
        for inp in seg["inputs"]:
            assert set(inp) == {"constant", "cos", "sin"}


def test_plan_json_is_strict_with_non_finite_numbers():
    """A Newton step has no homogeneous distance (NaN): to_json() is still strict JSON,
    the number null and its place listed (issue 18: every to_json() strict)."""
    import dataclasses
    import math

    p = plan(get_model("unicycle"), (0, 0, 0), (sp.Rational(1, 10), 0, 0), engine="scipy")
    assert p.iterations
    first = dataclasses.replace(p.iterations[0], distance=math.nan)
    q = dataclasses.replace(p, iterations=(first, *p.iterations[1:]))
    data = q.to_json()
    text = json.dumps(data, allow_nan=False)  # raises on NaN/Infinity
    assert json.loads(text)["iterations"][0]["distance"] is None
    assert data["undefined"]["paths"] == ["iterations[0].distance"]
    assert math.isnan(q.json_fields()["iterations"][0]["distance"])


def test_start_equal_goal_gives_an_empty_plan():
    p = plan(get_model("unicycle"), (0, 0, 0), (0, 0, 0), engine="scipy")
    assert p.segments == () and p.error == 0 and isinstance(p, Plan)


def test_singular_start_is_reported():
    # Martinet at the origin: growth (2, 2, 3), singular
    with pytest.raises(SingularPointError):
        plan(get_model("martinet"), (0, 0, 0), (0.1, 0.1, 0.01), engine="scipy")


def test_singular_joint_configuration_is_reported():
    # all legs along +y: the wheel axles are parallel, the joint form is undefined
    q = (0, 0, 0, np.pi / 2, -np.pi / 6, -5 * np.pi / 6)
    with pytest.raises(SingularPointError):
        plan(get_model("trident-snake-joints"), q, np.array(q) + 0.01, engine="scipy")


def test_bad_options_are_option_errors_bad_points_planning_errors():
    """A bad option value is an OptionError (kind ``option``), as on the command line."""
    system = get_model("unicycle")
    with pytest.raises(OptionError, match="anchor"):
        plan(system, (0, 0, 0), (0.1, 0, 0), anchor="nowhere")
    with pytest.raises(OptionError, match="tol"):
        plan(system, (0, 0, 0), (0.1, 0, 0), tol=-1)
    with pytest.raises(PlanningError, match="coordinates"):
        plan(system, (0, 0), (0.1, 0, 0))


def test_failure_returns_best_plan_when_asked():
    system = get_model("trident-snake")
    goal = np.array([0.05, -0.04, 0.03, 0.08, -0.06, 0.05])
    with pytest.raises(PlanningError, match="not reached"):
        plan(system, np.zeros(6), goal, max_iterations=1, refine=False)
    p = plan(system, np.zeros(6), goal, max_iterations=1, raise_on_failure=False, refine=False)
    assert not p.converged and len(p.iterations) == 1 and p.error < p.initial_error


def test_shooting_refinement_finishes_a_truncated_plan():
    system = get_model("trident-snake")
    goal = np.array([0.05, -0.04, 0.03, 0.08, -0.06, 0.05])
    p = plan(system, np.zeros(6), goal, max_iterations=2)
    kinds = [it.kind for it in p.iterations]
    assert kinds[:2] == ["nilpotent", "nilpotent"] and set(kinds[2:]) == {"newton"}
    assert np.linalg.norm(resimulate(system, np.zeros(6), p.segments) - goal) <= 1e-8


def test_not_bracket_generating_is_reported():
    from nilpotent.core.model.system import ControlSystem
    from nilpotent.errors import NotBracketGeneratingError

    x, y, z = sp.symbols("x y z")
    flat = ControlSystem("flat", (x, y, z), ((1, 0, 0), (0, 1, 0)))
    with pytest.raises(NotBracketGeneratingError):
        plan(flat, (0, 0, 0), (0.1, 0.1, 0.1), engine="scipy")


def test_handover_to_shooting_refinement_on_a_high_step_system():
    system = get_model("car-trailers:1")
    goal = random_goal(system, 0.2, np.random.default_rng(3))
    p = plan(system, np.zeros(4), goal, engine="scipy", handover=1e-3)
    kinds = [it.kind for it in p.iterations]
    assert "newton" in kinds and kinds[0] == "nilpotent"
    assert np.linalg.norm(resimulate(system, np.zeros(4), p.segments) - goal) <= 1e-8
    with pytest.raises(OptionError, match="handover"):
        plan(system, np.zeros(4), goal, handover=-1.0)
