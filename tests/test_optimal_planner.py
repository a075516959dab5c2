"""``--planner rrtstar``: OMPL RRT* under the ball–box cost, then our steering (issue 20).

Every returned plan is replayed independently (tests/replay.py: scipy on lambdified fields)
and checked against the limits and the goal at dense samples; the anytime cost never
increases; the reported reversals equal the sign changes of the drive input read from the
JSON segments by a formula of this file; the ball–box cost matches hand derivations.
"""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import nilpotent.cli.cmd_plan  # noqa: F401  (registers the command)
from nilpotent.cli import app
from nilpotent.errors import OptionError
from nilpotent.models import get_model
from nilpotent.planning.global_planner import plan_global
from nilpotent.planning.optimal_planner import ball_box_metric
from nilpotent.planning.timing import input_reversals
from replay import resimulate

LIMITS = {"theta": (-1.0, 1.0), "y": (-1.0, 1.0)}
START, GOAL = (0.0, 0.0, 0.0), (3.0, 0.6, 0.0)


@pytest.fixture(scope="module")
def unicycle_plan():
    """The unicycle between limits, far enough for the global route (seeded)."""
    system = get_model("unicycle")
    limits = system.limits.tightened(LIMITS)
    result = plan_global(system, START, GOAL, 1e-6, limits=limits, time_limit=20.0,
                         planner="rrtstar", objective="length", seed=3)
    return system, result


def drive_sign_changes(segments: list[dict], samples: int = 4001) -> int:
    """Sign changes of input 1 evaluated from the JSON segment formula (zeros skipped)."""
    values = []
    for seg in segments:
        t = np.linspace(0.0, seg["duration"], samples)
        inp = seg["inputs"][0]
        u = inp["constant"] + sum(a * np.cos((k + 1) * seg["omega"] * t)
                                  for k, a in enumerate(inp["cos"]))
        u = u + sum(b * np.sin((k + 1) * seg["omega"] * t) for k, b in enumerate(inp["sin"]))
        values.append(np.atleast_1d(u))
    u = np.concatenate(values)
    signs = np.sign(u[np.abs(u) > 1e-9 * np.abs(u).max()])
    return int(np.count_nonzero(np.diff(signs)))


def test_rrtstar_plan_replays_within_limits_to_the_goal(unicycle_plan):
    system, result = unicycle_plan
    out = result.to_json()
    assert out["planner"] == "rrtstar" and out["route"] == "global"
    states = resimulate(system, START, out["segments"], samples=200)
    assert np.all(np.abs(states[:, 1]) <= 1.0 + 1e-9)   # y limit
    assert np.all(np.abs(states[:, 2]) <= 1.0 + 1e-9)   # theta limit
    assert np.linalg.norm(states[-1] - np.array(GOAL)) <= 1e-5


def test_rrtstar_cost_is_non_increasing(unicycle_plan):
    _, result = unicycle_plan
    history = [c for _, c in result.cost_history]
    assert history, "RRT* recorded no cost"
    assert all(b <= a for a, b in itertools.pairwise(history))
    assert result.path_cost == pytest.approx(history[-1])
    assert all(b >= a for (a, _), (b, _) in itertools.pairwise(result.cost_history))


def test_reported_reversals_are_the_drive_sign_changes(unicycle_plan):
    _, result = unicycle_plan
    out = json.loads(json.dumps(result.to_json()))
    assert out["reversals"] == drive_sign_changes(out["segments"])


def test_reversals_of_hand_made_controls():
    from nilpotent.planning.controls import constant_segment

    fwd, back = constant_segment((1.0, 0.0)), constant_segment((-2.0, 0.5))
    assert input_reversals([fwd, back, fwd])[0] == 2
    assert input_reversals([fwd, constant_segment((0.0, 1.0)), fwd])[0] == 0  # a stop


def test_ball_box_cost_by_hand():
    """Unicycle frame (X1, X2, [X1, X2]) = ((cos θ, sin θ, 0), (0, 0, 1), (sin θ, −cos θ, 0)):
    a step along the heading costs its length, a sideways step ``d`` costs ``2√(π|d|)``
    (weight 2), a turn on the spot ``|Δθ|``."""
    metric = ball_box_metric(get_model("unicycle"), (0.0, 0.0, 0.0))
    p = np.zeros((1, 3))
    assert metric.cost(p, np.array([[0.3, 0.0, 0.0]]))[0] == pytest.approx(0.3)
    assert metric.cost(p, np.array([[0.0, 0.0, -0.2]]))[0] == pytest.approx(0.2)
    assert metric.cost(p, np.array([[0.0, 0.01, 0.0]]))[0] == pytest.approx(
        2 * math.sqrt(math.pi * 0.01))
    # heading π/2: the step along x is now sideways
    q = np.array([[0.0, 0.0, math.pi / 2]])
    assert metric.cost(q, q + np.array([0.01, 0.0, 0.0]))[0] == pytest.approx(
        2 * math.sqrt(math.pi * 0.01))
    # the edge cost of a long chord sums its pieces: 4 pieces of length ≤ 1 for 3.5 ahead
    assert metric.edge_cost(p[0], np.array([3.5, 0.0, 0.0]), 1.0) == pytest.approx(3.5)
    side = metric.edge_cost(p[0], np.array([0.0, 2.0, 0.0]), 1.0)
    assert side == pytest.approx(2 * 2 * math.sqrt(math.pi * 1.0))


def test_unknown_planner_refused():
    with pytest.raises(OptionError, match="planner"):
        plan_global(get_model("unicycle"), START, GOAL, planner="prm")
    result = CliRunner().invoke(app, ["plan", "unicycle", "--to", "x=1", "--planner", "prm"])
    assert result.exit_code == 2
    assert "--planner" in result.output and "Traceback" not in result.output


@pytest.mark.slow
def test_cli_rrtstar_json_fields():
    result = CliRunner().invoke(app, [
        "plan", "unicycle", "--to", "x=3,y=0.6", "--limit", "theta=-1:1", "--limit", "y=-1:1",
        "--planner", "rrtstar", "--objective", "length", "--tol", "1e-6", "--time-limit", "20",
        "--seed", "3", "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    assert out["planner"] == "rrtstar"
    assert out["reversals"] == drive_sign_changes(out["segments"])
    assert isinstance(out["path_cost"], float) and out["cost_history"]


def car_body_points(q: np.ndarray, wheelbase: float = 0.6, per_edge: int = 20) -> np.ndarray:
    """Points on the edges of the car's body rectangle, from ``L/4`` behind the rear axle to
    ``L/4`` ahead of the front one, ``3L/4`` wide (docstring of ``car_outline``), ``(N, P, 2)``."""
    h = 3 * wheelbase / 8
    corners = np.array([(-wheelbase / 4, -h), (5 * wheelbase / 4, -h),
                        (5 * wheelbase / 4, h), (-wheelbase / 4, h)])
    s = np.linspace(0.0, 1.0, per_edge)[:, None]
    local = np.vstack([a + s * (b - a) for a, b in zip(corners, np.roll(corners, -1, axis=0),
                                                          strict=True)])
    c, sn = np.cos(q[:, 2])[:, None], np.sin(q[:, 2])[:, None]
    x = q[:, :1] + c * local[None, :, 0] - sn * local[None, :, 1]
    y = q[:, 1:2] + sn * local[None, :, 0] + c * local[None, :, 1]
    return np.stack([x, y], axis=-1)


@pytest.mark.slow
def test_car_rrtstar_plan_in_a_world_replays_collision_free():
    """The ``car`` around a block (rrtstar): the independently re-simulated body stays
    outside the block and inside the bounds, |φ| within its limit, and reaches the goal."""
    from nilpotent.planning.world import world_from_dict

    block = [[1.5, 0.8], [2.5, 0.8], [2.5, 2.5], [1.5, 2.5]]
    world = world_from_dict({"name": "block", "bounds": {"x": [-2, 7], "y": [-2.5, 2.5]},
                             "obstacles": [{"polygon": block}]})
    system = get_model("car")
    start, goal = (0.0, 0.0, 0.0, 0.0), (4.0, 0.0, 0.0, 0.0)
    out = plan_global(system, start, goal, 1e-6, world=world, time_limit=60.0,
                      planner="rrtstar", seed=1).to_json()
    q = resimulate(system, start, out["segments"], samples=200)
    assert np.linalg.norm(q[-1] - np.array(goal)) <= 1e-5
    assert np.all(np.abs(q[:, 3]) <= math.atan(0.6) + 1e-9)
    pts = car_body_points(q).reshape(-1, 2)
    inside = ((pts[:, 0] > 1.5) & (pts[:, 0] < 2.5) & (pts[:, 1] > 0.8) & (pts[:, 1] < 2.5))
    assert not inside.any()
    assert np.all((pts[:, 0] > -2) & (pts[:, 0] < 7) & (pts[:, 1] > -2.5) & (pts[:, 1] < 2.5))
    assert out["reversals"] == drive_sign_changes(out["segments"])


@pytest.mark.slow
def test_execute_with_rrtstar_replans_with_it():
    """``execute --planner rrtstar``: the execution reports the planner, succeeds under
    measurement noise, and the applied controls re-simulated independently on the model
    end within the tolerance of the goal, inside the limits.  (RRT* improves its path for a
    share of the time limit, hence a limit of 40 s: ~10 s of improvement, the rest spare.)"""
    result = CliRunner().invoke(app, [
        "execute", "unicycle", "--to", "x=3,y=0.6", "--limit", "theta=-1:1", "--limit",
        "y=-1:1", "--planner", "rrtstar", "--noise", "1e-5", "--time-limit", "40", "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    assert out["planner"] == "rrtstar" and out["success"] is True
    q = resimulate(get_model("unicycle"), out["from"], out["closed_loop"]["segments"],
                   samples=100)
    assert np.linalg.norm(q[-1] - np.array([3.0, 0.6, 0.0])) <= 1e-3 + 1e-4
    assert np.abs(q[:, 1]).max() <= 1 + 1e-6 and np.abs(q[:, 2]).max() <= 1 + 1e-6


def test_execute_refuses_an_unknown_planner():
    result = CliRunner().invoke(app, ["execute", "unicycle", "--to", "x=1", "--planner",
                                      "prm", "--json"])
    assert result.exit_code == 2
    assert "--planner must be" in json.loads(result.stdout)["error"]["message"]


@pytest.mark.parametrize(("model", "expected"), [
    ("car", "reeds-shepp"), ("car-trailers:1", "reeds-shepp"), ("car-trailers:2", "reeds-shepp"),
    ("car-trailers:3", "rrtconnect"), ("unicycle", "rrtconnect"), ("trident-snake", "trident-ocp"),
])
def test_auto_chooses_the_stage_that_applies_to_the_model(model, expected):
    """``--planner auto``: the Reeds–Shepp guide (or lattice) where the model is car-like,
    the trident's optimal control where CasADi is installed, RRTConnect elsewhere."""
    from pathlib import Path

    from nilpotent.planning.optimal_planner import HolonomicStage
    from nilpotent.planning.verify import Checker
    from nilpotent.planning.world import load_world

    if expected == "trident-ocp":
        pytest.importorskip("casadi")
    world = None
    if model != "unicycle":
        world = load_world(Path(__file__).resolve().parents[1] / "examples" / "worlds"
                           / "parking.toml")
    stage = HolonomicStage("auto", 1.0, Checker(get_model(model), world))
    assert stage.planner == expected
    assert HolonomicStage("auto", 1.0).planner == "rrtconnect"  # no checker: nothing to test


def test_an_unknown_planner_names_auto_among_the_choices():
    from nilpotent.planning.optimal_planner import HolonomicStage

    with pytest.raises(OptionError, match="auto"):
        HolonomicStage("fastest", 1.0)
