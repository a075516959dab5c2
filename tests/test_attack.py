"""Faults found by a second attack on the command line (issue 10, after the first fixes).

Each test is a reproducer of one kind of fault, checked as the interface promises it:
exit status 0 or 2 with one JSON object under ``--json``, no internal error, no planted
code imported.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from importlib._bootstrap_external import _code_to_timestamp_pyc  # type: ignore[attr-defined]
from importlib.util import cache_from_source
from pathlib import Path

import pytest

DATA = Path(__file__).parent / "data" / "hostile"


def _error(out: str) -> dict:
    data = json.loads(out)
    assert set(data) == {"error"}
    return data["error"]


@pytest.mark.parametrize(
    "bracket", ["\u00b2,1", "1" * 5000 + ",1", "\u0661,\u0662", "9" * 40 + ",1"])
def test_field_numbers_of_any_text_are_option_errors(run_cli, bracket):
    """Superscript or Arabic digits (str.isdigit is true, int() fails) and numbers past
    Python's 4300-digit limit were internal errors (exit 70)."""
    status, out, err = run_cli("simulate", "unicycle", "--bracket", bracket,
                               "--amplitude", "0.1", "--json")
    assert status == 2, err
    assert _error(out)["kind"] == "option"


def test_scaling_amplitude_count_is_limited(run_cli):
    amps = ",".join(f"{0.01 + k * 1e-6:.6f}" for k in range(5000))
    status, out, _ = run_cli("scaling", "unicycle", "--bracket", "1,2", "--amplitudes", amps,
                             "--json")
    assert status == 2
    assert _error(out)["kind"] == "computation-limit"


def test_vary_combinations_are_limited(run_cli):
    values = ",".join(str(1 + k / 1000) for k in range(3000))
    status, out, _ = run_cli("sweep", "trident-snake", "--bracket", "1,2", "--vary",
                             f"r={values}", "--json")
    assert status == 2
    error = _error(out)
    assert error["kind"] == "computation-limit" and "--vary" in error["message"]


@pytest.mark.parametrize("kind", ["loop", "self", "dangling", "long", "empty"])
def test_a_model_path_that_cannot_be_opened_is_named(run_cli, tmp_path, kind):
    if kind == "loop":
        (tmp_path / "a.toml").symlink_to(tmp_path / "b.toml")
        (tmp_path / "b.toml").symlink_to(tmp_path / "a.toml")
        spec, word = str(tmp_path / "a.toml"), "loop"
    elif kind == "self":
        (tmp_path / "s.toml").symlink_to(tmp_path / "s.toml")
        spec, word = str(tmp_path / "s.toml"), "loop"
    elif kind == "dangling":
        (tmp_path / "d.toml").symlink_to(tmp_path / "nowhere.toml")
        spec, word = str(tmp_path / "d.toml"), "broken"
    elif kind == "long":
        spec, word = "m" * 100_000 + ".toml", "too long"
    else:
        spec, word = "", "empty"
    status, out, err = run_cli("analyze", spec, "--json")
    assert status == 2, err
    error = _error(out)
    assert error["kind"] == "model" and word in error["message"]
    assert len(error["message"]) < 2200


def test_plan_plot_of_a_one_coordinate_model(run_cli, tmp_path):
    """plot_plan drew coordinate 1 against coordinate 2 and failed for n = 1 (exit 70)."""
    target = tmp_path / "plan.png"
    status, _, err = run_cli("plan", str(DATA / "one-coordinate.toml"), "--to", "x=0.1",
                             "--plot", str(target))
    assert status == 0, err
    assert target.stat().st_size > 0
    assert [p.name for p in tmp_path.iterdir()] == ["plan.png"]


def test_sweep_with_amplitudes_that_blow_up_some_lanes(run_cli):
    """A lane whose state blew up had a non-finite time; heyoka then refused the whole
    batch (ValueError: internal error). Now: a result, the lanes counted as early stops."""
    status, out, err = run_cli("sweep", "unicycle", "--bracket", "1,2", "--amplitudes",
                               "1e-300:1e300:40", "--json")
    assert status in (0, 2), err
    data = json.loads(out)
    assert "error" not in data or data["error"]["kind"] != "internal"


def _plant_bytecode(folder: Path, marker: Path) -> int:
    """Put a .pyc beside every generated module that would run ``marker``'s write."""
    count = 0
    bytecode = folder / "__pycache__"
    bytecode.mkdir(exist_ok=True)
    for source in folder.glob("*.py"):
        info = source.stat()
        code = compile(f"open({str(marker)!r}, 'a').write('planted')\n" + source.read_text(),
                       str(source), "exec")
        Path(cache_from_source(str(source))).write_bytes(
            _code_to_timestamp_pyc(code, int(info.st_mtime), info.st_size))
        count += 1
    return count


@pytest.mark.parametrize("pycache_mode", [0o777, 0o700])
def test_planted_bytecode_in_the_cache_is_never_run(tmp_path, pycache_mode):
    """The cache folder itself was checked (0700, owner, content hash of the .py), but the
    import read a .pyc from __pycache__: one planted there (a world-writable __pycache__,
    or one left from when the folder was unsafe) ran as the user."""
    cache = tmp_path / "cache"
    cache.mkdir(mode=0o700)
    marker = tmp_path / "planted"
    env = dict(os.environ, NILPOTENT_CACHE=str(cache), PYTHONDONTWRITEBYTECODE="1")
    args = [sys.executable, "-m", "nilpotent", "simulate", "unicycle", "--bracket", "1,2",
            "--amplitude", "0.1", "--json", "--quiet"]
    first = subprocess.run(args, env=env, capture_output=True, text=True, timeout=300)
    assert first.returncode == 0, first.stderr
    assert _plant_bytecode(cache, marker) > 0
    os.chmod(cache / "__pycache__", pycache_mode)
    env.pop("PYTHONDONTWRITEBYTECODE")
    second = subprocess.run(args, env=env, capture_output=True, text=True, timeout=300)
    assert second.returncode == 0, second.stderr
    json.loads(second.stdout)
    assert not marker.exists()
