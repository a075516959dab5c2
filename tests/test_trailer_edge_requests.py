"""Requests at the edges of the trailer planners (``--planner reeds-shepp``): ends near or on
a hitch limit, a goal a full turn away, a goal caged by obstacles, and the progress shown.

Independent results: the plans replayed by scipy (tests/replay.py) against the goal and the
hitch limits; the cage's verdict against worlds built so that the answer is known (closed
walls, a gap the robot's outline fits through); the covered boxes against shapely's own
distances at points of each box; the estimates of time left against a clock the test sets.
"""

from __future__ import annotations

import io
import math
import time

import numpy as np
import pytest
import shapely

import nilpotent.cli.cmd_plan  # noqa: F401  (registers the command)
from nilpotent import progress
from nilpotent.errors import PlanningError
from nilpotent.models import get_model
from nilpotent.models.outlines import HITCH_LIMIT
from nilpotent.planning.global_planner import plan_global
from nilpotent.planning.grid_distance import refuse_unreachable
from nilpotent.planning.optimal_planner import refuse_full_turn
from nilpotent.planning.trailer_hitch import within_limits
from nilpotent.planning.verify import Checker
from nilpotent.planning.world import world_from_dict
from nilpotent.progress import ProgressEvent
from replay import resimulate

TWO = get_model("car-trailers:2")
ONE = get_model("car-trailers:1")


def _replayed_within(system, out, start, goal) -> None:
    q = resimulate(system, start, [s.to_dict() for s in out.plan.segments], samples=60)
    assert np.linalg.norm(q[-1] - np.array(goal, dtype=float)) <= 1e-5
    hitch = np.abs(np.diff(q[:, 2:], axis=1))
    assert hitch.max() <= HITCH_LIMIT + 1e-9


# defects 1 and 2: a goal near the limit of theta1 - theta2 (the search's root), a start on
# either limit (joined by the final approach), in free space
@pytest.mark.parametrize("start, goal", [
    ((0.0, 0.0, 0.0, 0.0, 0.0), (3.0, 1.0, 0.0, 0.0, -1.37)),
    ((0.0, 0.0, 0.0, 0.0, -HITCH_LIMIT), (3.0, 1.0, 0.0, 0.0, 0.0)),
    ((0.0, 0.0, HITCH_LIMIT, 0.0, 0.0), (3.0, 1.0, 0.0, 0.0, 0.0)),
])
def test_two_trailers_plan_from_and_to_the_hitch_limits(start, goal):
    """A goal 0.03 inside the hitch limit, and starts on it, are planned (they were refused:
    "expanded every reachable bin (1)", or the whole budget burnt); the scipy replay ends
    at the goal within the limits."""
    t0 = time.perf_counter()
    out = plan_global(TWO, start, goal, 1e-6, time_limit=120, planner="reeds-shepp",
                      direct=False)
    assert time.perf_counter() - t0 < 60
    _replayed_within(TWO, out, start, goal)


def test_limits_between_samples_let_a_motion_leave_its_bound():
    """A hitch angle leaving the limit it starts on passes; one crossing the limit between
    two samples inside fails (a parabola with its top past the bound); a sample short of the
    slack fails."""
    checker = Checker(TWO)
    s = np.linspace(0.0, 1.0, 11)
    leaving = np.zeros((11, 5))
    leaving[:, 4] = -(HITCH_LIMIT - 0.3 * s)  # theta1 - theta2 from 1.4 down
    crossing = np.zeros((11, 5))
    top = 0.55  # between samples 5 and 6, 0.01 past the limit
    crossing[:, 4] = -(HITCH_LIMIT + 0.01 - 8.0 * (s - top) ** 2)
    assert np.all(np.abs(crossing[:, 4]) <= HITCH_LIMIT)  # every sample inside
    ok = within_limits(checker, [leaving, crossing], 0.0)
    assert ok.tolist() == [True, False]
    assert not within_limits(checker, [leaving], 0.01)[0]


# defect 3: a goal a full turn away in heading
@pytest.mark.parametrize("system, goal", [
    (ONE, (3.0, 1.2, 2 * math.pi, 2 * math.pi)),
    (TWO, (3.0, 1.2, 2 * math.pi, 2 * math.pi, 2 * math.pi)),
    (get_model("car"), (3.0, 1.2, -2 * math.pi, 0.0)),
])
def test_a_full_turn_is_refused_at_once_naming_the_heading(system, goal):
    start = (0.0,) * system.n
    t0 = time.perf_counter()
    with pytest.raises(PlanningError, match="full turn") as e:
        plan_global(system, start, goal, 1e-6, time_limit=60, planner="reeds-shepp")
    assert time.perf_counter() - t0 < 10  # was 44 s for car-trailers:1
    heading = "theta" if system.name == "car" else "theta0"
    assert heading in str(e.value) and "6.283" in str(e.value)


def test_less_than_a_full_turn_is_not_refused():
    names = ONE.coordinate_names
    refuse_full_turn(names, np.zeros(4), np.array([0.0, 0.0, 2 * math.pi - 0.1, 6.0]))
    with pytest.raises(PlanningError):
        refuse_full_turn(names, np.zeros(4), np.array([0.0, 0.0, 5.0, 2 * math.pi]))


# defect 4: a caged goal
def _walls(gap: float) -> dict:
    """A box 4.6 x 2.6 (walls 0.2 thick) around (3.4, 1.7); the left wall has an opening
    ``gap`` high at mid-height (0: closed)."""
    lo, hi = 1.7 - gap / 2, 1.7 + gap / 2
    left = ([[[1.0, 0.3], [1.2, 0.3], [1.2, lo], [1.0, lo]],
             [[1.0, hi], [1.2, hi], [1.2, 3.1], [1.0, 3.1]]] if gap else
            [[[1.0, 0.3], [1.2, 0.3], [1.2, 3.1], [1.0, 3.1]]])
    polys = [[[1.0, 0.3], [5.8, 0.3], [5.8, 0.5], [1.0, 0.5]],
             [[1.0, 2.9], [5.8, 2.9], [5.8, 3.1], [1.0, 3.1]],
             [[5.6, 0.3], [5.8, 0.3], [5.8, 3.1], [5.6, 3.1]], *left]
    return {"name": "cage", "bounds": {"x": [-6, 8], "y": [-3, 4]},
            "obstacles": [{"polygon": p} for p in polys]}


@pytest.mark.parametrize("system, goal", [(ONE, (4.0, 1.7, 0.0, 0.0)),
                                          (TWO, (4.5, 1.7, 0.0, 0.0, 0.0))])
def test_a_caged_goal_is_refused_as_unreachable(system, goal):
    world = world_from_dict(_walls(0.0))
    start = (-3.0, 0.0) + (0.0,) * (system.n - 2)
    t0 = time.perf_counter()
    with pytest.raises(PlanningError, match="goal not reachable from start"):
        plan_global(system, start, goal, 1e-6, world=world, time_limit=60,
                    planner="reeds-shepp")
    assert time.perf_counter() - t0 < 10  # was the whole time limit


@pytest.mark.parametrize("gap", [0.05, 0.6])
def test_an_opening_is_never_called_a_cage(gap):
    """Soundness: with an opening (narrower than the car, 0.5 wide, or wider) the points
    of the outline are not separated, so nothing is refused (the search decides)."""
    checker = Checker(TWO, world_from_dict(_walls(gap)))
    refuse_unreachable(checker, np.array([-3.0, 0.0, 0.0, 0.0, 0.0]),
                       np.array([4.5, 1.7, 0.0, 0.0, 0.0]))


def test_a_covered_box_has_no_free_point():
    """Every box ``covers_boxes`` calls covered (margin 0.1) has its corners and centre
    within 0.1 of the obstacles by shapely's own distance; and a box around a free point is
    not covered."""
    world = world_from_dict({"name": "w", "bounds": {"x": [0, 4], "y": [0, 3]},
                             "obstacles": [{"polygon": [[1, 1], [2, 1], [2, 2], [1, 2]]},
                                           {"disc": {"center": [3, 1], "radius": 0.5}}]})
    rng = np.random.default_rng(1)
    lo = rng.uniform(-0.5, 4.5, (400, 2))
    hi = lo + rng.uniform(0.01, 0.4, (400, 1))
    covered = world.covers_boxes(lo, hi, 0.1)
    assert covered.any() and not covered.all()
    blocked = shapely.union_all([shapely.box(1, 1, 2, 2), shapely.Point(3, 1).buffer(0.5, 256),
                                 shapely.box(-50, -50, 50, 50).difference(
                                     shapely.box(0, 0, 4, 3))])
    for a, b in zip(lo[covered], hi[covered], strict=True):
        for p in ((a[0], a[1]), (b[0], b[1]), (a[0], b[1]), (b[0], a[1]), (a + b) / 2):
            assert shapely.distance(shapely.Point(*p), blocked) <= 0.1 + 1e-6
    assert not world.covers_boxes(np.array([[0.2, 0.2]]), np.array([[0.3, 0.3]]), 0.1)[0]


def test_the_cli_refuses_a_caged_goal_with_exit_2(run_cli, tmp_path):
    import json

    path = tmp_path / "cage.json"
    path.write_text(json.dumps(_walls(0.0)), encoding="utf-8")
    status, out, err = run_cli("plan", "car-trailers:1", "--world", str(path), "--from",
                               "x=-3,y=0", "--to", "x=4,y=1.7", "--planner", "reeds-shepp",
                               "--time-limit", "30", "--tol", "1e-6")
    assert status == 2
    assert "goal not reachable from start" in err and "Traceback" not in err + out


# defect 5: progress
@pytest.fixture
def clock(monkeypatch):
    was = progress.enabled()
    progress.configure(enabled=True)
    monkeypatch.setattr(progress, "PLAIN_INTERVAL", 0.0)
    monkeypatch.setattr(progress, "HEARTBEAT", 1e9)
    now = [1000.0]
    monkeypatch.setattr(progress.time, "monotonic", lambda: now[0])
    yield now
    progress.configure(enabled=was)


def test_the_time_left_counts_from_the_pieces_and_stops_at_the_deadline(clock):
    """100 s of search without a total, then pieces at 1 per second: 31 of 33 left is
    about 31 s (not 33 x 100 s); with the time limit 9 s away, no estimate past it."""
    out = io.StringIO()
    with progress.progress("plan", stream=out) as bar:
        clock[0] += 100.0
        bar(ProgressEvent("lattice nodes expanded", 400, None))
        bar(ProgressEvent("pieces steered", 1, 33))
        clock[0] += 1.0
        bar(ProgressEvent("pieces steered", 2, 33))
        assert bar.remaining() == pytest.approx(31.0)
        bar.deadline = clock[0] + 9.0
        assert bar.remaining() == pytest.approx(9.0)
        clock[0] += 1.0
        bar(ProgressEvent("pieces steered", 3, 33))
    text = out.getvalue()
    assert "min left" not in text
    assert "time limit in 8 s" in text.splitlines()[-2]
