"""Self-collision and relative limits (issue 20, item 2): model files, built-ins, checker,
planner, verification, execute.

Every check of a plan or a sample is independent of the code under test: the car and
trailer rectangles and the trident's legs are rebuilt here from their definitions
(:mod:`nilpotent.models.outlines` module doc) with plain shapely, and plans are
re-simulated here with scipy from the model's equations written out by hand.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
import shapely
from scipy.integrate import solve_ivp

from nilpotent.core.model.modelfile import (
    dump_model_file,
    load_model_file,
    system_from_dict,
    system_to_dict,
)
from nilpotent.core.model.outline import Limits
from nilpotent.errors import ExpressionError, ModelError, PlanningError
from nilpotent.models import get_model
from nilpotent.models.outlines import HITCH_LIMIT
from nilpotent.planning.verify import Checker
from nilpotent.planning.world import load_world

PARKING = "examples/worlds/parking.toml"


# --- independent geometry ----------------------------------------------------------------

def _rect(px: float, py: float, th: float, behind: float, ahead: float, width: float):
    c, s, h = math.cos(th), math.sin(th), width / 2
    return shapely.Polygon([(px + a * c - b * s, py + a * s + b * c)
                            for a, b in ((-behind, -h), (ahead, -h), (ahead, h), (-behind, h))])


def _train(q, d=None):
    """Car and trailer rectangles of car-trailers:K at ``q`` (car 0.1 behind / 0.7 ahead of
    its axle, 0.5 wide; trailers 0.2 / 0.3, 0.4 wide; axle P_i = P_{i-1} - d_i e(θ_i))."""
    x, y, th = q[0], q[1], list(q[2:])
    k = len(th) - 1
    d = d or [1.0] * k
    axles = [(x, y)]
    for i in range(1, k + 1):
        px, py = axles[-1]
        axles.append((px - d[i - 1] * math.cos(th[i]), py - d[i - 1] * math.sin(th[i])))
    return [_rect(x, y, th[0], 0.1, 0.7, 0.5)] + [
        _rect(*axles[i], th[i], 0.2, 0.3, 0.4) for i in range(1, k + 1)]


def _train_self_collides(q) -> bool:
    bodies = _train(q)
    return any(bodies[i].intersects(bodies[j])
               for i in range(len(bodies)) for j in range(i + 1, len(bodies)))


def _legs_cross(q, r=1.0, l=1.0) -> bool:
    """Two legs of trident-snake (vertex angles 0, 2π/3, 4π/3) touch at ``q``."""
    x, y, th, *phi = q
    legs = []
    for a, p in zip((0.0, 2 * math.pi / 3, 4 * math.pi / 3), phi, strict=True):
        vx, vy = x + r * math.cos(th + a), y + r * math.sin(th + a)
        legs.append(shapely.LineString([(vx, vy), (vx + l * math.cos(th + a + p),
                                                   vy + l * math.sin(th + a + p))]))
    return any(legs[i].intersects(legs[j]) for i in range(3) for j in range(i + 1, 3))


def _car_trailers_1_field(q, u):
    _, _, t0, t1 = q
    return [math.cos(t0) * u[0], math.sin(t0) * u[0], u[1], math.sin(t0 - t1) * u[0]]


def _inputs(seg, t):
    w = seg["omega"]
    out = []
    for s in seg["inputs"]:
        v = s["constant"]
        v += sum(c * math.cos((k + 1) * w * t) for k, c in enumerate(s["cos"]))
        v += sum(c * math.sin((k + 1) * w * t) for k, c in enumerate(s["sin"]))
        out.append(v)
    return out


def _resimulate(start, segments, per_segment=200):
    """Dense samples of the motion of car-trailers:1 under the JSON segments (scipy)."""
    q = np.array(start, dtype=float)
    samples = [q]
    for seg in segments:
        t_eval = np.linspace(0.0, seg["duration"], per_segment)
        sol = solve_ivp(lambda t, z, seg=seg: _car_trailers_1_field(z, _inputs(seg, t)),
                        (0.0, seg["duration"]), q, t_eval=t_eval, rtol=1e-10, atol=1e-12)
        samples.extend(sol.y.T[1:])
        q = sol.y[:, -1]
    return np.array(samples)


# --- model files ---------------------------------------------------------------------------

GOOD = {
    "coordinates": ["x", "y", "a", "b"],
    "parameters": {"l": 1.0},
    "fields": [{"x": "cos(a)", "y": "sin(a)", "b": "sin(a - b)/l"}, {"a": 1}],
    "limits": {"b": [-3.0, 3.0]},
    "relative_limits": {"a - b": [-1.2, "6/5"]},
    "geometry": {
        "self_collision": [["front", "back"]],
        "polygons": [
            {"points": [["x", "y"], ["x + 0.5*cos(a)", "y + 0.5*sin(a)"],
                        ["x - 0.2*sin(a)", "y + 0.2*cos(a)"]], "body": "front"},
            {"points": [["x - l*cos(b)", "y - l*sin(b)"], ["x - 1.3*l*cos(b)", "y - 1.3*l*sin(b)"],
                        ["x - l*cos(b) - 0.2*sin(b)", "y - l*sin(b) + 0.2*cos(b)"]],
             "body": "back"},
        ],
        "segments": [{"from": ["x", "y"], "to": ["x - l*cos(b)", "y - l*sin(b)"]}],
    },
}


def test_model_file_reads_bodies_pairs_and_relative_limits(tmp_path):
    s = system_from_dict(GOOD, "good.toml")
    assert s.limits.as_dict() == {"b": (-3.0, 3.0)}
    assert s.limits.relative_dict() == {"a - b": (-1.2, 1.2)}
    assert s.geometry is not None
    assert s.geometry.bodies == ("front", "back", None)
    assert s.geometry.self_collision == (("front", "back"),)
    assert s.geometry.self_collision_parts() == ((0, 1),)
    for suffix in (".toml", ".json"):  # written and read back: the same entries
        path = tmp_path / f"m{suffix}"
        dump_model_file(s, path)
        back = load_model_file(path)
        assert back.limits.relative_dict() == s.limits.relative_dict()
        assert back.geometry is not None
        assert back.geometry.bodies == s.geometry.bodies
        assert back.geometry.self_collision == s.geometry.self_collision
    # "all": every pair of distinct bodies
    data = json.loads(json.dumps(GOOD))
    data["geometry"]["segments"][0]["body"] = "bar"
    data["geometry"]["self_collision"] = "all"
    g = system_from_dict(data, "all.toml").geometry
    assert g is not None
    assert set(map(frozenset, g.self_collision)) == {
        frozenset(p) for p in (("front", "back"), ("front", "bar"), ("back", "bar"))}


def test_the_checker_uses_a_files_relative_limit_and_pairs():
    s = system_from_dict(GOOD, "good.toml")
    c = Checker(s)
    ok = c.valid(np.array([[0, 0, 0.0, 0.0], [0, 0, 1.3, 0.0], [0, 0, 0.0, -1.3]]))
    assert ok.tolist() == [True, False, False]
    assert "a - b = 1.3 outside" in c.why_invalid([0, 0, 1.3, 0.0])


@pytest.mark.parametrize(("edit", "needle"), [
    (lambda d: d["geometry"].__setitem__("self_collision", [["front", "nose"]]),
     "self_collision[0]: no body named 'nose'"),
    (lambda d: d["geometry"].__setitem__("self_collision", [["front", "front"]]),
     "pairs a body with itself"),
    (lambda d: d["geometry"].__setitem__("self_collision", [["front", "back"], ["back", "front"]]),
     "given twice"),
    (lambda d: d["geometry"].__setitem__("self_collision", "some"), "geometry.self_collision"),
    (lambda d: d["geometry"].__setitem__("self_collision", [["front"]]), "self_collision[0]"),
    (lambda d: d["geometry"]["polygons"][0].__setitem__("body", 3), "polygons[0].body"),
    (lambda d: d["geometry"]["polygons"][0].__setitem__("color", "red"), "polygons[0]"),
    (lambda d: d.__setitem__("relative_limits", {"a - l": [-1, 1]}), "relative_limits"),
    (lambda d: d.__setitem__("relative_limits", {"2*pi": [-1, 1]}), "is a constant"),
    (lambda d: d.__setitem__("relative_limits", {"a - b": [1, -1]}), "above the upper bound"),
    (lambda d: d.__setitem__("relative_limits", {"a - b": [1]}), "a pair [lo, hi]"),
    (lambda d: d.__setitem__("relative_limits", {"a - b": [-1, 1], "-b + a": [-2, 2]}),
     "the same expression"),
    (lambda d: d.__setitem__("relative_limits", {"__import__('os')": [-1, 1]}),
     "relative_limits"),
    (lambda d: d.__setitem__("relative_limits", [1, 2]), "relative_limits must be a table"),
])
def test_bad_entries_are_refused_naming_the_entry(edit, needle):
    data = json.loads(json.dumps(GOOD))
    edit(data)
    with pytest.raises((ModelError, ExpressionError)) as err:
        system_from_dict(data, "bad.toml")
    assert needle in str(err.value)
    assert "bad.toml" in str(err.value)


def test_a_bad_entry_exits_2_on_the_command_line(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('coordinates = ["x", "y"]\n[[fields]]\nx = "1"\n[[fields]]\ny = "1"\n'
                    '[relative_limits]\n"x - z" = [-1, 1]\n', encoding="utf-8")
    run = subprocess.run([sys.executable, "-m", "nilpotent", "analyze", str(path)],
                         capture_output=True, text=True, env=os.environ, timeout=120)
    assert run.returncode == 2, run.stderr
    assert "relative_limits" in run.stderr and "Traceback" not in run.stderr


def test_old_model_files_read_exactly_as_before():
    old = json.loads(json.dumps(GOOD))
    del old["relative_limits"], old["geometry"]["self_collision"]
    for poly in old["geometry"]["polygons"]:
        del poly["body"]
    s = system_from_dict(old, "old.toml")
    assert s.limits.relative == () and s.limits.as_dict() == {"b": (-3.0, 3.0)}
    assert s.geometry is not None
    assert s.geometry.bodies == () and s.geometry.self_collision == ()
    written = system_to_dict(s)
    assert set(written) == {"name", "coordinates", "parameters", "fields", "limits", "geometry"}
    assert set(written["geometry"]) == {"polygons", "segments"}
    assert all(set(p) == {"points"} for p in written["geometry"]["polygons"])
    assert Checker(s).robot.has_self_collision is False  # type: ignore[attr-defined]


# --- built-ins -----------------------------------------------------------------------------

def test_builtin_car_trailers_ship_hitch_limits_and_pairs():
    for k in (1, 2, 3):
        m = get_model(f"car-trailers:{k}")
        rel = m.limits.relative_dict()
        assert rel == {f"theta{i - 1} - theta{i}": (-HITCH_LIMIT, HITCH_LIMIT)
                       for i in range(1, k + 1)}
        g = m.geometry
        assert g is not None
        pairs = {frozenset(p) for p in g.self_collision}
        vehicles = ["car", *(f"trailer{i}" for i in range(1, k + 1))]
        for i, a in enumerate(vehicles):
            for b in vehicles[i + 1:]:
                assert frozenset((a, b)) in pairs
        for i in range(1, k + 1):  # a hitch never against the two bodies it joins
            assert frozenset((f"hitch{i}", vehicles[i - 1])) not in pairs
            assert frozenset((f"hitch{i}", vehicles[i])) not in pairs
    # the straight train is admissible: no pair touches by construction
    m = get_model("car-trailers:3")
    assert Checker(m).valid(np.zeros((1, 6)))[0]


def test_the_hitch_limit_is_below_the_first_contact_of_the_rectangles():
    """Within |θ0 − θ1| ≤ 1.4 the default rectangles never meet (independent sweep), and
    1.4 stays below the jackknife π/2 where the trailer's speed cos(θ0 − θ1) vanishes."""
    assert math.pi / 2 - 0.15 > HITCH_LIMIT
    first = None
    for a in np.linspace(0.0, math.pi, 3142):
        if _train_self_collides([0.0, 0.0, 0.0, -a]):
            first = a
            break
    assert first is not None and first > HITCH_LIMIT + 0.5


@pytest.mark.parametrize("k", [1, 2])
def test_states_the_checker_admits_never_self_collide(k):
    world = load_world(PARKING)
    m = get_model(f"car-trailers:{k}")
    rng = np.random.default_rng(20 + k)
    (xlo, xhi), (ylo, yhi) = world.bounds  # type: ignore[misc]
    n = 1500
    q = np.column_stack([rng.uniform(xlo, xhi, n), rng.uniform(ylo, yhi, n),
                         rng.uniform(-math.pi, math.pi, (n, k + 1))])
    colliding = np.array([_train_self_collides(p) for p in q])
    ok = Checker(m, world).valid(q)
    assert ok.sum() > 30
    assert not np.any(colliding[ok])
    assert np.all(np.abs(np.diff(q[ok, 2:], axis=1)) <= HITCH_LIMIT)
    # self-collision alone (hitch limits dropped) still refuses every colliding state
    only = replace(m, limits=Limits(m.limits.bounds))
    ok2 = Checker(only, world).valid(q)
    assert not np.any(colliding[ok2])
    assert np.any(colliding & ~ok2)  # and there were some to refuse


def test_trident_legs_never_cross_in_admitted_states():
    m = get_model("trident-snake")
    rng = np.random.default_rng(7)
    bound = 5 * math.pi / 6
    n = 1500
    q = np.column_stack([np.zeros((n, 3)), rng.uniform(-bound, bound, (n, 3))])
    crossing = np.array([_legs_cross(p) for p in q])
    ok = Checker(m).valid(q)
    assert np.any(crossing)  # the joint limits alone admit crossing legs
    assert not np.any(crossing[ok])
    assert np.all(ok[~crossing])  # and nothing else is refused


# --- planner, verification, execute ---------------------------------------------------------

def test_the_issues_command_fails_clearly():
    """The issue's start (θ1 = 2.8 behind θ0 = 0) has the trailer in the car: exit 2."""
    run = subprocess.run(
        [sys.executable, "-m", "nilpotent", "plan", "car-trailers:1",
         "--from", "x=0,y=1,theta0=0,theta1=2.8", "--to", "x=0.2,y=1.05,theta0=0.1,theta1=2.8",
         "--world", PARKING, "--tol", "1e-6", "--json"],
        capture_output=True, text=True, env=os.environ, timeout=300)
    assert run.returncode == 2, run.stderr
    err = json.loads(run.stdout)["error"]["message"]
    assert "start is not admissible" in err
    assert "theta0 - theta1" in err and "collides with itself" in err


def test_a_hitch_limit_violation_is_refused():
    from nilpotent.planning.global_planner import plan_global

    m = get_model("car-trailers:1")
    c = Checker(m, load_world(PARKING))
    free = [0.0, 1.0, 0.0, 0.0]
    assert c.valid(np.array([free]))[0]
    for bad in ([0.0, 1.0, 1.45, 0.0], [0.0, 1.0, 0.0, 1.45]):
        assert not c.valid(np.array([bad]))[0]
        assert not _train_self_collides(bad)  # refused for the hitch limit alone
    with pytest.raises(PlanningError, match=r"goal is not admissible.*theta0 - theta1"):
        plan_global(m, free, [0.0, 1.0, 1.45, 0.0], 1e-6, world=load_world(PARKING))


@pytest.mark.slow
def test_a_parking_plan_honours_self_collision_and_hitch_limits_independently():
    run = subprocess.run(
        [sys.executable, "-m", "nilpotent", "plan", "car-trailers:1",
         "--from", "x=0,y=1,theta0=0,theta1=0", "--to", "x=0.3,y=1.1,theta0=0.2,theta1=0.1",
         "--world", PARKING, "--tol", "1e-6", "--json"],
        capture_output=True, text=True, env=os.environ, timeout=300)
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    assert out["self_collision_ok"] is True and out["self_clearance"] > 0
    assert out["relative_limits"] == {"theta0 - theta1": [-HITCH_LIMIT, HITCH_LIMIT]}
    q = _resimulate(out["from"], out["segments"])
    assert np.linalg.norm(q[-1] - np.array(out["to"])) < 1e-4
    assert not any(_train_self_collides(p) for p in q)
    assert np.all(np.abs(q[:, 2] - q[:, 3]) <= HITCH_LIMIT + 1e-9)


def test_execute_cuts_the_controls_at_a_safety_stop():
    from nilpotent.numeric.signals import InputSignal, Segment
    from nilpotent.planning.execute import _cut

    segs = [Segment(1.0, 2 * math.pi, (InputSignal(1.0),)),
            Segment(2.0, math.pi, (InputSignal(0.5, (0.1,)),))]
    cut = _cut(segs, 1.5)
    assert [s.duration for s in cut] == [1.0, 0.5]
    assert cut[1].omega == segs[1].omega and cut[1].inputs == segs[1].inputs
    assert [s.duration for s in _cut(segs, 1.0)] == [1.0]
    assert _cut(segs, 0.0) == []


def test_execute_stops_the_true_robot_before_it_leaves_a_relative_limit():
    """The true robot is 1.5× faster along x than the model: open loop it passes x − y = 1;
    closed loop the safety stop holds it at the limit and the corrections bring it back."""
    from nilpotent.planning.execute import execute_plan
    from nilpotent.planning.global_planner import plan_global

    m = system_from_dict({"coordinates": ["x", "y"], "parameters": {"k": 1.0},
                          "fields": [{"x": "k"}, {"y": 1}],
                          "relative_limits": {"x - y": [-1, 1]}}, "<shift>")
    g = plan_global(m, [0.0, 0.0], [0.9, 0.0], 1e-8)
    ex = execute_plan(g, {"k": 0.5}, tol=1e-3, max_corrections=12, time_limit=60)
    q_open = ex.open_loop.states
    assert np.max(q_open[:, 0] - q_open[:, 1]) > 1.3  # 0.9 × 1.5, far past the limit
    assert ex.open_loop_violations and not ex.open_loop.limits_ok
    q = ex.closed_loop.states
    assert np.all(np.abs(q[:, 0] - q[:, 1]) <= 1.0)
    assert ex.safety_stops >= 1 and not ex.violations
    assert ex.reached and ex.to_json()["safety_stops"] == ex.safety_stops
