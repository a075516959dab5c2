"""``--planner reeds-shepp``: a Reeds–Shepp guide lifted to the car, then our steering.

Every plan is replayed independently (tests/replay.py: scipy on the lambdified fields);
the replayed body (the rectangle of ``car_outline``'s docstring, rebuilt here) is checked
against the world's polygons read from its TOML file with shapely, the steering angle
against its limit, the end against the goal; the rear axle's path length is compared with
OMPL's Reeds–Shepp distance of radius ``rmin`` (no obstacles): a lower bound for any path
of the car (its turning radius is at least ``rmin``) and the yardstick of the upper factor.
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
import shapely
from typer.testing import CliRunner

import nilpotent.cli.cmd_plan  # noqa: F401  (registers the command)
from nilpotent.cli import app
from nilpotent.errors import OptionError
from nilpotent.models import get_model
from nilpotent.planning.global_planner import plan_global
from nilpotent.planning.guide import PHI_MARGIN, lift
from nilpotent.planning.world import load_world
from replay import resimulate
from test_optimal_planner import car_body_points

WORLDS = Path(__file__).resolve().parents[1] / "examples" / "worlds"
PHI_MAX = math.atan(0.6)
#: (world, start, goal, the most the rear axle's path may exceed the Reeds–Shepp distance)
CASES = {
    # measured 1.23x (around the corner) with every Reeds-Shepp leg driven exactly; RRT*'s
    # improvement is timed, so its guide (and this ratio) varies with the load: room for that
    "corner": ((2.2, 0.65, -0.25, 0.0), (6.0, 5.6, 1.8, 0.0), 1.6),
    # the first pair of benchmarks/plan_world.py's car-parking (rounded): into the slot
    # (measured 1.09x; RRT*'s first paths here were up to 2x, room for a loaded machine)
    "parking": ((-0.271, 0.843, -0.275, 0.0), (0.033, -0.519, 0.041, 0.0), 2.5),
}


def reeds_shepp_distance(a, b, radius: float = 1.0) -> float:
    """OMPL's Reeds–Shepp distance between the poses of ``a`` and ``b``."""
    from ompl import base as ob

    space = ob.ReedsSheppStateSpace(radius)
    s, g = space.allocState(), space.allocState()
    for st, q in ((s, a), (g, b)):
        st.setX(float(q[0]))
        st.setY(float(q[1]))
        st.setYaw(float(q[2]))
    return float(space.distance(s, g))


def collision_free(name: str, q: np.ndarray) -> bool:
    """The body at every replayed sample inside the bounds and outside every polygon of the
    world file (read here, not through the product's world loader)."""
    spec = tomllib.loads((WORLDS / f"{name}.toml").read_text())
    pts = car_body_points(q).reshape(-1, 2)
    (x0, x1), (y0, y1) = spec["bounds"]["x"], spec["bounds"]["y"]
    inside = (pts[:, 0] > x0) & (pts[:, 0] < x1) & (pts[:, 1] > y0) & (pts[:, 1] < y1)
    hit = np.zeros(len(pts), dtype=bool)
    for ob in spec["obstacles"]:
        hit |= shapely.contains_xy(shapely.Polygon(ob["polygon"]), pts[:, 0], pts[:, 1])
    return bool(inside.all() and not hit.any())


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(CASES))
def test_reeds_shepp_plan_replays_collision_free(name):
    start, goal, factor = CASES[name]
    system = get_model("car")
    out = plan_global(system, start, goal, 1e-6, world=load_world(name), time_limit=600,
                      planner="reeds-shepp", seed=0).to_json()
    assert out["planner"] == "reeds-shepp"
    q = resimulate(system, start, out["segments"], samples=200)
    assert np.linalg.norm(q[-1] - np.array(goal)) <= 1e-5
    assert np.all(np.abs(q[:, 3]) <= PHI_MAX + 1e-9)
    assert collision_free(name, q)
    xy = float(np.linalg.norm(np.diff(q[:, :2], axis=0), axis=1).sum())
    rs = reeds_shepp_distance(start, goal)
    assert 0.999 * rs <= xy <= factor * rs
    # the legs are driven, not steered: the replay is the guide's own path (measured 1.0000
    # its length, every piece exact; 2x and 3x when every piece was steered)
    assert xy <= 1.05 * out["path_cost"]
    # reversals of the drive along the heading, from the replay (measured 0 and 2; 391 and
    # 363 when every piece was steered)
    d = np.diff(q[:, :2], axis=0)
    along = d[:, 0] * np.cos(q[:-1, 2]) + d[:, 1] * np.sin(q[:-1, 2])
    signs = np.sign(along[np.abs(along) > 1e-9])
    assert int(np.sum(signs[1:] != signs[:-1])) <= 6
    # the guide's own length: at least the obstacle-free distance of its larger radius
    radius = 0.6 / math.tan(PHI_MAX - PHI_MARGIN)
    assert out["path_cost"] >= 0.999 * reeds_shepp_distance(start, goal, radius)


def test_not_car_like_refused():
    with pytest.raises(OptionError, match="car-like"):
        plan_global(get_model("unicycle"), (0, 0, 0), (3, 1, 0), planner="reeds-shepp",
                    time_limit=600)
    with pytest.raises(OptionError, match="car-like"):
        plan_global(get_model("car-trailers:3"), (0,) * 6, (3, 1, 0, 0, 0, 0),
                    planner="reeds-shepp", time_limit=600)
    result = CliRunner().invoke(app, ["plan", "unicycle", "--to", "x=3", "--planner",
                                      "reeds-shepp", "--json"])
    assert result.exit_code == 2
    assert "car-like" in json.loads(result.stdout)["error"]["message"]


def test_lift_of_an_arc_then_a_straight_leg():
    """A left arc of radius 2 through a quarter turn, then straight ahead: φ = atan(L/2) on
    the arc, 0 on the leg, the wheels turned at rest at the start, the switch, the end."""
    t = np.linspace(0.0, math.pi / 2, 400)
    arc = np.column_stack([2 * np.sin(t), 2 - 2 * np.cos(t), t])
    line = np.column_stack([np.full(100, 2.0), np.linspace(2.0, 3.0, 100),
                            np.full(100, math.pi / 2)])
    poses = np.vstack([arc, line[1:]])
    x0, xg = np.zeros(4), np.array([2.0, 3.0, math.pi / 2, 0.0])
    pts = np.array(lift(poses, x0, xg, 0.6, 2.0))
    assert np.allclose(pts[0], x0) and np.allclose(pts[-1], xg)
    phi = math.atan(0.3)
    on_arc = (pts[:, 1] < 2.0 - 1e-9) & (pts[:, 0] > 1e-9)
    assert np.allclose(pts[on_arc, 3], phi)
    on_line = pts[:, 1] > 2.0 + 1e-9
    assert np.allclose(pts[on_line, 3], 0.0)
    # every waypoint lies on the circle or the line, with the heading of the path there
    r = np.hypot(pts[:, 0], pts[:, 1] - 2)
    assert np.all(on_line | np.isclose(r, 2.0, atol=1e-3))
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert steps.max() <= 0.3


@pytest.mark.slow
def test_cli_reeds_shepp_json():
    result = CliRunner().invoke(app, [
        "plan", "car", "--from", "x=2.2,y=0.65,theta=-0.25", "--to", "x=6,y=5.6,theta=1.8",
        "--world", "corner", "--planner", "reeds-shepp", "--tol", "1e-6", "--time-limit",
        "600", "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    assert out["planner"] == "reeds-shepp" and out["route"] == "global"
    assert isinstance(out["path_cost"], float) and out["cost_history"]
    system = get_model("car")
    q = resimulate(system, (2.2, 0.65, -0.25, 0.0), out["segments"], samples=100)
    assert np.linalg.norm(q[-1] - np.array([6.0, 5.6, 1.8, 0.0])) <= 1e-5
    assert collision_free("corner", q)
