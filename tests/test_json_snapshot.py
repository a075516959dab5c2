"""tools/json_snapshot.py (issue 18 item 7): the comparison masks only the documented
volatile fields and finds every other difference; a run of one command records its JSON."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

TOOL = Path(__file__).resolve().parents[1] / "tools" / "json_snapshot.py"


def _tool():
    spec = importlib.util.spec_from_file_location("json_snapshot", TOOL)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _write(folder: Path, name: str, record: dict) -> None:
    folder.mkdir(exist_ok=True)
    (folder / f"{name}.json").write_text(json.dumps(record))


def test_compare_masks_the_volatile_fields_only(tmp_path, capsys):
    tool = _tool()
    a, b = tmp_path / "a", tmp_path / "b"
    base = {"exit": 0, "seconds": 1.0, "stdout": {"x": [1.0, 2.0], "seconds": 3.0,
                                                  "summary": {"wall_time": 0.5}}}
    _write(a, "same", base)
    _write(b, "same", {**base, "seconds": 9.0,
                       "stdout": {"x": [1.0, 2.0], "seconds": 4.0,
                                  "summary": {"wall_time": 0.7}}})
    _write(a, "differs", base)
    _write(b, "differs", {**base, "stdout": {"x": [1.0, 2.0000000000000004], "new": 1,
                                             "seconds": 3.0, "summary": {"wall_time": 0.5}}})
    assert tool.compare(a, b, rtol=0.0, limit=10) == 1
    out = capsys.readouterr().out
    assert "same: same" in out
    assert ".stdout.x[1]" in out and ".stdout.new: added" in out
    assert tool.compare(a, b, rtol=1e-12, limit=10) == 1  # the added field still differs
    assert {"seconds", "wall_time"} <= tool.VOLATILE


def test_a_run_records_the_json_of_a_command(tmp_path):
    tool = _tool()
    tool.run(tmp_path, Path("/nonexistent-cases"), timeout=120.0, only=["analyze-heisenberg"])
    record = json.loads((tmp_path / "analyze-heisenberg.json").read_text())
    assert record["exit"] == 0
    assert record["stdout"]["growth_vector"] == [2, 3]  # the Heisenberg group: (2, 3)
