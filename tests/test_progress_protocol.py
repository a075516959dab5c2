"""One progress protocol: every ``progress=`` of the library takes a callable of one
:class:`~nilpotent.progress.ProgressEvent`, and the bar on stderr is one such callable."""

from __future__ import annotations

import ast
import io
from pathlib import Path

import pytest

import nilpotent
from nilpotent import progress
from nilpotent.models import get_model
from nilpotent.progress import ProgressEvent
from nilpotent.report import run_audit
from nilpotent.report.audit.run import CHECKS

SRC = Path(__file__).resolve().parents[1] / "src" / "nilpotent"


@pytest.fixture
def reports_on(monkeypatch):
    was = progress.enabled()
    progress.configure(enabled=True)
    monkeypatch.setattr(progress, "PLAIN_INTERVAL", 0.0)
    yield
    progress.configure(enabled=was)


def test_every_progress_parameter_takes_the_one_callback():
    """No ``progress`` parameter in src/ with another signature (the protocol is one)."""
    found = []
    for path in SRC.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                for arg in [*node.args.args, *node.args.kwonlyargs]:
                    if arg.arg in ("progress", "callback", "on_progress"):
                        found.append((path.name, node.name, ast.unparse(arg.annotation)
                                      if arg.annotation else None))
    assert found  # sweep, execute, reproduce, run_audit, ...
    wrong = [f for f in found if f[2] != "ProgressCallback | None"]
    assert not wrong, wrong


def test_a_sweep_reports_its_bracket_motions_to_a_callback():
    events: list[ProgressEvent] = []
    # grid: 2 amplitudes x 3 random starts = 6 bracket motions, one per row
    result = nilpotent.sweep(get_model("unicycle"), (1, 2), (0.05, 0.1), samples=3,
                             radius=0.1, chunk_size=2, progress=events.append)
    assert all(isinstance(e, ProgressEvent) for e in events)
    assert {e.stage for e in events} == {"bracket motions"}
    assert [e.total for e in events] == [6] * len(events)
    done = [e.done for e in events]
    assert done == sorted(done) and done[-1] == 6 == len(result.amplitude)


def test_the_bar_is_a_callback(reports_on):
    out = io.StringIO()
    with progress.progress("bracket motions", stream=out) as bar:
        nilpotent.sweep(get_model("unicycle"), (1, 2), (0.05, 0.1), samples=2, radius=0.1,
                        chunk_size=1, progress=bar)
        assert (bar.completed, bar.total) == (4, 4)
        # a stage other than the bar's own description is shown as its detail
        bar(ProgressEvent("writing the page", 1, 9))
        assert (bar.completed, bar.total, bar.detail) == (1, 9, "writing the page")
    assert "bracket motions" in out.getvalue()


def test_the_audit_reports_its_groups_in_order():
    events: list[ProgressEvent] = []
    names = [CHECKS[0][0], CHECKS[1][0]]
    run_audit(only=names, progress=events.append)
    assert events == [ProgressEvent(names[0], 0, 2), ProgressEvent(names[1], 1, 2)]
