"""Issue 21 items 4-7: honest speed options, progress with ETA, figures fit for a paper,
papercuts (``--version``, help texts, defaults, pasteable formulas, sampled inputs).

Cheap and deterministic: no timing asserts; figures are inspected through the returned
axes (labels, line styles, z-order), never by pixels.
"""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

from nilpotent import progress
from nilpotent.errors import OptionError
from nilpotent.models import get_model

# --- command line: options and papercuts ---------------------------------------------


def test_version_prints_the_package_version(run_cli):
    from nilpotent.version import __version__

    status, out, _ = run_cli("--version")
    assert status == 0
    assert out.strip() == f"nilpotent {__version__}"


def test_quiet_and_debug_appear_in_the_help(run_cli):
    status, out, _ = run_cli("--help")
    assert status == 0
    for flag in ("--version", "--quiet", "--debug"):
        assert flag in out


@pytest.mark.parametrize(("value", "kind"), [("1", "option"), ("1001", "computation-limit")])
def test_time_samples_is_bounded(run_cli, value, kind):
    status, out, _ = run_cli("sweep", "unicycle", "--bracket", "1,2", "--time-samples", value,
                             "--json")
    assert status == 2
    error = json.loads(out)["error"]
    assert error["kind"] == kind and "--time-samples" in error["message"]


def test_time_samples_times_chunk_size_is_bounded(run_cli):
    status, out, _ = run_cli("sweep", "unicycle", "--bracket", "1,2", "--time-samples", "1000",
                             "--chunk-size", "1000000", "--json")
    assert status == 2
    assert json.loads(out)["error"]["kind"] == "computation-limit"


def test_time_samples_reaches_the_sweep(run_cli):
    status, out, err = run_cli("sweep", "unicycle", "--bracket", "1,2", "--amplitudes",
                               "0.05,0.1", "--time-samples", "2", "--json")
    assert status == 0, err
    data = json.loads(out)
    assert data["parameters"]["time_samples"] == 2
    # with 2 samples (start and end) the error along the way is the end-point error
    for w, along in data["summary"]["along_by_weight"].items():
        assert along["max"] == pytest.approx(data["summary"]["endpoint_by_weight"][w]["max"])


def test_simulate_has_a_default_amplitude(run_cli):
    status, out, err = run_cli("simulate", "unicycle", "--bracket", "1,2", "--json")
    assert status == 0, err
    assert json.loads(out)["amplitude"] == 0.1


def test_plain_text_approximation_uses_one_minus_sign(run_cli):
    status, out, err = run_cli("approximate", "unicycle")
    assert status == 0, err
    assert "\u2212" not in out  # U+2212 beside ASCII '-' does not paste into Python
    assert "-" in out


# --- progress ----------------------------------------------------------------------------


@pytest.fixture
def reports_on():
    was = progress.enabled()
    progress.configure(enabled=True)
    yield
    progress.configure(enabled=was)


def test_terminal_bar_has_rate_and_time_left_columns():
    from rich.progress import BarColumn, MofNCompleteColumn, TimeRemainingColumn

    columns = progress.rich_columns(100)
    assert any(isinstance(c, TimeRemainingColumn) for c in columns)
    assert any(isinstance(c, MofNCompleteColumn) for c in columns)
    assert any(isinstance(c, BarColumn) for c in columns)
    assert any(type(c).__name__ == "RateColumn" for c in columns)


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_nested_tasks_share_one_terminal_bar(reports_on):
    out = _Terminal()
    with progress.progress("outer", total=3, stream=out) as bar:
        with progress.progress(progress.COMPILING, stream=out) as inner:
            assert inner._bar is bar._bar  # one live display, a second line
        bar.advance(3)
    assert progress.current() is None


def test_plain_lines_say_rate_and_time_left(reports_on, monkeypatch):
    monkeypatch.setattr(progress, "PLAIN_INTERVAL", 0.0)
    out = io.StringIO()
    with progress.progress("work", total=4, stream=out) as bar:
        for _ in range(4):
            bar.advance()
    lines = out.getvalue().splitlines()
    assert any("/s" in line and "left" in line for line in lines), lines


def test_report_updates_the_innermost_task(reports_on, monkeypatch):
    monkeypatch.setattr(progress, "PLAIN_INTERVAL", 0.0)
    out = io.StringIO()
    with progress.progress("plan", stream=out) as bar:
        progress.report(progress.ProgressEvent("pieces steered", 2, 5))
        assert (bar.completed, bar.total) == (2, 5)
    assert "pieces steered" in out.getvalue()
    progress.report(progress.ProgressEvent("plan", 1, 2))  # no task: nothing happens


def test_progress_goes_to_stderr_and_quiet_silences_it(run_cli, monkeypatch):
    monkeypatch.setattr(progress, "PLAIN_INTERVAL", 0.0)
    monkeypatch.setattr(progress, "HEARTBEAT", 0.0)
    args = ("sweep", "unicycle", "--bracket", "1,2", "--amplitudes", "0.05,0.1", "--samples",
            "20", "--radius", "0.01", "--time-samples", "2", "--json")
    status, out, err = run_cli(*args)
    assert status == 0
    json.loads(out)  # stdout is the JSON object only
    assert "nilpotent: bracket motions" in err
    status, out, err = run_cli(*args, "--quiet")
    assert status == 0 and err == ""
    json.loads(out)


# --- figures -----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def unicycle_comparison():
    from nilpotent.simulation import compare_bracket_motion

    return compare_bracket_motion(get_model("unicycle"), (1, 2), 0.5)


def test_comparison_figure_labels_styles_and_floor(unicycle_comparison):
    comp = unicycle_comparison
    _fig, (ax_states, ax_errors) = comp.plot()
    for ax in (ax_states, ax_errors):
        assert ax.get_xlabel() and ax.get_ylabel()
    assert "rad" in ax_states.get_ylabel()
    n = comp.system.n
    drawn = [line for line in ax_states.get_lines() if len(line.get_xdata())]
    originals, approximations = drawn[0::2][:n], drawn[1::2][:n]
    assert all(line.get_linestyle() == "-" for line in originals)
    assert all(line.get_linestyle() == "--" for line in approximations)
    assert min(a.get_zorder() for a in approximations) > max(o.get_zorder() for o in originals)
    legend = [t.get_text() for t in ax_states.get_legend().get_texts()]
    assert "original (solid)" in legend and "approximation (dashed)" in legend
    assert ax_errors.get_ylim()[0] >= comp.tolerance / 10  # not down to 1e-17


def test_paper_comparison_follows_the_same_convention(unicycle_comparison):
    from nilpotent.viz import plot_motion_comparison

    rng = np.random.default_rng(0)
    qo = np.cumsum(rng.normal(size=(30, 6)) * 0.01, axis=0)
    qa = qo + 0.01
    _fig, (ax, axt) = plot_motion_comparison(qo, qa, times=np.linspace(0, 1, 30))
    assert ax.get_xlabel() and ax.get_ylabel() and axt.get_xlabel() and axt.get_ylabel()
    lines = axt.get_lines()
    originals, approximations = lines[0::2], lines[1::2]
    assert {line.get_linestyle() for line in originals} == {"-"}
    assert {line.get_linestyle() for line in approximations} == {"--"}
    assert min(a.get_zorder() for a in approximations) > max(o.get_zorder() for o in originals)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "original (solid)" in legend and "approximation (dashed)" in legend


def test_trajectory_figure_has_labels():
    from nilpotent.numeric.signals import bracket_signal
    from nilpotent.simulation import simulate

    s = get_model("unicycle")
    _fig, ax = simulate(s, bracket_signal(s.m, 1, 2, amplitude=0.1)).plot()
    assert ax.get_xlabel() and ax.get_ylabel()


@pytest.fixture(scope="module")
def unicycle_plan():
    import nilpotent

    s = get_model("unicycle")
    return nilpotent.plan(s, (0.0, 0.0, 0.0), (0.3, 0.1, 0.2))


def test_global_plan_plot_returns_the_labelled_figure(unicycle_plan):
    from matplotlib.figure import Figure

    fig = unicycle_plan.plot()
    assert isinstance(fig, Figure) and len(fig.axes) == 3
    for ax in fig.axes:
        assert ax.get_xlabel() and ax.get_ylabel()
    # Plan.plot() draws the same figure (one function, plot_plan_world)
    other = unicycle_plan.plan.plot()
    assert [a.get_xlabel() for a in other.axes] == [a.get_xlabel() for a in fig.axes]
    assert [a.get_ylabel() for a in other.axes] == [a.get_ylabel() for a in fig.axes]


def test_animation_is_framed_to_the_motion(unicycle_plan):
    from nilpotent.viz.plan_world import frame_motion

    states = unicycle_plan.plan.trajectory.states
    lo, hi = frame_motion(states, None)
    extent = (states[:, :2].max(axis=0) - states[:, :2].min(axis=0)).max()
    assert np.all(lo <= states[:, :2].min(axis=0)) and np.all(hi >= states[:, :2].max(axis=0))
    assert (hi - lo).max() <= 2 * extent  # the motion fills the view: not a few pixels


# --- the audit table -----------------------------------------------------------------------


def test_long_formulas_are_cut_between_top_level_terms():
    from nilpotent.report.document import split_latex, wrapped_formula

    latex = (r"g_1 = \cos\theta \partial_x +\sin\theta\partial_y+\sin\phi_1\partial_{\phi_1}"
             r"+\sin(\phi_2+\tfrac{2\pi}{3})\partial_{\phi_2} +\sin(\phi_3+\tfrac{4\pi}{3})"
             r"\partial_{\phi_3}")
    pieces = split_latex(latex)
    assert len(pieces) > 1 and "".join(pieces) == latex
    for piece in pieces:
        assert piece.count("{") == piece.count("}") and piece.count("(") == piece.count(")")
    html = wrapped_formula(latex)
    assert html.count("<math") == len(pieces) and 'data-latex="' in html


def test_the_papers_sentences_show_no_raw_latex():
    from nilpotent.report.document import _paper_cell

    cell = _paper_cell(r"Fig. \ref{figg5} shows the $g_5$ motion along the $x$--axis.")
    assert "$" not in cell and r"\ref" not in cell and cell.count("<math") == 2


# --- sampled and callable inputs -------------------------------------------------------------


def test_sampled_and_callable_inputs():
    from nilpotent.numeric import compile_system, integrate
    from nilpotent.simulation import simulate

    s = get_model("unicycle")
    times = np.linspace(0.0, 1.0, 11)
    values = np.column_stack([np.ones(11), np.zeros(11)])  # drive straight: x = t
    for hold in ("linear", "zero"):
        assert np.allclose(simulate(s, (times, values), hold=hold).final, [1, 0, 0])
    assert np.allclose(simulate(s, (times, values.T)).final, [1, 0, 0])  # (m, K) layout
    # u = (cos t, 1): theta = t, x' = cos^2 t, y' = cos t sin t; at pi/2: (pi/4, 1/2, pi/2)
    traj = simulate(s, lambda t: [np.cos(t), 1.0], duration=np.pi / 2)
    assert np.allclose(traj.final, [np.pi / 4, 0.5, np.pi / 2], atol=1e-8)
    batch = integrate(compile_system(s), np.zeros((2, 3)), (times, values))
    assert np.allclose(batch.final, [[1, 0, 0], [1, 0, 0]])


@pytest.mark.parametrize("bad", [
    "text",
    (np.array([0.0, 1.0]), np.zeros((3, 2))),       # K mismatch
    (np.array([0.5, 1.0]), np.zeros((2, 2))),       # does not start at 0
    (np.array([0.0, 0.0]), np.zeros((2, 2))),       # not increasing
    (np.array([0.0, 1.0]), np.full((2, 2), np.nan)),
])
def test_bad_inputs_are_refused(bad):
    from nilpotent.numeric.sampled import as_signal

    with pytest.raises(OptionError):
        as_signal(bad, 2)


def test_a_callable_needs_a_duration():
    from nilpotent.numeric.sampled import as_signal

    with pytest.raises(OptionError, match="duration"):
        as_signal(lambda t: [0.0, 0.0], 2)


@pytest.mark.parametrize("command", ["analyze", "approximate", "simulate", "scaling", "sweep",
                                     "plan", "execute", "reproduce", "models"])
def test_every_command_help_names_the_global_flags(run_cli, command):
    status, out, _ = run_cli(command, "--help")
    assert status == 0
    assert "--quiet" in out and "--debug" in out
