"""The example worlds ship with the package and are reachable by name (``--world room``)
as well as by path; a file of that name, where one exists, wins."""

from __future__ import annotations

import json
import re
import tomllib

import pytest

from nilpotent.errors import WorldError
from nilpotent.planning.world import builtin_worlds, load_world


def test_the_shipped_worlds_are_room_parking_and_corner_and_each_names_itself():
    worlds = builtin_worlds()
    assert set(worlds) == {"room", "parking", "corner"}
    for name, file in worlds.items():
        assert tomllib.loads(file.read_text("utf-8"))["name"] == name


def test_a_world_by_name_is_the_same_as_by_path():
    by_name = load_world("room")
    by_path = load_world(str(builtin_worlds()["room"]))
    assert by_name.name == by_path.name == "room"
    assert by_name.bounds == by_path.bounds == ((-5.0, 13.0), (-6.0, 6.0))  # the file's
    assert by_name.polygons == by_path.polygons and by_name.discs == by_path.discs


def test_a_file_of_that_name_wins_over_the_builtin(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "room").write_text('name = "mine"\n[bounds]\nx = [0, 1]\ny = [0, 1]\n')
    # the file is read, not the built-in: a world file needs its suffix, so it is refused
    with pytest.raises(WorldError, match="suffix"):
        load_world("room")
    (tmp_path / "room.toml").write_text('name = "mine"\n[bounds]\nx = [0, 1]\ny = [0, 1]\n')
    assert load_world("room.toml").name == "mine"


def test_an_unknown_world_names_the_builtin_ones(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(WorldError, match=r"not found .*built-in world: corner, parking, room"):
        load_world("hall")


def test_the_plan_help_lists_every_builtin_world(run_cli):
    status, out, _ = run_cli("plan", "--help")
    assert status == 0
    text = re.sub(r"[\s│]+", " ", out)  # rich wraps the help into a box
    assert all(name in text for name in builtin_worlds()), text


@pytest.mark.slow
def test_plan_among_a_builtin_world_by_name(run_cli, tmp_path, monkeypatch):
    """A short move of the car with a trailer in the ``parking`` world (about 3 CPU-s)."""
    monkeypatch.chdir(tmp_path)  # no file called "parking" here: the name is the world's
    status, out, _ = run_cli(
        "plan", "car-trailers:1", "--from", "x=-2,y=1", "--to", "x=-1.8,y=1",
        "--world", "parking", "--json", "--quiet",
    )
    assert status == 0, out
    payload = json.loads(out)
    assert payload["world"] == "parking"
    assert payload["clearance"] is not None and payload["clearance"] > 0  # it was checked
    assert payload["error"] <= payload["tol"]


def test_an_unknown_world_on_the_command_line_is_a_world_error(run_cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, out, _ = run_cli("plan", "unicycle", "--to", "x=0.1", "--world", "nowhere", "--json")
    assert status == 2 and json.loads(out)["error"]["kind"] == "world"
    assert "room" in json.loads(out)["error"]["message"]


def test_the_example_worlds_by_path_are_the_shipped_ones():
    """``examples/worlds/*.toml`` stay where the README and earlier releases put them
    (``--world examples/worlds/room.toml``); they are the shipped files, byte for byte."""
    from pathlib import Path

    examples = Path(__file__).resolve().parents[1] / "examples" / "worlds"
    for name, file in builtin_worlds().items():
        assert (examples / f"{name}.toml").read_bytes() == file.read_bytes()
