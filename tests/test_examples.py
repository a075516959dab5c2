"""Every script in examples/ runs headless (MPLBACKEND=Agg) and writes what it promises."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"

#: script -> (files it writes into the output folder, text its output contains)
EXPECTED: dict[str, tuple[tuple[str, ...], str]] = {
    "01_analyze_trident.py": ((), "growth vector:      (3, 6)"),
    "02_approximate_any_system.py": (("engel-like.toml",), "weights (1, 1, 2, 3)"),
    "03_bracket_motion.py": (("bracket_motion.png",), "end-point difference"),
    "04_scaling.py": (("scaling.png",), "expected 3"),
    "05_plan.py": (("plan.json",), "converged True"),
    "06_sweep.py": (("sweep.csv", "sweep.json", "sweep.png"), "blow-ups: 0"),
}
#: Scripts that may compile numba kernels or iterate a planner (tens of seconds cold).
SLOW = {"05_plan.py", "06_sweep.py"}


def test_every_example_is_listed():
    assert sorted(p.name for p in EXAMPLES.glob("[0-9][0-9]_*.py")) == sorted(EXPECTED)


@pytest.mark.parametrize(
    "script",
    [pytest.param(s, marks=pytest.mark.slow) if s in SLOW else s for s in sorted(EXPECTED)],
)
def test_example_runs(script, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    env["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT / "src"), *filter(None, [os.environ.get("PYTHONPATH")])]
    )
    proc = subprocess.run(
        [sys.executable, str(EXAMPLES / script), str(tmp_path)],
        capture_output=True, text=True, env=env, cwd=tmp_path, timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    files, text = EXPECTED[script]
    assert text in proc.stdout
    for name in files:
        assert (tmp_path / name).is_file() and (tmp_path / name).stat().st_size > 0
