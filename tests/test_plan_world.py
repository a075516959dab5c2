"""Planning among limits and obstacles: limits, outlines, worlds, global plans, JSON, CLI.

Plans are checked independently of the planner: the returned JSON segments
are re-simulated with scipy's DOP853 from the sympy fields, sampled densely,
and the trident snake's outline (hand formulas of MATH.md §8) is tested
against the obstacles with matplotlib's point-in-polygon and plain distances
(not shapely, which the planner uses).
"""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.path import Path as MplPath

import nilpotent.cli.cmd_plan  # noqa: F401  (registers the command)
from nilpotent.core.model.modelfile import system_from_dict, system_to_dict
from nilpotent.core.model.outline import Limits
from nilpotent.errors import ComputationLimitError, ModelError, PlanningError, WorldError
from nilpotent.models import get_model
from nilpotent.models.trident import TridentGeometry
from nilpotent.planning.global_planner import plan_global, plan_json
from nilpotent.planning.verify import Checker
from nilpotent.planning.world import World, world_from_dict
from replay import resimulate

ALPHA = (0.0, 2 * math.pi / 3, 4 * math.pi / 3)
ROOM = Path(__file__).resolve().parents[1] / "src/nilpotent/planning/worlds/room.toml"

UNICYCLE = {
    "coordinates": ["x", "y", "theta"],
    "fields": [{"x": "cos(theta)", "y": "sin(theta)"}, {"theta": 1}],
}


# --- independent re-simulation and geometry ----------------------------------------

def trident_points(q: np.ndarray, r: float = 1.0, l: float = 1.0, per_edge: int = 25):
    """Points on the body's edges, the legs and the wheels (MATH.md §8), and the triangles."""
    x, y, th = q[:, 0], q[:, 1], q[:, 2]
    verts = np.stack([np.stack([x + r * np.cos(th + a), y + r * np.sin(th + a)], -1)
                      for a in ALPHA], 1)                      # (N, 3, 2)
    psi = th[:, None] + np.array(ALPHA) + q[:, 3:6]
    wheels = verts + l * np.stack([np.cos(psi), np.sin(psi)], -1)
    s = np.linspace(0, 1, per_edge)[None, :, None]
    pts = []
    for i in range(3):
        a, b = verts[:, i][:, None], verts[:, (i + 1) % 3][:, None]
        pts.append(a + s * (b - a))
        pts.append(a + s * (wheels[:, i][:, None] - a))
    return np.concatenate(pts, axis=1), verts               # (N, P, 2), (N, 3, 2)


def distance_to_polygon(points: np.ndarray, corners) -> np.ndarray:
    """0 inside, else the distance to the nearest edge (projection on each segment)."""
    poly = np.asarray(corners, dtype=float)
    best = np.full(len(points), np.inf)
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        t = np.clip(((points - a) @ (b - a)) / ((b - a) @ (b - a)), 0, 1)
        best = np.minimum(best, np.linalg.norm(points - (a + t[:, None] * (b - a)), axis=1))
    best[MplPath(poly).contains_points(points)] = 0.0
    return best


def independent_collision_free(q: np.ndarray, world_dict: dict, margin: float = 0.0) -> bool:
    """No sampled point of the outline within ``margin`` of an obstacle, inside the bounds."""
    pts, verts = trident_points(q)
    flat = pts.reshape(-1, 2)
    for ob in world_dict.get("obstacles", []):
        if "polygon" in ob:
            if (distance_to_polygon(flat, ob["polygon"]) <= margin).any():
                return False
            for corner in ob["polygon"]:  # an obstacle corner inside the body triangle
                for tri in verts:
                    if MplPath(tri).contains_point(corner):
                        return False
        else:
            c = np.asarray(ob["disc"]["center"])
            if (np.linalg.norm(flat - c, axis=1) <= ob["disc"]["radius"] + margin).any():
                return False
            if any(MplPath(tri).contains_point(c) for tri in verts):
                return False
    if "bounds" in world_dict:
        (xlo, xhi), (ylo, yhi) = world_dict["bounds"]["x"], world_dict["bounds"]["y"]
        if not ((flat[:, 0] >= xlo) & (flat[:, 0] <= xhi) & (flat[:, 1] >= ylo)
                & (flat[:, 1] <= yhi)).all():
            return False
    return True


# --- limits and outlines -----------------------------------------------------------

def test_model_file_limits_and_geometry_round_trip():
    data = dict(UNICYCLE, limits={"theta": [-1, "pi/2"]},
                geometry={"discs": [{"center": ["x", "y"], "radius": "0.2"}],
                          "segments": [{"from": ["x", "y"],
                                        "to": ["x + cos(theta)", "y + sin(theta)"]}]})
    s = system_from_dict(data, default_name="u")
    assert s.limits.as_dict() == {"theta": (-1.0, math.pi / 2)}
    assert len(s.geometry.discs) == 1 and len(s.geometry.segments) == 1
    back = system_from_dict(system_to_dict(s))
    assert back.limits == s.limits and back.geometry == s.geometry


@pytest.mark.parametrize(
    "extra, text",
    [
        ({"limits": {"z": [0, 1]}}, "not a coordinate"),
        ({"limits": {"x": [1, 0]}}, "above the upper bound"),
        ({"limits": {"x": [0]}}, "pair"),
        ({"geometry": {"polygons": [{"points": [["x", "y"], ["x", "1"]]}]}}, "at least 3"),
        ({"geometry": {"blobs": []}}, "unknown key"),
        # a constant of the outline beyond a double (was OverflowError, exit 70) or huge
        ({"geometry": {"discs": [{"center": ["x", "1" + "0" * 400], "radius": "0.1"}]}},
         r"center\[1\].*finite"),
        ({"geometry": {"segments": [{"from": ["x", "y"], "to": ["2e7", "y"]}]}},
         r"segments\[0\]\.to\[0\].*magnitude"),
        ({"geometry": {"discs": [{"center": ["x", "y"], "radius": "-1"}]}}, "radius"),
    ],
)
def test_model_file_bad_limits_or_geometry(extra, text):
    with pytest.raises(ModelError, match=text):
        system_from_dict(dict(UNICYCLE, **extra), default_name="u")


def test_geometry_expression_outside_grammar_is_refused():
    data = dict(UNICYCLE, geometry={"discs": [{"center": ["__import__('os')", "y"],
                                               "radius": "1"}]})
    with pytest.raises(Exception, match="geometry"):
        system_from_dict(data, default_name="u")


def test_trident_default_limit_is_the_leg_along_an_edge():
    """At φ1 = 5π/6 leg 1 lies along the edge V1→V2 (derived by hand: interior angle π/3)."""
    s = get_model("trident-snake")
    bound = s.limits.as_dict()["phi1"][1]
    assert bound == pytest.approx(5 * math.pi / 6)
    g = TridentGeometry()
    q = np.array([0.3, -0.2, 0.7, bound, 0, 0])
    v = g.vertices(q)
    leg = g.wheels(q)[0] - v[0]
    edge = v[1] - v[0]
    assert abs(leg[0] * edge[1] - leg[1] * edge[0]) < 1e-12 and leg @ edge > 0
    # a bit more and a point of the leg is inside the body
    q[3] = bound + 0.05
    inside = g.vertices(q)[0] + 0.3 * (g.wheels(q)[0] - g.vertices(q)[0])
    assert MplPath(g.vertices(q)).contains_point(inside)


def test_limits_tighten_never_widen():
    lim = Limits((("a", -1.0, 1.0),))
    assert lim.tightened({"a": (-2.0, 0.5), "b": (0.0, 1.0)}).as_dict() == {
        "a": (-1.0, 0.5), "b": (0.0, 1.0)}
    with pytest.raises(ModelError):
        lim.tightened({"a": (2.0, 3.0)})


def test_with_parameters_keeps_limits_and_outline():
    s = get_model("trident-snake", {"l": 2})
    assert s.limits and s.geometry is not None
    c = Checker(s)
    # wheel 1 at (r + l, 0) = (3, 0): check through the robot's points
    pts = c.robot.points(np.zeros((1, 6)))
    assert np.allclose(pts["discs"][0, 0], [3.0, 0.0])


# --- worlds --------------------------------------------------------------------------

def test_world_clearance_matches_hand_distances():
    w = world_from_dict({"bounds": {"x": [-10, 10], "y": [-10, 10]},
                         "obstacles": [{"polygon": [[2, -1], [3, -1], [3, 1], [2, 1]]},
                                       {"disc": {"center": [0, 5], "radius": 1}}]})
    import shapely

    pts = shapely.points([[0, 0], [2.5, 0], [0, 3], [9, 0]])
    # (0,0): square at 2, disc at 5-1=4, bounds at 10 -> 2; inside square -> 0;
    # (0,3): disc 1, square sqrt(4+4); (9,0): bound at 1, square 6
    assert np.allclose(w.clearance(pts), [2.0, 0.0, 1.0, 1.0])


@pytest.mark.parametrize(
    "data, text",
    [
        ({"bounds": {"x": [1, 0], "y": [0, 1]}}, "lo < hi"),
        ({"obstacles": [{"disc": {"center": [0, 0], "radius": -1}}]}, "radius"),
        ({"obstacles": [{"polygon": [[0, 0], [1, 1]]}]}, "3 points"),
        ({"obstacles": [{"polygon": [[0, 0], [1, 1], [1, 0], [0, 1]]}]}, "simple polygon"),
        ({"walls": []}, "unknown key"),
    ],
)
def test_bad_worlds(data, text):
    with pytest.raises(WorldError, match=text):
        world_from_dict(data)


@settings(max_examples=30, deadline=None)
@given(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3.14, 3.14),
       st.lists(st.floats(-2.6, 2.6), min_size=3, max_size=3))
def test_checker_agrees_with_independent_geometry(x, y, th, phis):
    world = {"bounds": {"x": [-6, 6], "y": [-6, 6]},
             "obstacles": [{"polygon": [[1, 1], [2, 1], [2, 2], [1, 2]]},
                           {"disc": {"center": [-2, -1], "radius": 0.5}}]}
    c = Checker(get_model("trident-snake"), world_from_dict(world))
    q = np.array([[x, y, th, *phis]])
    clear = float(c.measures(q)[0][0])
    if clear > 0.05:  # clearly free: the sampled points must be free too
        assert independent_collision_free(q, world)
    elif clear <= 0:
        assert not independent_collision_free(q, world, margin=0.05)


# --- global plans ---------------------------------------------------------------------

# the straight motion to x = 4.5 would hit the post with leg 2 (wheel 2 at (x - 1, √3))
SMALL_WORLD = {
    "name": "post",
    "bounds": {"x": [-4.0, 8.0], "y": [-4.0, 4.0]},
    "obstacles": [{"disc": {"center": [2.2, 1.9], "radius": 0.3}}],
}


def test_plan_around_an_obstacle_is_verified_independently(run_cli, tmp_path):
    wfile = tmp_path / "post.toml"
    wfile.write_text(
        'name = "post"\n[bounds]\nx = [-4.0, 8.0]\ny = [-4.0, 4.0]\n'
        "[[obstacles]]\ndisc = { center = [2.2, 1.9], radius = 0.3 }\n"
    )
    status, out, _ = run_cli("plan", "trident-snake", "--to", "x=4.5,y=0.3,theta=0.2",
                             "--world", str(wfile), "--tol", "1e-7", "--clearance", "0.05",
                             "--time-limit", "900", "--json")
    assert status == 0, out
    data = json.loads(out)
    assert data["schema"] == "nilpotent/plan@1" and data["world"] == "post"
    assert data["clearance"] > 0.05 and data["limits_ok"] is True
    assert data["limits"]["phi1"] == pytest.approx([-5 * math.pi / 6, 5 * math.pi / 6])
    assert data["waypoints"][0] == data["from"] and data["waypoints"][-1] == data["to"]
    assert data["route"] == "global"
    q = resimulate(get_model("trident-snake"), data["from"], data["segments"])
    assert np.linalg.norm(q[-1] - np.array(data["to"])) <= 1e-6
    assert independent_collision_free(q, SMALL_WORLD, margin=0.04)
    assert np.all(np.abs(q[:, 3:6]) <= 5 * math.pi / 6 + 1e-9)


def test_far_goal_without_world_keeps_legs_within_limits(run_cli):
    """The issue's example: x=3, y=1 once turned the legs by 9 rad; now |φ_i| ≤ 1.2."""
    # a limit far above the ~25 s it takes here: the test is about the legs, not speed
    args = ["plan", "trident-snake", "--to", "x=3,y=1", "--time-limit", "900", "--json"]
    for i in (1, 2, 3):
        args += ["--limit", f"phi{i}=-1.2:1.2"]
    status, out, _ = run_cli(*args)
    assert status == 0, out
    data = json.loads(out)
    q = resimulate(get_model("trident-snake"), data["from"], data["segments"])
    assert np.abs(q[:, 3:6]).max() <= 1.2 + 1e-7
    assert np.linalg.norm(q[-1] - np.array([3, 1, 0, 0, 0, 0])) <= 1e-7
    # the body stays near the straight path (no overshoot to x = 5 as before)
    assert q[:, 0].max() < 4.0 and np.abs(q[:, 1]).max() < 2.0
    assert data["clearance"] is None and "clearance" in data["null_reasons"]
    assert data["limits_ok"] is True


def test_small_problem_keeps_the_direct_route():
    s = get_model("trident-snake")
    g = plan_global(s, (0,) * 6, (0.1, -0.05, 0.1, 0.2, 0, 0))
    assert g.route == "direct" and len(g.pieces) == 1 and g.error <= 1e-8


def test_singular_margin_is_kept_for_the_joint_form():
    s = get_model("trident-snake-joints")
    start = (0, 0, 0, 0.3, -0.2, 0.1)
    goal = (0.05, 0.02, 0.03, 0.35, -0.15, 0.12)
    g = plan_global(s, start, goal, 1e-8, singular_margin=0.5)
    assert g.verification.min_singular_margin >= 0.5
    geom = TridentGeometry()
    # independent: det M from its rows (MATH.md §8)
    q = g.plan.trajectory.states
    psi = q[:, 2:3] + np.array(ALPHA) + q[:, 3:6]
    rows = np.stack([-np.sin(psi), np.cos(psi), geom.r * np.cos(q[:, 3:6]) + geom.l], -1)
    assert np.abs(np.linalg.det(rows)).min() >= 0.5 - 1e-9


def test_singular_margin_refused_where_undefined():
    from nilpotent.errors import OptionError

    with pytest.raises(OptionError, match="singular margin"):
        plan_global(get_model("trident-snake"), (0,) * 6, (0.1, 0, 0, 0, 0, 0),
                    singular_margin=0.1)


def test_blocked_goal_and_time_limit_raise_planning_error():
    world = World("walled", ((-5.0, 5.0), (-5.0, 5.0)),
                  (((2.5, -5.0), (3.0, -5.0), (3.0, 5.0), (2.5, 5.0)),))
    s = get_model("trident-snake")
    with pytest.raises(PlanningError, match="not admissible"):
        plan_global(s, (0,) * 6, (2.7, 0, 0, 0, 0, 0), world=world)
    with pytest.raises((PlanningError, ComputationLimitError)):
        plan_global(s, (0,) * 6, (4.2, 0, 0, 0, 0, 0), world=world, time_limit=1.0)


def test_cli_failure_writes_nothing(run_cli, tmp_path):
    png = tmp_path / "p.png"
    status, out, _ = run_cli("plan", "trident-snake", "--to", "x=9,y=-2",
                             "--world", str(ROOM), "--time-limit", "0.5",
                             "--plot", str(png), "--json")
    assert status == 2
    # OMPL finding no path in its share, or the time limit itself running out
    assert json.loads(out)["error"]["kind"] in ("planning", "computation-limit")
    assert not png.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("text", ["phi1=1", "phi1=2:1", "nope=0:1", "phi1=a:1"])
def test_bad_limit_options(run_cli, text):
    status, out, _ = run_cli("plan", "trident-snake", "--to", "x=0.1", "--limit", text, "--json")
    assert status == 2 and "error" in json.loads(out)


def test_plan_json_replaces_non_finite_numbers_and_says_why():
    out = plan_json({"a": [1.0, math.nan], "iterations": [{"distance": math.inf}],
                     "clearance": None}, {"clearance": "no world"})
    assert out["a"] == [1.0, None] and out["iterations"][0]["distance"] is None
    assert "iterations[0].distance" in out["undefined"]["paths"]
    assert out["null_reasons"] == {"clearance": "no world"}
    json.dumps(out, allow_nan=False)


def test_plan_figures(tmp_path):
    from nilpotent.viz.plan_world import animate_plan_world, plot_plan_world

    s = get_model("trident-snake")
    g = plan_global(s, (0,) * 6, (0.5, 0.1, 0, 0, 0, 0), world=world_from_dict(SMALL_WORLD))
    fig = plot_plan_world(g)
    fig.savefig(tmp_path / "p.png")
    assert (tmp_path / "p.png").stat().st_size > 0
    assert animate_plan_world(g, tmp_path / "a.html", frames=4) == 4
    assert "player-selfcheck" in (tmp_path / "a.html").read_text()


# --- closed-loop execution --------------------------------------------------------------

@pytest.mark.slow
def test_closed_loop_reaches_1e3_with_mismatch_where_open_loop_misses(run_cli):
    status, out, _ = run_cli("execute", "trident-snake", "--to", "x=0.3,y=0.1,theta=0.2,phi1=0.1",
                             "--mismatch", "r=0.05,l=-0.05", "--noise", "1e-5", "--seed", "2",
                             "--time-limit", "900", "--json")
    assert status == 0, out
    data = json.loads(out)
    assert data["schema"] == "nilpotent/execution@1" and data["success"] is True
    assert data["closed_loop"]["violations"] == []
    # independent: the applied controls on the true robot (r = 1.05, l = 0.95) by scipy
    true = get_model("trident-snake", {"r": sp.Rational(105, 100), "l": sp.Rational(95, 100)})
    q = resimulate(true, data["from"], data["closed_loop"]["segments"], samples=40)
    goal = np.array(data["to"])
    assert np.linalg.norm(q[-1] - goal) <= 1e-3
    assert np.abs(q[:, 3:6]).max() <= 5 * math.pi / 6
    assert data["open_loop"]["error"] > 10 * data["closed_loop"]["error"]
    assert data["open_loop"]["error"] > 1e-2


def test_mismatch_options_are_checked(run_cli):
    for bad in ("q=0.1", "r=-1", "r", "r=-0.99", "r=1e6"):
        status, out, _ = run_cli("execute", "trident-snake", "--to", "x=0.1",
                                 "--mismatch", bad, "--json")
        assert status == 2 and "error" in json.loads(out)


def test_car_trailers_outline_matches_the_documented_sizes():
    """Car: 0.1 behind to 0.7 ahead of (x, y), 0.5 wide; trailer 1 at (x − d1, y) when all
    headings are 0: 0.2 behind to 0.3 ahead, 0.4 wide; hitch bar between the axle centres."""
    s = get_model("car-trailers:1", {"d1": 2})
    pts = Checker(s).robot.points(np.array([[1.0, 2.0, 0.0, 0.0]]))
    car, trailer = (np.asarray(p[0]) for p in pts["polygons"])
    assert np.allclose(sorted(map(tuple, car)),
                       sorted([(0.9, 1.75), (1.7, 1.75), (1.7, 2.25), (0.9, 2.25)]))
    assert np.allclose(sorted(map(tuple, trailer)),
                       sorted([(-1.2, 1.8), (-0.7, 1.8), (-0.7, 2.2), (-1.2, 2.2)]))
    assert np.allclose(pts["segments"][0, 0], [[-1.0, 2.0], [1.0, 2.0]])


def test_example_room_world_loads():
    from nilpotent.planning.world import load_world

    w = load_world(ROOM)
    assert w.name == "room" and w.bounds == ((-5.0, 13.0), (-6.0, 6.0))
    assert len(w.polygons) == 2 and len(w.discs) == 1


def test_user_model_file_with_outline_plans_around_a_disc(run_cli, tmp_path):
    """A unicycle of radius 0.2 (model file [geometry]) passes a post of radius 0.3."""
    model = tmp_path / "bot.toml"
    model.write_text(
        'coordinates = ["x", "y", "theta"]\n'
        "[parameters]\nrho = 0.2\n"
        '[[fields]]\nx = "cos(theta)"\ny = "sin(theta)"\n'
        '[[fields]]\ntheta = "1"\n'
        '[limits]\ntheta = ["-pi/2", "pi/2"]\n'
        '[[geometry.discs]]\ncenter = ["x", "y"]\nradius = "rho"\n'
    )
    world = tmp_path / "w.toml"
    world.write_text('[bounds]\nx = [-1.0, 3.0]\ny = [-1.5, 1.5]\n'
                     "[[obstacles]]\ndisc = { center = [1.0, 0.0], radius = 0.3 }\n")
    status, out, _ = run_cli("plan", str(model), "--to", "x=2", "--world", str(world),
                             "--tol", "1e-6", "--json")
    assert status == 0, out
    data = json.loads(out)
    q = resimulate(system_from_dict(
        {"coordinates": ["x", "y", "theta"], "parameters": {"rho": 0.2},
         "fields": [{"x": "cos(theta)", "y": "sin(theta)"}, {"theta": "1"}]}),
        data["from"], data["segments"])
    assert np.linalg.norm(q[-1] - np.array([2.0, 0, 0])) <= 1e-5
    assert (np.hypot(q[:, 0] - 1.0, q[:, 1]) > 0.5).all()        # 0.3 + 0.2
    assert (np.abs(q[:, 2]) <= math.pi / 2 + 1e-9).all()
    assert data["clearance"] > 0 and data["world"] == "w"


# --- global path with the shape held; single-configuration checks ---------------------------

DOORWAY = {
    "name": "doorway",
    "bounds": {"x": [-6.0, 10.0], "y": [-5.0, 5.0]},
    "obstacles": [
        {"polygon": [[1.7, -5.0], [2.3, -5.0], [2.3, -2.3], [1.7, -2.3]]},
        {"polygon": [[1.7, 2.3], [2.3, 2.3], [2.3, 5.0], [1.7, 5.0]]},
    ],
}


def test_shape_coordinates_are_the_limited_non_position_ones():
    from nilpotent.planning.global_planner import shape_indices

    trident = Checker(get_model("trident-snake"))
    names = trident.system.coordinate_names
    assert [names[j] for j in shape_indices(trident)] == ["phi1", "phi2", "phi3"]
    assert shape_indices(Checker(get_model("car-trailers:1"))) == ()
    # a user limit on x does not make x a shape coordinate; one on theta does
    lim = Checker(get_model("trident-snake")).limits.tightened(  # type: ignore[union-attr]
        {"x": (-1.0, 1.0), "theta": (-1.0, 1.0)})
    assert [names[j] for j in shape_indices(Checker(get_model("trident-snake"), limits=lim))] \
        == ["theta", "phi1", "phi2", "phi3"]


def test_held_ompl_path_keeps_the_shape_and_is_admissible():
    from nilpotent.planning.holonomic_path import ompl_path

    checker = Checker(get_model("trident-snake"), world_from_dict(DOORWAY))
    start = np.array([-3.0, 2.5, 0.4, 0.3, -0.2, 0.1])
    goal = np.array([6.0, -2.5, -1.0, 0.3, -0.2, 0.1])
    path = ompl_path(checker, start, goal, 20.0, seed=1, held=(3, 4, 5))
    assert np.allclose(path[0], start) and np.allclose(path[-1], goal)
    for q in path:
        assert np.array_equal(q[3:], start[3:])
    for a, b in itertools.pairwise(path):
        t = np.linspace(0, 1, 400)[:, None]
        chord = a + t * (b - a)
        assert checker.valid(chord).all()
        assert independent_collision_free(chord, DOORWAY)
    with pytest.raises(ValueError, match="held"):
        ompl_path(checker, start, goal + np.array([0, 0, 0, 0.1, 0, 0]), 1.0, held=(3,))


def test_shape_held_path_changes_the_shape_only_at_the_goal_pose():
    from nilpotent.planning.global_planner import shape_held_path

    checker = Checker(get_model("trident-snake"), world_from_dict(DOORWAY))
    start = np.array([-3.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    goal = np.array([6.0, 1.0, 0.5, 0.4, -0.3, 0.2])
    path = shape_held_path(checker, start, goal, 20.0, 0, checker.valid, (3, 4, 5))
    assert np.allclose(path[-1], goal)
    for q in path[:-1]:
        assert np.array_equal(q[3:], start[3:])
    assert np.allclose(path[-2][:3], goal[:3])  # the shape changes at the goal's pose
    # a goal whose pose with the start's shape is inside the wall: refused, not guessed
    wall_goal = np.array([2.0, 3.5, 0.0, 0.0, 0.0, 0.0])
    with pytest.raises(PlanningError, match="not admissible"):
        shape_held_path(checker, start, wall_goal, 1.0, 0, checker.valid, (3, 4, 5))


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-4.0, 4.0), min_size=6, max_size=6),
       st.lists(st.floats(0.1, 3.0), min_size=3, max_size=3))
def test_limit_margin_is_the_distance_to_the_nearest_bound(q, half):
    lim = Limits(tuple((f"phi{i + 1}", -h, h) for i, h in enumerate(half)))
    checker = Checker(get_model("trident-snake"), limits=lim)
    margin = float(checker.robot.limit_margin(np.array([q]))[0])
    expected = min(min(q[3 + i] + h, h - q[3 + i]) for i, h in enumerate(half))
    assert margin == pytest.approx(expected)


@pytest.mark.slow
def test_doorway_plan_keeps_legs_straight_and_is_verified_independently():
    """Legs straight at both ends: the global path never bends them, and the plan
    re-simulated with scipy is collision-free, within the limits and at the goal."""
    world = world_from_dict(DOORWAY)
    s = get_model("trident-snake")
    start = (-3.0, 2.0, 0.5, 0.0, 0.0, 0.0)
    goal = (6.5, -2.0, -2.0, 0.0, 0.0, 0.0)
    g = plan_global(s, start, goal, 1e-6, world=world, time_limit=900, seed=3)
    assert np.abs(np.array(g.waypoints)[:, 3:]).max() == 0.0
    data = g.to_json()
    q = resimulate(s, data["from"], data["segments"], samples=60)
    assert np.linalg.norm(q[-1] - np.array(goal)) <= 1e-6
    assert np.all(np.abs(q[:, 3:6]) <= 5 * math.pi / 6 + 1e-9)
    assert independent_collision_free(q, DOORWAY)


def test_outline_constant_bound_is_the_point_magnitude():
    from nilpotent.core.model.outline import MAX_CONSTANT
    from nilpotent.core.model.points import MAX_MAGNITUDE

    assert MAX_CONSTANT == MAX_MAGNITUDE
