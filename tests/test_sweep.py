"""Sweeps of bracket motions: scaling laws, agreement with single trajectories, engines.

Expected values come from hand derivations (unicycle, Heisenberg), from
MATH.md §6 (slopes w + 1), or from an independent path (``simulate`` of each
system with exact sympy maps between coordinates), never from the sweep itself.
"""

from __future__ import annotations

import csv
import json
import math
import sys

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from nilpotent.core.coordinates.approximation import approximate
from nilpotent.errors import ExpressionError, MissingExtraError, OptionError
from nilpotent.models import get_model
from nilpotent.numeric.integrate import Status
from nilpotent.numeric.signals import bracket_signal
from nilpotent.simulation import amplitude_range, compare_bracket_motion, simulate, sweep

AMPS = amplitude_range(0.01, 0.08, 4)
#: scipy: no numba compilation in a fresh cache (the batches here are tiny).
FAST = dict(engine="scipy", rtol=1e-11, atol=1e-13)


# --- scaling laws ---------------------------------------------------------------------


def test_trident_slopes_are_weight_plus_one():
    """MATH.md §6: from p the error of weight group w is O(A^{w+1}); the trident attains it."""
    result = sweep(get_model("trident-snake"), (1, 2), AMPS, **FAST)
    (fit,) = result.fits()
    assert result.weights == ((1, 1, 1, 2, 2, 2),)
    for w in ("1", "2"):
        assert fit["slopes"][w] == pytest.approx(int(w) + 1, abs=0.1)
    assert result.ok.all()


def test_unicycle_slopes_by_hand():
    """Unicycle x' = cos θ u1, y' = sin θ u1, θ' = u2 at 0; approximation x' = u1, y' = θ u1.

    θ is exact; cos θ − 1 = −θ²/2 makes the x error ∫θ²u1/2 = O(A³) (weight 1: slope 3);
    sin θ − θ = −θ³/6 makes the y error O(A⁴) (weight 2: slope 4).  Both are ≥ w + 1.
    """
    result = sweep(get_model("unicycle"), (1, 2), AMPS, **FAST)
    (fit,) = result.fits()
    assert fit["slopes"]["1"] == pytest.approx(3.0, abs=0.1)
    assert fit["slopes"]["2"] == pytest.approx(4.0, abs=0.1)
    for w, slope in fit["slopes"].items():
        assert slope >= fit["expected_slopes"][w] - 0.1


def test_heisenberg_is_its_own_approximation():
    """The Heisenberg system is nilpotent and homogeneous: every error is integration noise."""
    result = sweep(get_model("heisenberg"), (1, 2), AMPS, samples=3, radius=0.2, **FAST)
    (fit,) = result.fits()
    assert all(s is None for s in fit["slopes"].values())
    for errors in (*result.endpoint_by_weight.values(), *result.along_by_weight.values()):
        assert np.all(errors <= result.floor)


# --- agreement with single trajectories --------------------------------------------------


@pytest.mark.parametrize("omega", [1.0, 3.0])
def test_start_at_p_matches_compare_bracket_motion(omega):
    """Errors at q0 = p equal those of compare_bracket_motion, at any ω (ω drops out)."""
    system = get_model("trident-snake")
    result = sweep(system, (2, 3), [0.03, 0.1], time_samples=17, **FAST)
    for r, amp in enumerate(result.amplitude):
        comp = compare_bracket_motion(system, (2, 3), float(amp), omega=omega, samples=17,
                                      rtol=1e-11, atol=1e-13)
        for w in result.groups:
            assert result.endpoint_by_weight[w][r] == pytest.approx(
                comp.endpoint_by_weight[w], rel=1e-6, abs=1e-10)
            assert result.along_by_weight[w][r] == pytest.approx(
                comp.errors_by_weight[w], rel=1e-6, abs=1e-10)
        assert result.endpoint_error[r] == pytest.approx(comp.endpoint_error, rel=1e-6, abs=1e-10)


def test_start_near_p_matches_simulate():
    """From q0 ≠ p: the original from q0, the approximation from y(q0) mapped back exactly."""
    system = get_model("trident-snake").specialized()
    result = sweep(system, (1, 3), [0.05], samples=3, radius=0.1, seed=7, **FAST)
    approx = approximate(system)
    coords = approx.coordinates
    y_system = approx.as_system("y")
    for r in range(len(result)):
        q0 = result.start[r]
        sig = bracket_signal(system.m, 1, 3, 0.05)
        orig = simulate(system, sig, q0, engine="scipy", rtol=1e-11, atol=1e-13)
        np.testing.assert_allclose(result.final_original[r], orig.final, atol=1e-8)
        at_q0 = dict(zip(system.coordinates, q0, strict=True))
        y0 = [float(sp.N(e.xreplace(at_q0))) for e in coords.forward]
        appr = simulate(y_system, sig, y0, engine="scipy", rtol=1e-11, atol=1e-13)
        at_y = dict(zip(coords.names, appr.final, strict=True))
        back = [float(sp.N(e.xreplace(at_y))) for e in coords.inverse]
        np.testing.assert_allclose(result.final_approximation[r], back, atol=1e-8)
        assert result.endpoint_error[r] == pytest.approx(
            float(np.linalg.norm(orig.final - np.array(back))), rel=1e-5, abs=1e-9)


# --- designs, parameters, statuses -----------------------------------------------------


def test_grid_layout_and_seed():
    system = get_model("unicycle")
    a = sweep(system, [(1, 2), (2, 1)], [0.02, 0.04, 0.08], samples=4, radius=0.05, seed=3,
              **FAST)
    b = sweep(system, [(1, 2), (2, 1)], [0.02, 0.04, 0.08], samples=4, radius=0.05, seed=3,
              **FAST)
    assert len(a) == 2 * 4 * 3
    assert np.array_equal(a.start, b.start) and np.array_equal(a.final_original, b.final_original)
    assert np.all(a.offset <= 0.05 + 1e-15)
    # every start meets every amplitude and both orientations of the loop
    assert len({tuple(s) for s in a.start}) == 4
    assert sorted(set(a.amplitude)) == [0.02, 0.04, 0.08]
    # the reversed loop moves along −[X1,X2]: the bracket direction (y) changes sign
    # at p's neighbourhood, to first order: compare the y-displacements' signs
    dy = a.final_original[:, 1] - a.start[:, 1]
    forward = (a.bracket[:, 0] == 1) & (a.amplitude == 0.08)
    backward = (a.bracket[:, 0] == 2) & (a.amplitude == 0.08)
    assert np.all(np.sign(dy[forward]) == -np.sign(dy[backward]))


def test_random_design():
    system = get_model("unicycle")
    r = sweep(system, [(1, 2), (2, 1)], [0.01, 0.1], samples=40, radius=0.2, seed=1,
              design="random", **FAST)
    assert len(r) == 40
    assert np.all((r.amplitude >= 0.01) & (r.amplitude <= 0.1))
    assert {tuple(b) for b in r.bracket} == {(1, 2), (2, 1)}
    assert np.all(r.offset <= 0.2 + 1e-15)
    other = sweep(system, [(1, 2), (2, 1)], [0.01, 0.1], samples=40, radius=0.2, seed=2,
                  design="random", **FAST)
    assert not np.array_equal(r.amplitude, other.amplitude)


def test_vary_parameters_equals_separate_sweeps():
    system = get_model("trident-snake")
    both = sweep(system, (1, 2), [0.05], vary={"l": [1, "1/2"]}, **FAST)
    assert both.parameter_sets == ({"l": "1"}, {"l": "1/2"})
    half = sweep(system.with_parameters({"l": sp.Rational(1, 2)}), (1, 2), [0.05], **FAST)
    rows = both.parameter_index == 1
    np.testing.assert_array_equal(both.final_original[rows], half.final_original)
    assert not np.allclose(both.final_original[~rows], half.final_original)


def test_blow_ups_are_reported_not_raised():
    """|x_k| > bound stops a trajectory: its status says so and its errors are NaN."""
    r = sweep(get_model("heisenberg"), (1, 2), [0.01, 0.5], bound=0.3, **FAST)
    big = r.amplitude == 0.5
    assert np.all(r.status_original[big] == Status.BLOW_UP)
    assert np.all(r.status_original[~big] == Status.SUCCESS)
    assert np.all(np.isnan(r.endpoint_error[big]))
    summary = r.summary()
    assert summary["blow_ups"] == 1 and summary["succeeded"] == 1
    json.dumps(r.to_json(include_samples=True), allow_nan=False)


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(design="sobol"),
        dict(samples=3, radius=0.0),
        dict(design="random"),
        dict(amplitudes=[0.1, -0.1]),
        dict(amplitudes=[]),
        dict(brackets=(1, 1)),
        dict(brackets=[(1, 4)]),
        dict(time_samples=1),
        dict(vary={"nope": [1]}),
        dict(vary={"r": "1,2"}),
        dict(seed=-1),
    ],
)
def test_bad_requests(kwargs):
    args = dict(brackets=(1, 2), amplitudes=[0.1])
    args.update(kwargs)
    system = get_model("trident-snake") if "vary" in kwargs else get_model("unicycle")
    with pytest.raises(OptionError):
        sweep(system, args.pop("brackets"), args.pop("amplitudes"), **args)


def test_vary_text_goes_through_the_grammar():
    with pytest.raises(ExpressionError):
        sweep(get_model("trident-snake"), (1, 2), [0.1], vary={"r": ["__import__('os')"]})


# --- export ---------------------------------------------------------------------------


def test_csv_and_json(tmp_path):
    r = sweep(get_model("unicycle"), (1, 2), [0.02, 0.04], samples=2, radius=0.01, **FAST)
    path = r.to_csv(tmp_path / "s.csv")
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == len(r) == 4
    for k, row in enumerate(rows):
        assert float(row["amplitude"]) == r.amplitude[k]
        assert float(row["start_theta"]) == r.start[k, 2]
        assert float(row["endpoint_w2"]) == r.endpoint_by_weight[2][k]
        assert row["status_original"] == "success"
    obj = json.loads(json.dumps(r.to_json(), allow_nan=False))
    assert obj["schema"] == "nilpotent/sweep@1"
    assert obj["parameters"]["omega"] == 1.0
    assert obj["backend"] == "local" and obj["engine"] == "scipy"
    assert {"python", "nilpotent", "numpy", "sympy"} <= set(obj["versions"])
    assert obj["summary"]["count"] == 4
    assert set(obj["fits"][0]["slopes"]) == {"1", "2"}


@settings(max_examples=30, deadline=None)
@given(low=st.floats(1e-4, 1.0), ratio=st.floats(1.0, 100.0), count=st.integers(2, 12))
def test_amplitude_range_is_geometric(low, ratio, count):
    amps = amplitude_range(low, low * ratio, count)
    assert len(amps) == count
    assert amps[0] == pytest.approx(low) and amps[-1] == pytest.approx(low * ratio)
    logs = np.diff(np.log(amps))
    np.testing.assert_allclose(logs, math.log(ratio) / (count - 1), atol=1e-9)


# --- Dask -----------------------------------------------------------------------------


def test_missing_dask_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(MissingExtraError, match=r'pip install "nilpotent\[dask\]"'):
        sweep(get_model("unicycle"), (1, 2), [0.1], dask="local")


@pytest.mark.slow
def test_dask_local_equals_local():
    pytest.importorskip("distributed")
    system = get_model("unicycle")
    kw = dict(samples=300, radius=0.05, seed=5, chunk_size=1000, engine="numba")
    local = sweep(system, (1, 2), [0.02, 0.05, 0.1, 0.2], **kw)
    remote = sweep(system, (1, 2), [0.02, 0.05, 0.1, 0.2], dask="local", **kw)
    assert remote.backend == "dask" and remote.scheduler
    np.testing.assert_array_equal(local.final_original, remote.final_original)
    np.testing.assert_array_equal(local.final_approximation, remote.final_approximation)
    for w in local.groups:
        np.testing.assert_array_equal(local.endpoint_by_weight[w], remote.endpoint_by_weight[w])


def test_dask_needs_big_chunks():
    pytest.importorskip("distributed")
    with pytest.raises(OptionError, match="1000"):
        sweep(get_model("unicycle"), (1, 2), [0.1], dask="local", chunk_size=10)


# --- CLI ------------------------------------------------------------------------------


@pytest.fixture
def sweep_cli(run_cli):
    import nilpotent.cli.cmd_sweep  # noqa: F401  (registers the command)

    return run_cli


def test_cli_json_and_csv(sweep_cli, tmp_path):
    out = tmp_path / "rows.csv"
    status, stdout, _ = sweep_cli("sweep", "unicycle", "--bracket", "1,2", "--amplitudes",
                                  "0.01:0.08:4", "--out", str(out), "--json")
    assert status == 0
    obj = json.loads(stdout)
    assert obj["schema"] == "nilpotent/sweep@1"
    assert obj["fits"][0]["slopes"]["2"] == pytest.approx(4.0, abs=0.1)
    with open(out, newline="") as handle:
        assert len(list(csv.DictReader(handle))) == 4


def test_plot_draws_every_group_and_fit():
    r = sweep(get_model("trident-snake"), (1, 2), AMPS, **FAST)
    _, ax = r.plot()
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "weight 1" in labels and "weight 2" in labels
    assert sum(lab.startswith("slope") for lab in labels) == 2
    _, ax2 = r.plot(which="endpoint")
    assert ax2 is not ax
    with pytest.raises(OptionError):
        r.plot(which="sideways")


def test_cli_plot(sweep_cli, tmp_path):
    fig = tmp_path / "s.png"
    status, stdout, _ = sweep_cli("sweep", "unicycle", "--bracket", "1,2", "--amplitudes",
                                  "0.02,0.04", "--plot", str(fig))
    assert status == 0 and fig.stat().st_size > 0 and "figure written" in stdout
    status, _, _ = sweep_cli("sweep", "unicycle", "--bracket", "1,2", "--plot",
                             str(tmp_path / "s.nope"))
    assert status == 2


def test_cli_table(sweep_cli):
    status, stdout, _ = sweep_cli("sweep", "heisenberg", "--bracket", "1,2", "--amplitudes",
                                  "0.1,0.2", "--samples", "2", "--radius", "0.1")
    assert status == 0
    assert "succeeded 4 of 4" in stdout and "exact" in stdout


@pytest.mark.parametrize(
    "args",
    [
        ["--amplitudes", "0.1:0.01"],
        ["--amplitudes", "0.2:0.1:3"],
        ["--amplitudes", "-1"],
        ["--design", "latin"],
        ["--samples", "3"],
        ["--vary", "r"],
        ["--vary", "r=__import__('os')"],
        ["--bracket", "1,1"],
    ],
)
def test_cli_bad_input(sweep_cli, args):
    status, stdout, _ = sweep_cli("sweep", "unicycle", "--bracket", "1,2", *args, "--json")
    assert status == 2
    assert "error" in json.loads(stdout)


def test_cli_missing_dask(sweep_cli, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    status, stdout, _ = sweep_cli("sweep", "unicycle", "--bracket", "1,2", "--dask", "local",
                                  "--json")
    assert status == 2
    err = json.loads(stdout)["error"]
    assert err["kind"] == "missing-extra" and "nilpotent[dask]" in err["message"]


def test_cli_random_design_counts_its_rows_not_rows_times_amplitudes(sweep_cli):
    """``--design random`` runs ``--samples`` rows (each with its own amplitude), so the
    motion limit counts rows: 300 rows over 10,000 amplitudes is 300 motions, well within
    the limit, though 300 x 10,000 would exceed it."""
    status, stdout, _ = sweep_cli("sweep", "unicycle", "--bracket", "1,2", "--amplitudes",
                                  "0.01:0.08:10000", "--design", "random", "--samples", "300",
                                  "--radius", "0.1", "--json")
    assert status == 0, stdout
    assert json.loads(stdout)["summary"]["count"] == 300
