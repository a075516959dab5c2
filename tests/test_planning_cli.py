"""``nilpotent plan``: JSON schema, independent check of the controls, errors, figures."""

from __future__ import annotations

import json

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import nilpotent.cli.cmd_plan  # noqa: F401  (registers the command)
from nilpotent.models import get_model


def resimulate(name: str, start, segments) -> np.ndarray:
    system = get_model(name)
    mat = sp.lambdify([system.coordinates], sp.Matrix(system.specialized_fields).T, "numpy")
    x = np.asarray(start, dtype=float)
    for seg in segments:
        omega = seg["omega"]

        def u(t, seg=seg, omega=omega):
            out = []
            for inp in seg["inputs"]:
                v = inp["constant"]
                v += sum(a * np.cos((k + 1) * omega * t) for k, a in enumerate(inp["cos"]))
                v += sum(b * np.sin((k + 1) * omega * t) for k, b in enumerate(inp["sin"]))
                out.append(v)
            return np.array(out)

        def rhs(t, z, u=u):
            return np.asarray(mat(z), dtype=float) @ u(t)

        x = solve_ivp(rhs, (0, seg["duration"]), x, method="DOP853", rtol=1e-13,
                      atol=1e-14).y[:, -1]
    return x


def test_plan_json_controls_reach_the_goal(run_cli):
    status, out, _ = run_cli("plan", "unicycle", "--from", "x=1/10", "--to",
                             "x=1/5,y=1/20,theta=-1/10", "--tol", "1e-9", "--json")
    assert status == 0
    data = json.loads(out)
    assert data["schema"] == "nilpotent/plan@1"
    assert data["model"] == "unicycle" and data["coordinates"] == ["x", "y", "theta"]
    assert data["from"] == [0.1, 0.0, 0.0] and data["to"] == [0.2, 0.05, -0.1]
    assert data["error"] <= 1e-9 and all("error" in it for it in data["iterations"])
    reached = resimulate("unicycle", data["from"], data["segments"])
    assert np.linalg.norm(reached - np.array(data["to"])) <= 1e-8


@pytest.mark.slow
def test_plan_human_output_and_figures(run_cli, tmp_path):
    png = tmp_path / "plan.png"
    gif = tmp_path / "plan.gif"
    status, out, _ = run_cli("plan", "trident-snake", "--to", "x=1/20,phi1=1/10",
                             "--plot", str(png), "--animate", str(gif), "--time-limit", "900")
    assert status == 0, out
    assert "goal reached" in out
    assert png.stat().st_size > 1000
    assert gif.read_bytes()[:6] in (b"GIF87a", b"GIF89a")


@pytest.mark.parametrize(
    ("args", "kind"),
    [
        (("plan", "unicycle", "--to", "x=1", "--tol", "-1"), "option"),
        (("plan", "unicycle", "--to", "q=1"), "point"),
        (("plan", "unicycle", "--to", "x=__import__('os')"), None),
        (("plan", "unicycle", "--to", "x=1/10", "--anchor", "moon"), "option"),
        (("plan", "unicycle", "--to", "x=1/10", "--animate", "a.mp4"), "option"),
        (("plan", "martinet", "--to", "x1=1/10"), "singular-point"),
        (("plan", "no-such-model", "--to", "x=1"), "model"),
    ],
)
def test_plan_errors_exit_2_with_json(run_cli, args, kind):
    status, out, _ = run_cli(*args, "--json")
    assert status == 2
    err = json.loads(out)["error"]
    if kind is not None:
        assert err["kind"] == kind
    assert err["message"]
