"""Plans re-timed under input bounds (issue 19, items 2-3): bounds at every sample,
continuous inputs at rest at the ends and at every stop, the samples re-integrated
independently (RK4 on sympy's fields, nothing of the product), the CSV export,
bad bounds refused, reversals counted."""

from __future__ import annotations

import csv
import io
import json
import math

import numpy as np
import pytest
import sympy as sp

import nilpotent as nil
import nilpotent.cli.cmd_plan  # registers the command
from nilpotent.errors import OptionError
from nilpotent.numeric.signals import InputSignal, Segment
from nilpotent.planning.timing import (
    InputBounds,
    drive_reversals,
    input_bounds,
    input_reversals,
    retime,
)

#: Relative slack of the finite-difference acceleration check: the bound is kept at
#: the samples and at CHECK_FACTOR points per TOPP-RA cell, a difference quotient is
#: dũ/dt at some point between two samples (mean value theorem), where dũ/dt differs
#: from its checked neighbours by O(cell) (measured: 3e-14 over the bound).
FD_SLACK = 1e-3

CASES = {
    "unicycle": ([0.0, 0.0, 0.0], [0.5, 0.5, 0.3], 0.5, 1.0),
    "heisenberg": ([0.0, 0.0, 0.0], [0.3, -0.2, 0.4], 0.5, 1.0),
}


@pytest.fixture(scope="module")
def planned():
    out = {}
    for name, (start, goal, v, a) in CASES.items():
        system = nil.get_model(name)
        out[name] = (system, nil.plan(system, start, goal, 1e-8, max_speed=v, max_accel=a))
    return out


def reintegrate(system, start, times, inputs):
    """The true system under the samples' inputs read linearly between samples: classical
    RK4 on each sample interval (the input at its midpoint is the mean of its ends), on
    sympy's fields; the reading's O(h²) error dominates RK4's O(h⁴)."""
    fields = sp.lambdify([system.coordinates], sp.Matrix(system.specialized_fields).T, "numpy")

    def rhs(z, u):
        return np.asarray(fields(z), dtype=float) @ u

    x = np.asarray(start, dtype=float)
    out = [x]
    for k in range(times.size - 1):
        h, u0, u1 = times[k + 1] - times[k], inputs[k], inputs[k + 1]
        um = (u0 + u1) / 2
        k1 = rhs(x, u0)
        k2 = rhs(x + h / 2 * k1, um)
        k3 = rhs(x + h / 2 * k2, um)
        k4 = rhs(x + h * k3, u1)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(x)
    return np.array(out)


def check_bounds(timed, speed, accel):
    u, t = timed.inputs, timed.times
    assert np.all(np.diff(t) > 0)
    assert np.all(np.abs(u) <= np.asarray(speed) * (1 + 1e-12))
    assert np.all(np.abs(timed.accelerations) <= np.asarray(accel) * (1 + 1e-12))
    quotient = np.abs(np.diff(u, axis=0)) / np.diff(t)[:, None]
    assert np.all(quotient <= np.asarray(accel) * (1 + FD_SLACK))


@pytest.mark.parametrize("name", list(CASES))
def test_every_sample_is_within_the_bounds_and_at_rest_at_every_stop(planned, name):
    system, result = planned[name]
    _, goal, v, a = CASES[name]
    timed = result.timed
    assert timed is not None
    check_bounds(timed, [v] * system.m, [a] * system.m)
    assert np.all(timed.inputs[0] == 0) or np.max(np.abs(timed.inputs[0])) <= 1e-12
    for stop in timed.stops:
        k = int(np.argmin(np.abs(timed.times - stop)))
        assert timed.times[k] == stop
        assert np.max(np.abs(timed.inputs[k])) <= 1e-12  # at rest: ṡ = 0 there
    assert timed.stops[0] == 0.0 and timed.stops[-1] == timed.times[-1]
    # the last sample is the plan's verified point, the goal within tol
    assert np.array_equal(timed.states[-1], np.array(result.plan.reached))
    assert np.linalg.norm(timed.states[-1] - np.array(goal)) <= 1e-8
    # plan time runs forward from 0 to the plan's duration
    assert np.all(np.diff(timed.plan_times) >= 0)
    assert timed.plan_times[-1] == pytest.approx(result.plan.duration, rel=1e-12)


def test_the_json_carries_the_samples_strictly(planned):
    system, result = planned["unicycle"]
    data = json.loads(json.dumps(result.to_json(), allow_nan=False))
    traj = data["trajectory"]
    n = len(traj["t"])
    assert np.shape(traj["x"]) == (n, system.n) and np.shape(traj["u"]) == (n, system.m)
    assert traj["max_speed"] == [0.5, 0.5] and traj["max_accel"] == [1.0, 1.0]
    assert data["segments"] == [s.to_dict() for s in result.plan.segments]  # unchanged


@pytest.mark.parametrize("name", list(CASES))
def test_the_samples_reintegrated_independently_reach_the_goal(planned, name):
    """The samples' inputs, read linearly between samples, re-integrated by RK4: the
    error of that reading is O(h²) on the smooth stretches (h, the step), so halving the
    step divides the end error by about 4 (2.5 asked for: the kinks of s̈ give O(h²)
    per stop only)."""
    system, result = planned[name]
    start, goal, _, _ = CASES[name]
    errors = []
    for fraction in (1 / 1000, 1 / 2000):
        step = result.timed.duration * fraction
        timed = retime(system, start, result.plan.segments, result.timed.bounds, step=step)
        states = reintegrate(system, start, timed.times, timed.inputs)
        # the exported states are the plan's path at s(t): the same as re-integrated
        assert np.max(np.abs(states - timed.states)) <= 1e-3
        errors.append(float(np.linalg.norm(states[-1] - np.array(goal))))
    assert errors[1] <= 2e-4
    assert errors[1] <= errors[0] / 2.5


def test_inputs_are_continuous_the_jumps_shrink_with_the_step(planned):
    system, result = planned["unicycle"]
    jumps = []
    for samples in (250, 1000):
        timed = retime(system, CASES["unicycle"][0], result.plan.segments,
                       result.timed.bounds, step=result.timed.duration / samples)
        jumps.append(float(np.max(np.abs(np.diff(timed.inputs, axis=0)))))
    # a jump between samples is at most A·Δt (bounded acceleration): it falls with the step
    assert jumps[1] <= jumps[0] / 3.5
    # the plan's own inputs jump at its segment boundaries by far more
    ends = [s.values(s.duration) for s in result.plan.segments[:-1]]
    heads = [s.values(0.0) for s in result.plan.segments[1:]]
    assert max(float(np.max(np.abs(a - b))) for a, b in zip(ends, heads, strict=True)) > 0.1


def test_constant_inputs_give_the_closed_form_time_optimal_profile():
    """Straight pieces of length L under |u| ≤ V, |du/dt| ≤ A (L ≥ V²/A): the time-optimal
    rest-to-rest motion accelerates, cruises, brakes, in L/V + V/A (trapezoid profile)."""
    system = nil.get_model("unicycle")
    segments = (Segment(1.0, 1.0, (InputSignal(1.0), InputSignal(0.0))),
                Segment(2.0, 1.0, (InputSignal(0.0), InputSignal(0.5))),
                Segment(1.0, 1.0, (InputSignal(0.0), InputSignal(1e-8))))
    bounds = InputBounds((0.5, 0.25), (1.0, 1.0))
    timed = retime(system, [0, 0, 0], segments, bounds)
    # the last piece, L = 1e-8 < V²/A, never cruises: 2√(L/A) (a triangle)
    want = (1.0 / 0.5 + 0.5 / 1.0) + (1.0 / 0.25 + 0.25 / 1.0) + 2 * math.sqrt(1e-8)
    assert timed.duration == pytest.approx(want, rel=1e-3)
    assert len(timed.stops) == 4 and timed.stops[1] == pytest.approx(2.5, rel=1e-3)
    assert timed.stops[3] - timed.stops[2] == pytest.approx(2e-4, rel=1e-3)
    assert np.allclose(timed.states[-1], [1.0, 0.0, 1.0 + 1e-8], atol=1e-12)
    check_bounds(timed, bounds.speed, bounds.accel)


def test_per_input_and_partial_speed_bounds(planned):
    system, result = planned["unicycle"]
    bounds = input_bounds(2, {"u1": 0.25}, [1.0, 2.0])
    assert bounds == InputBounds((0.25, math.inf), (1.0, 2.0))
    timed = retime(system, [0, 0, 0], result.plan.segments, bounds)
    check_bounds(timed, bounds.speed, bounds.accel)
    assert np.max(np.abs(timed.inputs[:, 0])) == pytest.approx(0.25, rel=1e-6)
    assert timed.to_json()["max_speed"] == [0.25, None]


@pytest.mark.parametrize("speed, accel, message", [
    (0.0, 1.0, "finite number > 0"),
    (-1.0, 1.0, "finite number > 0"),
    ({"u3": 1.0}, 1.0, "unknown input 'u3'"),
    (1.0, {"u1": 1.0}, "must bound every input"),
    (1.0, None, "needs max_accel"),
    (None, math.inf, "finite number > 0"),
    (1e-300, 1.0, "between 1e-09 and 1e"),
    ([1.0], 1.0, "1 bounds given for 2 inputs"),
])
def test_bad_bounds_are_refused_before_planning(speed, accel, message):
    with pytest.raises(OptionError, match=message):
        nil.plan(nil.get_model("unicycle"), [0, 0, 0], [1, 0, 0], max_speed=speed,
                 max_accel=accel)


def test_reversals_are_counted_by_hand():
    # u1 = cos t on [0, 2π] changes sign at π/2 and 3π/2, then -1: one more at the
    # boundary (cos 2π = 1); u2 = 1 never; a value near 0 is no reversal
    segments = (Segment(2 * math.pi, 1.0, (InputSignal(0.0, (1.0,)), InputSignal(1.0))),
                Segment(1.0, 1.0, (InputSignal(-1.0), InputSignal(1e-12))))
    assert input_reversals(segments) == (3, 0)
    assert drive_reversals(nil.get_model("unicycle"), segments) == 3
    assert drive_reversals(nil.get_model("car-trailers:2"), segments) == 3
    assert drive_reversals(nil.get_model("heisenberg"), segments) is None


def test_reversals_in_the_plan_json(planned):
    _, uni = planned["unicycle"]
    _, heis = planned["heisenberg"]
    data = uni.to_json()
    assert data["reversals"] == data["input_reversals"][0]
    assert data["input_reversals"] == list(input_reversals(uni.plan.segments))
    other = heis.to_json()
    assert other["reversals"] is None and "reversals" in other["null_reasons"]


@pytest.mark.slow
def test_the_car_re_timed_keeps_its_bounds():
    system = nil.get_model("car")
    # a goal the steering reaches in a few seconds (the sideways shift [0, 1, 0, 0] takes
    # ~35 s here, twice that on a loaded 2-core CI machine); no time limit decides the test
    goal = [0.5, 0.5, 0.8, 0]
    result = nil.plan(system, [0, 0, 0, 0], goal, 1e-8, time_limit=900,
                      max_speed={"u1": 1.0}, max_accel=[2.0, 4.0])
    timed = result.timed
    check_bounds(timed, [1.0, math.inf], [2.0, 4.0])
    errors = []
    for samples in (1000, 4000):  # the reading's error O(h²): 4 times the samples, ~16 less
        fine = retime(system, [0, 0, 0, 0], result.plan.segments, timed.bounds,
                      step=timed.duration / samples)
        states = reintegrate(system, [0, 0, 0, 0], fine.times, fine.inputs)
        errors.append(float(np.linalg.norm(states[-1] - goal)))
    assert errors[1] <= 1e-3 and errors[1] <= errors[0] / 4
    data = result.to_json()
    assert data["reversals"] == input_reversals(result.plan.segments)[0] > 0


# --- the command line ----------------------------------------------------------------------


def test_trajectory_csv_matches_the_json(run_cli, tmp_path):
    out_csv = tmp_path / "traj.csv"
    status, out, err = run_cli(
        "plan", "unicycle", "--to", "x=1/2,y=1/2,theta=3/10", "--max-speed", "u1=1/2,u2=1",
        "--max-accel", "1", "--trajectory-out", str(out_csv), "--trajectory-step", "0.05",
        "--json")
    assert status == 0, err
    data = json.loads(out)
    traj = data["trajectory"]
    rows = list(csv.reader(io.StringIO(out_csv.read_text(encoding="utf-8"))))
    assert rows[0] == ["t", "x", "y", "theta", "u1", "u2"]
    table = np.array(rows[1:], dtype=float)
    assert np.array_equal(table[:, 0], traj["t"])
    assert np.array_equal(table[:, 1:4], traj["x"])
    assert np.array_equal(table[:, 4:], traj["u"])
    assert np.all(np.diff(table[:, 0]) <= 0.05 * (1 + 1e-12))
    assert np.all(np.abs(table[:, 4]) <= 0.5 * (1 + 1e-12))
    assert np.allclose(table[-1, 1:4], data["to"], atol=1e-8)


@pytest.mark.parametrize("args, message", [
    (["--max-speed", "0", "--max-accel", "1"], "--max-speed: a bound must be a finite number"),
    (["--max-speed", "-2", "--max-accel", "1"], "--max-speed: a bound must be a finite number"),
    (["--max-speed", "v=1", "--max-accel", "1"], "--max-speed: unknown input 'v'"),
    (["--max-accel", "u1=1"], "--max-accel must bound every input"),
    (["--max-speed", "1"], "--max-speed needs --max-accel"),
    (["--trajectory-out", "t.csv"], "--trajectory-out needs --max-accel"),
    (["--max-accel", "1", "--trajectory-out", "/nonexistent-dir/t.csv"], "does not exist"),
])
def test_bad_trajectory_options_exit_2(run_cli, args, message, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, out, err = run_cli("plan", "unicycle", "--to", "x=1", *args)
    assert status == 2
    assert message in out + err
    assert "Traceback" not in out + err
    assert list(tmp_path.iterdir()) == []


def test_a_plan_that_does_not_move_re_times_to_one_sample_at_rest(run_cli, tmp_path):
    """Goal = start: the plan verifies without bounds, so with bounds it must too (it
    was refused, exit 2); the motion that stays put is one sample at rest, at the goal."""
    out_csv = tmp_path / "rest.csv"
    status, out, err = run_cli(
        "plan", "unicycle", "--from", "x=1/4", "--to", "x=1/4", "--max-speed", "1",
        "--max-accel", "1", "--trajectory-out", str(out_csv), "--json")
    assert status == 0, err
    data = json.loads(out)
    traj = data["trajectory"]
    assert traj["t"] == [0.0] and traj["duration"] == 0.0
    assert traj["x"] == [[0.25, 0.0, 0.0]] and traj["u"] == [[0.0, 0.0]]
    rows = list(csv.reader(io.StringIO(out_csv.read_text(encoding="utf-8"))))
    assert [float(v) for v in rows[1]] == [0.0, 0.25, 0.0, 0.0, 0.0, 0.0]
    # every input 0 (segments that do not move): the same, in the Python API
    unicycle = nil.get_model("unicycle")
    still = Segment(1.0, 2 * math.pi, (InputSignal(0.0), InputSignal(0.0)))
    timed = retime(unicycle, [0.1, 0.2, 0.3], [still, still],
                   InputBounds((1.0, 1.0), (1.0, 1.0)))
    assert timed.times.tolist() == [0.0] and timed.inputs.tolist() == [[0.0, 0.0]]
    assert timed.states.tolist() == [[0.1, 0.2, 0.3]]


def test_a_model_file_borrowing_a_vehicle_name_has_no_drive_input(tmp_path, run_cli):
    """A model file named ``unicycle`` over the Heisenberg fields is no vehicle: no
    reversals, and a reversal cost is refused; the built-in with other parameters is."""
    import sympy as sp

    from nilpotent.models import load_system

    f = tmp_path / "fake.toml"
    f.write_text('name = "unicycle"\ncoordinates = ["x", "y", "theta"]\n'
                 '[[fields]]\nx = "1"\ntheta = "-y/2"\n[[fields]]\ny = "1"\ntheta = "x/2"\n')
    assert drive_reversals(load_system(str(f), {}), ()) is None
    assert drive_reversals(nil.get_model("car", {"L": sp.Rational(1, 2)}), ()) == 0
    status, out, _ = run_cli("plan", str(f), "--to", "theta=1/10", "--refine", "ocp",
                             "--reversal-cost", "1", "--json")
    assert status == 2 and "no drive input" in json.loads(out)["error"]["message"]
