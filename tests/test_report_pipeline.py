"""``reproduce`` end to end (quick settings): files, offline page, atomic writing, CLI."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from nilpotent.errors import OptionError
from nilpotent.report import AUDIT_SCHEMA, reproduce

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def replaced(quick_reproduction):
    """The suite's one quick reproduction (``tests/conftest.py``): the CLI replacing a
    previous reproduction's folder."""
    return quick_reproduction


@pytest.fixture(scope="module")
def result(replaced):
    return replaced[3]


def test_written_files(result) -> None:
    out = result.out_dir
    assert (out / "index.html").is_file() and (out / "audit.json").is_file()
    audit = json.loads((out / "audit.json").read_text())
    assert audit["schema"] == AUDIT_SCHEMA
    assert audit["summary"]["differs"] == len(result.audit.differing) > 0
    for p in (*result.figures, *result.data, *result.animations):
        assert p.is_file() and p.stat().st_size > 0 and out in p.parents
    stems = {p.stem for p in result.figures}
    for n in range(2, 8):
        assert any(s.startswith(f"fig{n}_") for s in stems), n
    assert {p.suffix for p in result.figures} == {".png", ".svg"}
    assert {p.suffix for p in result.animations} >= {".gif", ".html"}
    models = json.loads((out / "data" / "models.json").read_text())
    assert models["vf"]["growth_vector"] == [3, 6]
    assert models["vf"]["certificate"]["nilpotent_step"] == 2


def test_page_is_offline_and_complete(result) -> None:
    out = result.out_dir
    text = (out / "index.html").read_text()
    # nothing fetched: no absolute or protocol-relative URL in src/href
    assert not re.search(r'(?:src|href)="(?:[a-z]+:)?//', text)
    for ref in re.findall(r'(?:src|href)="([^"#]+)"', text):
        assert (out / ref).exists(), ref
    for entry in result.audit.entries:  # the audit table lists every entry
        assert f">{entry.id}<" in text
    assert 'id="selfcheck"' in text


def test_slopes_measured(result) -> None:
    # MATH.md §6: error O(A^(w+1)); with round-off groups reported as None
    for name, slopes in result.slopes.items():
        w2 = slopes["weight 2"]
        assert w2 is not None and w2 > 2.5, (name, slopes)


def test_refuses_a_foreign_folder(tmp_path: Path) -> None:
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("precious")
    with pytest.raises(OptionError, match="not a previous reproduction"):
        reproduce(foreign, quick=True)
    assert (foreign / "thesis.tex").read_text() == "precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine"]  # no temporary left


def test_cli_replaces_a_previous_reproduction(replaced, run_cli, tmp_path: Path) -> None:
    status, out, _ = run_cli("reproduce", "--out", str(tmp_path / "missing" / "x"), "--json")
    assert status == 2 and json.loads(out)["error"]["kind"] == "option"
    # replacing an earlier result: the folder is swapped whole
    status, out, marker, result = replaced
    target = result.out_dir
    assert status == 0
    summary = json.loads(out)
    assert summary["schema"] == "nilpotent/reproduce@1"
    assert Path(summary["index"]).is_file()
    assert Path(summary["index"]).parent == target
    assert not marker.exists()
    leftovers = [p.name for p in target.parent.iterdir() if p.name.startswith(".")]
    assert leftovers == []


def test_the_steps_are_reported_as_progress_events(result, reproduction_events) -> None:
    """``reproduce(progress=...)`` receives one ProgressEvent per step, in order, before
    it runs (the step's name, the steps done, their number), then ``"done"``."""
    from nilpotent.progress import ProgressEvent

    steps = list(result.timings)  # the named steps, in the order they ran
    n = len(steps)
    assert n > 1
    expected = [*(ProgressEvent(name, k, n) for k, name in enumerate(steps)),
                ProgressEvent("done", n, n)]
    assert reproduction_events == expected
