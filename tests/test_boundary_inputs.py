"""Input validation at the boundary (issue 22, items 2, 5, 6, 8, 9).

Every number a user gives (options, points, world files) is finite, within a
documented range, or refused with exit 2 and a message naming where it came
from; worlds and outlines are checked (finite, positive sizes) and seen by the
checker; files that are not regular files are refused before reading; user text
is never parsed as markup.  Each test asserts the interface's promise: exit 2
(or a correct result), the error's kind, one JSON object under ``--json``, no
traceback.  The values are not the ones of the issue's report.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import typing
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nilpotent.cli.app import bounded_float
from nilpotent.core.model.points import MAX_MAGNITUDE, check_magnitude
from nilpotent.errors import NilpotentError, OptionError, WorldError


def _error(status: int, out: str, err: str) -> dict:
    assert status == 2, (out, err)
    assert "Traceback" not in err
    data = json.loads(out)  # exactly one JSON object on stdout
    assert set(data) == {"error"} and set(data["error"]) == {"kind", "message"}
    return data["error"]


# A unicycle with a round outline (radius 0.1): cheap to plan among obstacles.
DISC_ROBOT = """\
name = "puck"
coordinates = ["x", "y", "theta"]
[[fields]]
x = "cos(theta)"
y = "sin(theta)"
[[fields]]
theta = "1"
[[geometry.discs]]
center = ["x", "y"]
radius = "{radius}"
"""


def _robot(tmp_path: Path, radius: str = "1/10") -> str:
    path = tmp_path / "puck.toml"
    path.write_text(DISC_ROBOT.format(radius=radius), encoding="utf-8")
    return str(path)


def _world(tmp_path: Path, text: str, name: str = "w.toml") -> str:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return str(path)


# --- 1. numbers of options: one check, exit 2 naming the option ------------------------
PLAN = ("plan", "unicycle", "--to", "x=0.2")
EXECUTE = ("execute", "unicycle", "--to", "x=0.2")
SIMULATE = ("simulate", "unicycle", "--bracket", "1,2")


@pytest.mark.parametrize(
    ("args", "option"),
    [
        ((*PLAN, "--tol", "-2.5e-3"), "--tol"),
        ((*PLAN, "--tol", "3e400"), "--tol"),
        ((*PLAN, "--time-limit", "-inf"), "--time-limit"),
        ((*PLAN, "--time-limit", "0"), "--time-limit"),
        ((*PLAN, "--clearance", "-0.01"), "--clearance"),
        ((*PLAN, "--singular-margin", "7e7"), "--singular-margin"),
        ((*PLAN, "--max-piece", "nan"), "--max-piece"),
        ((*PLAN, "--max-piece", "-1"), "--max-piece"),
        ((*EXECUTE, "--noise", "4.5e6"), "--noise"),
        ((*EXECUTE, "--tol", "0.0"), "--tol"),
        ((*SIMULATE, "--amplitude", "-0.3"), "--amplitude"),
        ((*SIMULATE, "--amplitude", "2" + "0" * 400), "--amplitude"),
        ((*SIMULATE, "--amplitude", "0.1", "--omega", "9e99"), "--omega"),
        (("sweep", "unicycle", "--bracket", "1,2", "--radius", "-3"), "--radius"),
        (("sweep", "unicycle", "--bracket", "1,2", "--rtol", "1.5"), "--rtol"),
        (("sweep", "unicycle", "--bracket", "1,2", "--bound", "1e15"), "--bound"),
        (("sweep", "unicycle", "--bracket", "1,2", "--amplitudes", "0.01,7e8"), "--amplitudes"),
        (("scaling", "unicycle", "--bracket", "1,2", "--amplitudes", "0.1,inf"), "--amplitudes"),
        # seeds: within [0, 2**63) for every command
        ((*PLAN, "--seed", str(2**70 + 3)), "--seed"),
        ((*EXECUTE, "--seed", "-4"), "--seed"),
        ((*EXECUTE, "--seed", str(2**64 + 11)), "--seed"),
        (("sweep", "unicycle", "--bracket", "1,2", "--seed", str(2**63)), "--seed"),
    ],
)
def test_numeric_options_outside_their_range_are_option_errors(run_cli, args, option):
    error = _error(*run_cli(*args, "--json"))
    assert error["kind"] == "option", error
    assert option in error["message"]


def test_max_piece_has_a_floor_and_max_corrections_a_ceiling(run_cli):
    error = _error(*run_cli(*PLAN, "--max-piece", "3e-7", "--json"))
    assert error["kind"] == "computation-limit" and "--max-piece" in error["message"]
    error = _error(*run_cli(*EXECUTE, "--max-corrections", "10" + "0" * 30, "--json"))
    assert error["kind"] == "computation-limit" and "--max-corrections" in error["message"]


def test_every_numeric_option_goes_through_a_bounded_parser():
    """One mechanism: every int/float option of every command has a bounded parser."""
    import typer

    from nilpotent.cli import app

    checked = 0
    for info in app.registered_commands:
        assert info.callback is not None
        hints = typing.get_type_hints(info.callback, include_extras=True)
        for name, hint in hints.items():
            if typing.get_origin(hint) is not typing.Annotated:
                continue
            base, *extras = typing.get_args(hint)
            kinds = set(typing.get_args(base)) - {type(None)} or {base}
            if not kinds & {int, float}:
                continue
            option = next(e for e in extras if isinstance(e, typer.models.OptionInfo))
            assert option.parser is not None, (info.callback.__name__, name)
            checked += 1
    assert checked >= 20  # plan, execute, simulate, scaling, sweep, analyze, approximate


@settings(max_examples=200, deadline=None)
@given(st.one_of(st.text(max_size=30), st.floats(), st.integers()))
def test_bounded_float_answers_every_value(value):
    """A float in the range, or a clear error: never another exception."""
    import typer

    parse = bounded_float("--x", 0.0, open_low=True)
    try:
        number = parse(value)
    except (NilpotentError, typer.BadParameter):
        return
    assert 0.0 < number <= MAX_MAGNITUDE


def test_check_magnitude_refuses_what_is_not_a_finite_number_in_range():
    assert check_magnitude(-MAX_MAGNITUDE, "v") == -MAX_MAGNITUDE
    for bad in (float("nan"), float("-inf"), 10**400, MAX_MAGNITUDE * (1 + 1e-12)):
        with pytest.raises(OptionError, match=r"^v: "):
            check_magnitude(bad, "v")
    with pytest.raises(WorldError):
        check_magnitude(-1e-300, "radius", low=0.0, error=WorldError)


# --- 2. points and NAME=VALUE options: magnitude and each name once --------------------
@pytest.mark.parametrize(
    ("args", "kind", "where"),
    [
        (("plan", "unicycle", "--to", "x=2.5e6"), "point", "--to x"),
        (("plan", "unicycle", "--to", "y=-3*10**150"), "point", "--to y"),
        (("plan", "unicycle", "--to", "x=0.1", "--from", "theta=1e309"), "point", "--from"),
        (("analyze", "unicycle", "--at", "x=-1000001"), "point", "--at x"),
        (("execute", "trident-snake", "--to", "x=0.1", "--mismatch", "r=-3e6"), "option",
         "--mismatch r"),
        (("plan", "unicycle", "--to", "x=0.1", "--limit", "x=-2e7:1"), "option", "--limit x"),
    ],
)
def test_point_and_fraction_values_have_a_magnitude_limit(run_cli, args, kind, where):
    """Parameters are exempt: the exact commands are scale-invariant (``l=1e300``)."""
    error = _error(*run_cli(*args, "--json"))
    assert error["kind"] == kind, error
    assert where in error["message"]


@pytest.mark.parametrize(
    ("args", "name"),
    [
        (("execute", "trident-snake", "--to", "x=0.1", "--mismatch", "l=0.1,r=0.02,l=-0.3"),
         "--mismatch"),
        (("plan", "unicycle", "--to", "y=0.1,theta=1,y=0.2"), "--to"),
        (("plan", "unicycle", "--to", "x=0.1", "--from", "x=0,x=0"), "--from"),
        (("analyze", "unicycle", "--at", "theta=1/3,theta=1/4"), "--at"),
    ],
)
def test_a_name_given_twice_in_one_option_is_refused(run_cli, args, name):
    error = _error(*run_cli(*args, "--json"))
    assert name in error["message"] and "twice" in error["message"]


# --- 3. world files: numbers, sizes, limits, the model-file reader ---------------------
@pytest.mark.parametrize(
    ("text", "where"),
    [
        ('[bounds]\nx = [-3.0e300, 1.0]\ny = [-1.0, 1.0]\n', "bounds.x"),
        ("[[obstacles]]\ndisc = { center = [0.0, 2.0], radius = " + "7" * 250 + " }\n",
         "radius"),
        ('[[obstacles]]\ndisc = { center = [0.0, 2.0], radius = 3.3e6 }\n', "radius"),
        ('[[obstacles]]\ndisc = { center = ["2*10**7", 2.0], radius = 1.0 }\n', "center"),
        ('[[obstacles]]\ndisc = { center = [0.0, 2.0], radius = nan }\n', "radius"),
        ('[[obstacles]]\npolygon = [[0.0, 1.0], [1.0, 1.0], [1e-3, -inf]]\n', "polygon"),
    ],
)
def test_world_numbers_are_finite_and_bounded(run_cli, tmp_path, text, where):
    world = _world(tmp_path, 'name = "w"\n' + text)
    error = _error(*run_cli("plan", _robot(tmp_path), "--to", "x=0.3", "--world", world,
                            "--json"))
    assert error["kind"] == "world", error
    assert where in error["message"] and "w.toml" in error["message"]


def test_world_size_is_limited(run_cli, tmp_path):
    from nilpotent.planning.world import MAX_OBSTACLES, MAX_POLYGON_VERTICES

    many = "".join(f"[[obstacles]]\ndisc = {{ center = [{k}.0, 9.0], radius = 0.25 }}\n"
                   for k in range(MAX_OBSTACLES + 1))
    world = _world(tmp_path, 'name = "crowd"\n' + many)
    error = _error(*run_cli("plan", _robot(tmp_path), "--to", "x=0.3", "--world", world,
                            "--json"))
    assert error["kind"] == "computation-limit" and "obstacles" in error["message"]
    n = MAX_POLYGON_VERTICES + 2
    angles = [2 * math.pi * k / n for k in range(n)]
    ring = ", ".join(f"[{5 + math.cos(a):.6f}, {math.sin(a):.6f}]" for a in angles)
    world = _world(tmp_path, f'name = "ring"\n[[obstacles]]\npolygon = [{ring}]\n', "r.toml")
    error = _error(*run_cli("plan", _robot(tmp_path), "--to", "x=0.3", "--world", world,
                            "--json"))
    assert error["kind"] == "computation-limit" and "vertices" in error["message"]


@pytest.mark.parametrize("path", ["/dev/zero", "/dev/null", "/"])
def test_a_world_that_is_not_a_regular_file_is_refused_before_reading(run_cli, tmp_path, path):
    error = _error(*run_cli("plan", _robot(tmp_path), "--to", "x=0.3", "--world", path,
                            "--json"))
    assert error["kind"] == "world" and "not a world file" in error["message"]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes need POSIX")
@pytest.mark.parametrize("what", ["--world", "model"])
def test_a_fifo_is_refused_not_waited_on(tmp_path, what):
    fifo = tmp_path / ("pipe.toml" if what == "--world" else "pipe.json")
    os.mkfifo(fifo)
    args = (["plan", _robot(tmp_path), "--to", "x=0.3", "--world", str(fifo)]
            if what == "--world" else ["analyze", str(fifo)])
    proc = subprocess.run([sys.executable, "-m", "nilpotent", *args, "--json"],
                          capture_output=True, text=True, timeout=120)
    error = _error(proc.returncode, proc.stdout, proc.stderr)
    assert "named pipe" in error["message"]


def test_world_files_are_read_like_model_files(tmp_path):
    """A BOM is read past, JSON holds the same structure, a JSON key given twice is refused."""
    from nilpotent.planning.world import load_world

    toml = 'name = "yard"\n[[obstacles]]\ndisc = { center = [1.5, -2.0], radius = 0.75 }\n'
    plain = load_world(_world(tmp_path, toml, "a.toml"))
    bom = tmp_path / "b.toml"
    bom.write_bytes(b"\xef\xbb\xbf" + toml.encode())
    as_json = _world(tmp_path, json.dumps(
        {"name": "yard", "obstacles": [{"disc": {"center": [1.5, -2.0], "radius": 0.75}}]}),
        "c.json")
    for other in (load_world(bom), load_world(as_json)):
        assert other.to_json() == plain.to_json()
    dup = _world(tmp_path, '{"name": "yard", "obstacles": [], "name": "court"}', "d.json")
    with pytest.raises(WorldError, match="duplicate key 'name'"):
        load_world(dup)
    with pytest.raises(WorldError, match="UTF-16"):
        (tmp_path / "e.toml").write_bytes(b"\xff\xfe" + toml.encode("utf-16-le"))
        load_world(tmp_path / "e.toml")


def test_a_json_world_plans_like_its_toml_twin(run_cli, tmp_path):
    world = _world(tmp_path, json.dumps(
        {"name": "yard", "bounds": {"x": [-2, 2], "y": [-2, 2]},
         "obstacles": [{"disc": {"center": [0.3, 1.2], "radius": 0.2}}]}), "yard.json")
    status, out, err = run_cli("plan", _robot(tmp_path), "--to", "x=0.4", "--world", world,
                               "--json")
    assert status == 0, (out, err)
    data = json.loads(out)
    assert data["world"] == "yard" and data["error"] <= 1e-8
    # the world is seen: the clearance is at most the start's, |(0.3, 1.2)| - 0.2 - 0.1
    # (robot radius 0.1 at the origin; the bounds are farther, 2 - 0.1)
    assert 0 < data["clearance"] <= math.hypot(0.3, 1.2) - 0.3 + 1e-9


# --- 4. obstacles covering start or goal, outlines that are not defined -----------------
@pytest.mark.parametrize(
    ("disc", "what"),
    [("{ center = [0.0, 0.0], radius = 9.5e5 }", "start"),  # covers both
     ("{ center = [0.45, 0.0], radius = 0.2 }", "goal")],
)
def test_an_obstacle_covering_start_or_goal_fails_the_plan(run_cli, tmp_path, disc, what):
    world = _world(tmp_path, f'name = "blocked"\n[[obstacles]]\ndisc = {disc}\n')
    error = _error(*run_cli("plan", _robot(tmp_path), "--to", "x=0.5", "--world", world,
                            "--json"))
    assert error["kind"] == "planning", error
    assert f"the {what} is not admissible" in error["message"]


@pytest.mark.parametrize(
    ("radius", "start", "label"),
    [
        ("-2/5", "x=0", "radius = -2/5"),  # a constant: refused when the model is read
        ("x - 3/10", "x=0", "is negative"),  # negative at the start
        ("1/(x - 1/4)", "x=1/4", "is not finite"),  # singular at the start
        ("1/10 + log(y)", "y=0", "is not finite"),
        ("sqrt(theta - 1)", "theta=0", "is not finite"),
    ],
)
def test_undefined_or_negative_outline_values_are_clear_errors(run_cli, tmp_path, radius,
                                                               start, label):
    world = _world(tmp_path, 'name = "w"\n[[obstacles]]\ndisc = { center = [4.0, 4.0], '
                             'radius = 0.5 }\n')
    error = _error(*run_cli("plan", _robot(tmp_path, radius), "--from", start, "--to",
                            "x=0.5", "--world", world, "--json"))
    assert error["kind"] == "model", error
    assert "geometry.discs[0].radius" in error["message"] and label in error["message"]


# --- 5. user text in figures: never parsed as markup ------------------------------------
@pytest.mark.parametrize("name", [r"$\sqrt{$ room", "[red]yard[/red] \x1b[2J$x^$"])
def test_world_names_are_literal_in_plot_titles(run_cli, tmp_path, name):
    world = _world(tmp_path, f"name = {json.dumps(name)}\n[[obstacles]]\n"
                             "disc = { center = [3.0, 3.0], radius = 0.5 }\n")
    figure = tmp_path / "plan.png"
    status, out, err = run_cli("plan", _robot(tmp_path), "--to", "x=0.3", "--world", world,
                               "--plot", str(figure), "--json")
    assert status == 0, (out, err)
    assert json.loads(out)["world"] == name
    assert figure.stat().st_size > 0


def test_a_world_name_is_bounded(run_cli, tmp_path):
    world = _world(tmp_path, f"name = {json.dumps('[b]' * 70)}\n")
    error = _error(*run_cli("plan", _robot(tmp_path), "--to", "x=0.3", "--world", world,
                            "--json"))
    assert error["kind"] == "world" and "characters" in error["message"]


@pytest.mark.parametrize("spec", ["car-trailers:10", "car-trailers:" + "7" * 5000])
def test_car_trailers_beyond_the_computable_bound_is_refused(run_cli, spec):
    from nilpotent.models import MAX_TRAILERS

    error = _error(*run_cli("analyze", spec, "--json"))
    assert error["kind"] == "model" and f"between 1 and {MAX_TRAILERS}" in error["message"]


def test_the_number_of_pieces_of_a_global_path_is_bounded():
    """A long path cut at the --max-piece floor is refused before billions of waypoints."""
    import numpy as np

    from nilpotent.cli.plan_options import MIN_MAX_PIECE
    from nilpotent.errors import ComputationLimitError
    from nilpotent.planning import global_planner as gp

    assert MIN_MAX_PIECE == gp.MIN_PIECE  # the option's floor is the planner's own
    path = [np.zeros(3), np.array([3.0, 4.0, 0.0]), np.array([3.0, 4.0, 12.0])]  # length 17
    assert len(gp._densify(path, 0.5)) == 1 + 10 + 24
    with pytest.raises(ComputationLimitError, match="--max-piece"):
        gp._densify(path, 17 / (gp.MAX_PIECES + 1) * 0.999)


@pytest.mark.parametrize("args", [
    ("plan", "unicycle", "--to", "x=0.1", "--to", "x=0.2"),
    ("analyze", "unicycle", "--at", "x=1", "--at=x=2"),
    ("sweep", "unicycle", "--bracket", "1,2", "--seed", "1", "--seed", "2"),
])
def test_a_single_valued_option_given_twice_is_refused(run_cli, args):
    """click keeps the last of two values silently; the CLI refuses the ambiguity."""
    status, out, err = run_cli(*args, "--json")
    assert status == 2 and "Traceback" not in err
    error = json.loads(out)["error"]
    assert error["kind"] == "usage" and "given twice" in error["message"]


def test_a_repeatable_option_may_be_repeated(run_cli):
    status, out, _ = run_cli("analyze", "trident-snake", "--param", "r=1", "--param", "l=2",
                             "--json")
    assert status == 0 and json.loads(out)["schema"] == "nilpotent/analysis@1"
