"""The command line as users and outside tests see it (INTERFACE.md): JSON schemas,
exit statuses, clean stdout, independent checks of the numbers."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest
import sympy as sp

from nilpotent.core.model.expressions import parse_expression


def _exact(text: str) -> sp.Expr:
    return parse_expression(text, {})


def test_analyze_unicycle_json_matches_hand_derivation(run_cli):
    status, out, err = run_cli("analyze", "unicycle", "--json")
    assert status == 0, err
    data = json.loads(out)
    assert data["schema"] == "nilpotent/analysis@1"
    assert data["coordinates"] == ["x", "y", "theta"]
    assert data["growth_vector"] == [2, 3]
    assert data["weights"] == [1, 1, 2]
    assert data["step"] == 2
    assert data["bracket_generating"] is True
    assert data["regular"] is True
    # Hand derivation: X1 = cos θ ∂x + sin θ ∂y, X2 = ∂θ,
    # [X1, X2] = DX2·X1 − DX1·X2 = −(−sin θ, cos θ, 0) = (sin θ, −cos θ, 0) → (0, −1, 0) at 0.
    assert data["frame"] == ["X1", "X2", "[X1,X2]"]
    values = [[_exact(v) for v in col] for col in data["frame_values"]]
    assert values == [[1, 0, 0], [0, 0, 1], [0, -1, 0]]


def test_analyze_at_point_exact_values(run_cli):
    status, out, err = run_cli("analyze", "unicycle", "--at", "theta=pi/3", "--json")
    assert status == 0, err
    data = json.loads(out)
    assert data["point"]["theta"] == "pi/3"
    x1 = [_exact(v) for v in data["frame_values"][0]]
    assert sp.simplify(x1[0] - sp.Rational(1, 2)) == 0
    assert sp.simplify(x1[1] - sp.sqrt(3) / 2) == 0


def test_analyze_martinet_singular(run_cli):
    status, out, _ = run_cli("analyze", "martinet", "--json")
    assert status == 0
    data = json.loads(out)
    assert data["growth_vector"] == [2, 2, 3]
    assert data["weights"] == [1, 1, 3]
    assert data["regular"] is False


def test_analyze_model_file(run_cli, tmp_path):
    model = tmp_path / "heis.toml"
    model.write_text(
        textwrap.dedent(
            """
            name = "scrambled"
            coordinates = ["b", "a", "c"]
            [[fields]]
            a = "1"
            c = "-b/2"
            [[fields]]
            b = "1"
            c = "a/2"
            """
        )
    )
    status, out, err = run_cli("analyze", str(model), "--json")
    assert status == 0, err
    data = json.loads(out)
    assert data["model"] == "scrambled"
    assert data["growth_vector"] == [2, 3]
    # [X1, X2] = DX2·X1 − DX1·X2: X1 = ∂a − b/2 ∂c, X2 = ∂b + a/2 ∂c → (1/2 + 1/2) ∂c = ∂c
    assert [_exact(v) for v in data["frame_values"][2]] == [0, 0, 1]


@pytest.mark.parametrize(
    "args, kind",
    [
        (["analyze", "no-such-model", "--json"], "model"),
        (["analyze", "unicycle", "--at", "z=1", "--json"], "point"),
        (["analyze", "unicycle", "--at", "theta=__import__('os')", "--json"], None),
        (["analyze", "unicycle", "--param", "q=1", "--json"], "model"),
        (["approximate", "unicycle", "--method", "magic", "--json"], "option"),
    ],
)
def test_bad_input_exit_2_with_json_error(run_cli, args, kind):
    status, out, _ = run_cli(*args)
    assert status == 2
    data = json.loads(out)
    assert set(data) == {"error"}
    assert data["error"]["message"]
    if kind is not None:
        assert data["error"]["kind"] == kind


def test_bad_input_without_json_has_no_traceback(run_cli):
    status, _out, err = run_cli("analyze", "unicycle", "--at", "theta=1+")
    assert status == 2
    assert "Traceback" not in err
    assert "theta" in err or "1+" in err


def test_hostile_model_file_refused(run_cli, tmp_path):
    model = tmp_path / "evil.toml"
    model.write_text('coordinates = ["x"]\n[[fields]]\nx = "().__class__.__bases__"\n')
    status, _out, err = run_cli("analyze", str(model))
    assert status == 2
    assert "evil.toml" in err
    assert "Traceback" not in err


def test_models_lists_builtins(run_cli):
    status, out, _ = run_cli("models", "--json")
    assert status == 0
    names = {m["name"] for m in json.loads(out)["models"]}
    assert {"trident-snake", "trident-snake-paper", "trident-snake-joints", "unicycle",
            "heisenberg", "engel", "cartan", "martinet"} <= names
    assert any(n.startswith("car-trailers") for n in names)


def test_approximate_json_schema_and_independent_checks(run_cli):
    status, out, err = run_cli("approximate", "heisenberg", "--json")
    assert status == 0, err
    data = json.loads(out)
    assert data["schema"] == "nilpotent/approximation@1"
    names = data["privileged"]["names"]
    ys = sp.symbols(names)
    table = dict(zip(names, ys, strict=True))
    fields = [[parse_expression(c, table) for c in f] for f in data["fields"]]
    # The approximation's first bracket must equal the privileged frame value
    # e_3 up to the basis: check it is a nonzero constant along y3 only.
    X1, X2 = (sp.Matrix(f) for f in fields)
    J = lambda F: F.jacobian(sp.Matrix(ys))  # noqa: E731
    br = sp.simplify(J(X2) * X1 - J(X1) * X2)
    assert br[0] == 0 and br[1] == 0 and br[2] != 0 and br[2].free_symbols == set()
    assert data["certificate"]["orders"] == data["weights"] == [1, 1, 2]


def test_console_script_runs(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "nilpotent", "analyze", "heisenberg", "--json"],
        capture_output=True, text=True, check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["growth_vector"] == [2, 3]


def test_core_does_not_import_numeric_stack():
    code = (
        "import sys, nilpotent.core.analysis.filtration, nilpotent.core.coordinates.approximation;"
        "bad = [m for m in ('matplotlib', 'scipy') if m in sys.modules];"
        "print(','.join(bad))"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == ""
