"""``--planner reeds-shepp`` for ``car-trailers:1``: the trailer driven as a Reeds–Shepp car.

Independent results: the exact legs and turns at rest re-simulated by scipy (tests/replay.py)
on the model's own fields, the trailer's axle centre on a circle of the guide's radius; the
parking plan replayed by scipy, its hitch angle against the limit, its bodies against one
another (the checker's self-clearance) and the world at every dense sample.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from nilpotent.errors import OptionError
from nilpotent.models import get_model
from nilpotent.models.outlines import HITCH_LIMIT
from nilpotent.planning.global_planner import plan_global
from nilpotent.planning.guide import Leg
from nilpotent.planning.trailer_guide import (
    TRAILER_PHI,
    from_car,
    motion_pieces,
    to_car,
    trailer_exact_piece,
    trailer_geometry,
)
from nilpotent.planning.verify import Checker
from nilpotent.planning.world import load_world
from replay import resimulate

SYSTEM = get_model("car-trailers:1")


def _json(plan) -> list[dict]:
    return [s.to_dict() for s in plan.segments]


def test_car_coordinates_round_trip_and_trailer_axle():
    rng = np.random.default_rng(0)
    q = rng.uniform(-3, 3, size=(50, 4))
    s = to_car(q, 1.3)
    assert np.allclose(from_car(s, 1.3), q, atol=1e-12)
    # the trailer's axle centre is d behind the car's along theta1, phi the hitch angle
    assert np.allclose(np.hypot(q[:, 0] - s[:, 0], q[:, 1] - s[:, 1]), 1.3)
    assert np.allclose(s[:, 3], q[:, 2] - q[:, 3])


def test_geometry_of_the_built_in_model():
    g = trailer_geometry(SYSTEM, Checker(SYSTEM))
    assert g.hitch == pytest.approx(1.0)
    assert g.phi_max == pytest.approx(HITCH_LIMIT)
    assert g.phi_guide == pytest.approx(min(TRAILER_PHI, HITCH_LIMIT))
    assert g.radius == pytest.approx(1.0 / math.tan(g.phi_guide))


@pytest.mark.parametrize("phi, s1", [(0.7, 0.8), (-1.1, -0.5), (0.0, -0.9)])
def test_exact_leg_holds_the_hitch_and_circles_the_trailer(phi, s1):
    """A leg of the guide from (x1, y1, θ1) = (0.3, -0.2, 0.4) with hitch angle ``phi``:
    the scipy replay keeps θ0 − θ1 = phi and the trailer's axle on the circle of radius
    d / tan(phi) (a line for phi = 0), and ends where the closed-form arc ends."""
    checker = Checker(SYSTEM)
    g = trailer_geometry(SYSTEM, checker)
    a = np.array([0.3, -0.2, 0.4, phi])
    kappa = math.tan(phi)
    th = a[2] + kappa * s1
    if kappa:
        end = [a[0] + (math.sin(th) - math.sin(a[2])) / kappa,
               a[1] - (math.cos(th) - math.cos(a[2])) / kappa, th, phi]
    else:
        end = [a[0] + s1 * math.cos(a[2]), a[1] + s1 * math.sin(a[2]), th, phi]
    x, w = from_car(a, 1.0), from_car(np.array(end), 1.0)
    p = trailer_exact_piece(checker, x, x, w, 1e-8, 40, g)
    assert p is not None and p.error <= 1e-8
    q = resimulate(SYSTEM, x, _json(p), samples=200)
    assert np.abs(q[-1] - w).max() <= 1e-9
    c = to_car(q, 1.0)
    assert np.abs(c[:, 3] - phi).max() <= 1e-9
    if kappa:
        centre = a[:2] + np.array([-math.sin(a[2]), math.cos(a[2])]) / kappa
        assert np.abs(np.hypot(*(c[:, :2] - centre).T) - 1 / abs(kappa)).max() <= 1e-9


def test_turn_at_rest_leaves_the_trailer():
    checker = Checker(SYSTEM)
    g = trailer_geometry(SYSTEM, checker)
    x = np.array([0.5, 0.2, 0.3, 0.1])
    w = x + np.array([0.0, 0.0, 0.9, 0.0])
    p = trailer_exact_piece(checker, x, x, w, 1e-8, 40, g)
    assert p is not None
    q = resimulate(SYSTEM, x, _json(p))
    assert np.abs(q[:, [0, 1, 3]] - x[[0, 1, 3]]).max() <= 1e-12
    assert q[-1, 2] == pytest.approx(1.2, abs=1e-9)


def test_motion_pieces_of_an_arc_then_a_straight_leg():
    """An arc of radius r (left, backwards) then a straight leg, from the hitch angle 0.3 to
    -0.4: the arc's poses at atan(d / r) on the circle, the straight's at 0 on its line, the
    turns at rest (0.3 to the arc's angle, to 0, to -0.4) in steps of at most 0.05 with the
    pose fixed, consecutive pieces sharing their ends, nothing else."""
    r, d = 0.5, 1.1
    phi_g = math.atan(d / r)
    pieces = motion_pieces(np.zeros(3), [Leg(1 / r, -0.3), Leg(0.0, 0.4)], 0.3, -0.4, d,
                           step=0.02, sweep=0.05)
    assert len(pieces) == 5
    for a, b in itertools.pairwise(pieces):
        assert np.array_equal(a[-1], b[0])
    turns, arc, straight = pieces[0::2], pieces[1], pieces[3]
    assert [(t[0, 3], t[-1, 3]) for t in turns] == [(0.3, phi_g), (phi_g, 0.0), (0.0, -0.4)]
    for t in turns:
        assert np.all(np.abs(np.diff(t[:, 3])) <= 0.05 + 1e-12)
        assert np.all(t[:, :3] == t[0, :3])
    assert np.all(arc[:, 3] == phi_g) and np.all(straight[:, 3] == 0.0)
    assert np.allclose(np.hypot(arc[:, 0], arc[:, 1] - r), r)
    assert arc[-1, 2] == pytest.approx(-0.6)  # theta = kappa * s
    assert np.all(np.linalg.norm(np.diff(arc[:, :2], axis=0), axis=1) <= 0.02)
    end = np.array([r * math.sin(-0.6), r * (1 - math.cos(-0.6)), -0.6])
    assert np.allclose(arc[-1, :3], end)
    off = straight[:, :2] - end[:2]
    assert np.allclose(off[:, 0] * math.sin(-0.6) - off[:, 1] * math.cos(-0.6), 0.0)
    assert np.hypot(*(straight[-1, :2] - end[:2])) == pytest.approx(0.4)


def test_three_trailers_refused():
    with pytest.raises(OptionError, match="car-like"):
        plan_global(get_model("car-trailers:3"), (0,) * 6, (3, 1, 0, 0, 0, 0),
                    planner="reeds-shepp", time_limit=600)


@pytest.mark.slow
def test_parking_with_the_trailer_guide():
    """The third pair of benchmarks/plan_world.py's ``parking`` (rounded) parked with the
    guide: the scipy replay reaches the goal, keeps |θ0 − θ1| ≤ 1.4, its bodies apart and
    out of the obstacles at every sample, and drives a short path with few reversals
    (measured 6.86 long, 1 reversal, 165 pieces all exact; RRTConnect's path steered: 246,
    601)."""
    start, goal = (0.52, 1.09, -0.12, -0.17), (1.61, -0.59, 0.02, 0.03)
    world = load_world("parking")
    out = plan_global(SYSTEM, start, goal, 1e-6, world=world, time_limit=600,
                      planner="reeds-shepp", seed=2)
    assert out.planner == "reeds-shepp"
    q = resimulate(SYSTEM, start, _json(out.plan), samples=200)
    assert np.linalg.norm(q[-1] - np.array(goal)) <= 1e-5
    assert np.abs(q[:, 2] - q[:, 3]).max() <= HITCH_LIMIT + 1e-9
    checker = Checker(SYSTEM, world)
    assert np.all(checker.self_clearance(q) > 0)
    assert np.all(checker.measures(q)[0] > 0)
    xy = float(np.linalg.norm(np.diff(q[:, :2], axis=0), axis=1).sum())
    assert xy <= 3 * out.path_cost / math.cos(1.2) + 2  # the car drives 1/cos(phi) as far
    d = np.diff(q[:, :2], axis=0)
    along = d[:, 0] * np.cos(q[:-1, 2]) + d[:, 1] * np.sin(q[:-1, 2])
    signs = np.sign(along[np.abs(along) > 1e-9])
    assert int(np.sum(signs[1:] != signs[:-1])) <= 10


def test_an_end_with_no_turn_at_rest_is_refused_at_once():
    """A goal in a tunnel 0.8 wide (the parking slot with a roof): the car cannot turn at
    rest to either hitch angle +-1.2 there (checked on the model's own configurations), so
    no guide curve can end there; the guide says so at once instead of searching."""
    import time

    from nilpotent.errors import PlanningError
    from nilpotent.planning.trailer_guide import trailer_guide_path
    from nilpotent.planning.world import world_from_dict

    world = world_from_dict({
        "name": "tunnel", "bounds": {"x": [-4.0, 6.0], "y": [-1.2, 2.5]},
        "obstacles": [
            {"polygon": [[-4.0, -1.2], [6.0, -1.2], [6.0, -1.0], [-4.0, -1.0]]},
            {"polygon": [[-0.5, -0.2], [3.5, -0.2], [3.5, 0.3], [-0.5, 0.3]]},
        ]})
    checker = Checker(SYSTEM, world)
    start, goal = np.array([-2.5, 1.0, 0.1, 0.1]), np.array([1.7, -0.6, 0.0, 0.0])
    assert checker.why_invalid(goal) == ""
    for phi in (1.2, -1.2):
        assert not checker.valid(np.array([[1.7, -0.6, phi, 0.0]]))[0]
    t = time.perf_counter()
    with pytest.raises(PlanningError, match="goal's trailer pose admits no turn"):
        trailer_guide_path(checker, start, goal, 60.0, seed=0)
    assert time.perf_counter() - t < 10.0


def test_a_straight_drive_in_a_corridor_is_not_refused():
    """A corridor 1 wide: the car cannot turn at rest to +-1.2 anywhere in it, but the goal
    lies straight ahead on the trailer's axis, so one straight leg joins the two ends (the
    default planner finds it too); the guide must not refuse it at once, and its path
    replays by scipy to the goal with the hitch angle 0 throughout."""
    from nilpotent.planning.world import world_from_dict

    world = world_from_dict({"name": "corridor",
                             "bounds": {"x": [-3.0, 6.0], "y": [-0.5, 0.5]}})
    checker = Checker(SYSTEM, world)
    for phi in (1.2, -1.2):
        assert not checker.valid(np.array([[0.0, 0.0, phi, 0.0]]))[0]
    start, goal = (0.0, 0.0, 0.0, 0.0), (3.0, 0.0, 0.0, 0.0)
    out = plan_global(SYSTEM, start, goal, 1e-6, world=world, time_limit=60,
                      planner="reeds-shepp", seed=0)
    assert out.planner == "reeds-shepp"
    q = resimulate(SYSTEM, start, _json(out.plan), samples=50)
    assert np.linalg.norm(q[-1] - np.array(goal)) <= 1e-5
    assert np.abs(q[:, 2] - q[:, 3]).max() <= 1e-9
    assert np.all(checker.measures(q)[0] > 0)


def test_a_trailer_model_with_another_drive_is_refused_with_its_reason(tmp_path):
    """A model file with the trailer's coordinates whose trailer is pushed ahead
    (``-sin(θ0 − θ1)/d``): refused naming what differs from a car with one trailer, not
    the car's coordinates."""
    from nilpotent.core.model.modelfile import load_model_file

    path = tmp_path / "ahead.toml"
    path.write_text(
        'coordinates = ["x", "y", "theta0", "theta1"]\n[parameters]\nd = 1.0\n'
        '[[fields]]\nx = "cos(theta0)"\ny = "sin(theta0)"\n'
        'theta1 = "-sin(theta0 - theta1)/d"\n[[fields]]\ntheta0 = 1\n'
        '[relative_limits]\n"theta0 - theta1" = [-1.4, 1.4]\n')
    with pytest.raises(OptionError, match=r"car-like.*first field other than"):
        plan_global(load_model_file(path), (0, 0, 0, 0), (3, 1, 0, 0),
                    planner="reeds-shepp", time_limit=600)


def test_a_hitch_limit_within_the_guide_margin_is_refused_naming_it(tmp_path):
    """A hitch limit of 0.002 rad (below the guide's margin, so no hitch angle to drive
    an arc at): the refusal states the lower bound too, not only ``< pi/2``."""
    from nilpotent.core.model.modelfile import load_model_file

    path = tmp_path / "stiff.toml"
    path.write_text(
        'coordinates = ["x", "y", "theta0", "theta1"]\n[parameters]\nd = 1.0\n'
        '[[fields]]\nx = "cos(theta0)"\ny = "sin(theta0)"\n'
        'theta1 = "sin(theta0 - theta1)/d"\n[[fields]]\ntheta0 = 1\n'
        '[relative_limits]\n"theta0 - theta1" = [-0.002, 0.002]\n')
    with pytest.raises(OptionError, match=r"0\.0025 < phi_max < pi/2"):
        plan_global(load_model_file(path), (0, 0, 0, 0), (3, 1, 0, 0),
                    planner="reeds-shepp", time_limit=600)


def test_a_hitch_angle_held_where_the_car_cannot_turn_at_rest():
    """The trailer at the origin, the car's hitch angle -1.2 beside a wall where the car
    cannot turn at rest to 0 (checked on the model's own configurations): a vertex of the
    guide takes the hitch angle its curves need (when every vertex had 0, no curve could
    leave this start).  The goal is 0.5 ahead on the right arc of the guide's radius; the
    path leaves the start without turning at rest, every piece is driven exactly, and the
    scipy replay reaches the goal with the hitch angle within its limit, out of the wall."""
    from nilpotent.planning.guide import leg_end
    from nilpotent.planning.trailer_guide import trailer_guide_path
    from nilpotent.planning.world import world_from_dict

    world = world_from_dict({
        "name": "wall", "bounds": {"x": [-4.0, 5.0], "y": [-4.0, 3.0]},
        "obstacles": [{"polygon": [[1.45, -0.3], [3.0, -0.3], [3.0, 0.3], [1.45, 0.3]]}]})
    checker = Checker(SYSTEM, world)
    g = trailer_geometry(SYSTEM, checker)
    phi = -g.phi_guide
    start = from_car(np.array([0.0, 0.0, 0.0, phi]), g.hitch)
    goal = from_car(np.array([*leg_end(np.zeros(3), math.tan(phi) / g.hitch, 0.5), phi]),
                    g.hitch)
    for turned in (-0.6, 0.0, 0.6):
        assert not checker.valid(from_car(np.array([[0.0, 0.0, 0.0, turned]]), g.hitch))[0]
    found = trailer_guide_path(checker, start, goal, 10.0, seed=0)
    points = [np.array(p) for p in found.points]
    assert np.allclose(points[0], start) and np.allclose(points[-1], goal)
    first = to_car(points[1], g.hitch)
    assert first[3] == pytest.approx(phi, abs=1e-9) and np.abs(first[:2]).max() > 1e-3
    x, segments = start, []
    for prev, w in itertools.pairwise(points):
        piece = trailer_exact_piece(checker, x, prev, w, 1e-6, 40, g)
        assert piece is not None
        segments += _json(piece)
        x = np.array(piece.reached)
    q = resimulate(SYSTEM, start, segments, samples=50)
    assert np.linalg.norm(q[-1] - goal) <= 1e-5
    assert np.abs(q[:, 2] - q[:, 3]).max() <= HITCH_LIMIT + 1e-9
    assert np.all(checker.measures(q)[0] > 0)
