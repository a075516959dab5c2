"""`nilpotent simulate` and `nilpotent scaling` as users see them (INTERFACE.md)."""

from __future__ import annotations

import json
import math

import pytest


def test_simulate_json_schema_and_heisenberg_values(run_cli):
    status, out, err = run_cli(
        "simulate", "heisenberg", "--bracket", "1,2", "--amplitude", "0.2", "--periods", "2",
        "--json",
    )
    assert status == 0, err
    data = json.loads(out)
    for key in ("schema", "model", "coordinates", "point", "bracket", "amplitude", "omega",
                "periods", "final", "prediction", "errors", "tolerance"):
        assert key in data
    assert data["schema"] == "nilpotent/simulation@1"
    assert data["bracket"] == [1, 2] and data["periods"] == 2 and data["omega"] == 1.0
    assert set(data["final"]) == {"original", "approximation"}
    assert set(data["errors"]) >= {"endpoint", "max", "by_weight"}
    assert set(data["errors"]["by_weight"]) == {"1", "2"}
    # exact: x3 moves by K·πA²
    assert data["prediction"] == pytest.approx([0, 0, 2 * math.pi * 0.04], abs=1e-15)
    assert data["final"]["original"] == pytest.approx(data["prediction"], abs=1e-9)


def test_simulate_at_a_point_with_parameters(run_cli):
    status, out, err = run_cli(
        "simulate", "trident-snake", "--bracket", "2,3", "--amplitude", "0.05",
        "--at", "theta=1/2", "--param", "l=2", "--json",
    )
    assert status == 0, err
    data = json.loads(out)
    assert data["point"]["theta"] == "1/2"
    assert data["errors"]["endpoint"] < 0.05**2


@pytest.mark.parametrize(
    "args",
    [
        ("--bracket", "1,1", "--amplitude", "0.1"),
        ("--bracket", "1,4", "--amplitude", "0.1"),
        ("--bracket", "x", "--amplitude", "0.1"),
        ("--bracket", "1,2", "--amplitude", "0"),
        ("--bracket", "1,2", "--amplitude", "0.1", "--omega", "-1"),
        ("--bracket", "1,2", "--amplitude", "0.1", "--periods", "0"),
        ("--bracket", "1,2", "--amplitude", "0.1", "--plot", "out.unknown"),
    ],
)
def test_simulate_bad_input_exit_2_with_json_error(run_cli, args):
    status, out, _ = run_cli("simulate", "unicycle", *args, "--json")
    assert status == 2
    assert json.loads(out)["error"]["kind"] == "option"


def test_simulate_plot_writes_a_png(run_cli, tmp_path):
    target = tmp_path / "sim.png"
    status, out, err = run_cli(
        "simulate", "unicycle", "--bracket", "1,2", "--amplitude", "0.1", "--plot", str(target)
    )
    assert status == 0, err
    assert target.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "end-point difference" in out


def test_scaling_json_and_plot(run_cli, tmp_path):
    target = tmp_path / "scaling.svg"
    status, out, err = run_cli(
        "scaling", "trident-snake", "--bracket", "1,3", "--amplitudes", "0.01,0.02,0.04",
        "--json", "--plot", str(target),
    )
    assert status == 0, err
    data = json.loads(out)
    assert data["schema"] == "nilpotent/scaling@1"
    assert data["amplitudes"] == [0.01, 0.02, 0.04]
    assert data["expected_slopes"] == {"1": 2, "2": 3}
    assert set(data["errors"]) == set(data["slopes"]) == {"1", "2"}
    assert all(len(v) == 3 for v in data["errors"].values())
    for w, slope in data["slopes"].items():
        assert abs(slope - (int(w) + 1)) < 0.15
    assert target.read_text().lstrip().startswith("<?xml")


@pytest.mark.parametrize("amps", ["0.1", "0.1,0.1", "0.1,-0.2", "a,b"])
def test_scaling_bad_amplitudes_exit_2(run_cli, amps):
    status, out, _ = run_cli("scaling", "unicycle", "--bracket", "1,2", "--amplitudes", amps,
                             "--json")
    assert status == 2
    assert json.loads(out)["error"]["kind"] == "option"
