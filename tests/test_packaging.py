"""The package as users get it: ``python -m build`` makes an sdist and a wheel (the wheel
built from the sdist) that install into a clean virtual environment and run.

The clean environment installs the wheel with its dependencies from the package index
(pip's cache makes this about 35 s once ``make test`` has installed the project); what
this test checks is the package itself: its files, its declared dependencies (a missing
one fails the smoke test), its entry point, its data (the paper's LaTeX source the
audit reads, the example worlds ``--world room`` reads), its LICENSE and its metadata.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.slow


def _run(cmd: list[str], **kw) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600, **kw)
    assert done.returncode == 0, (cmd, done.stdout[-2000:], done.stderr[-2000:])
    return done


def test_wheel_and_sdist_install_into_a_fresh_venv_and_run(tmp_path):
    dist = tmp_path / "dist"
    _run([sys.executable, "-m", "build", "--outdir", str(dist), str(ROOT)])
    (wheel,) = dist.glob("nilpotent-*.whl")
    (sdist,) = dist.glob("nilpotent-*.tar.gz")
    names = zipfile.ZipFile(wheel).namelist()
    needed_files = (
        "nilpotent/py.typed",
        "nilpotent/report/assets/paper.tex",
        "nilpotent/cli/app.py",
        *(f"nilpotent/planning/worlds/{w}.toml" for w in ("room", "parking")),
    )
    for needed in needed_files:
        assert needed in names, needed
    assert any(n.endswith("entry_points.txt") for n in names)
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names), "LICENSE shipped"
    (metadata_name,) = [n for n in names if n.endswith(".dist-info/METADATA")]
    metadata = zipfile.ZipFile(wheel).read(metadata_name).decode()
    assert "License-Expression: MIT" in metadata
    assert "Author: The nilpotent contributors" in metadata
    assert "Classifier: Programming Language :: Python :: 3.11" in metadata
    assert "Keywords:" in metadata and "nonholonomic" in metadata
    assert "Provides-Extra: docs" in metadata
    with tarfile.open(sdist) as tar:
        members = tar.getnames()
    assert any(m.endswith("src/nilpotent/report/assets/paper.tex") for m in members)
    assert any(m.endswith("pyproject.toml") for m in members)

    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", str(venv)])
    python = venv / "bin" / "python"
    _run([str(python), "-m", "pip", "install", "--quiet", str(wheel)])

    where = _run([str(python), "-c", "import nilpotent; print(nilpotent.__file__)"], cwd=tmp_path)
    assert Path(where.stdout.strip()).is_relative_to(venv), where.stdout
    exe = str(venv / "bin" / "nilpotent")
    models = _run([exe, "models"], cwd=tmp_path)
    assert "trident-snake" in models.stdout
    room = _run([str(python), "-c", "import nilpotent; print(nilpotent.load_world('room').bounds)"],
                cwd=tmp_path)  # a world by name, read from the installed package's data
    assert room.stdout.strip() == "((-5.0, 13.0), (-6.0, 6.0))"
    out = _run([exe, "approximate", "trident-snake", "--json"], cwd=tmp_path)
    payload = json.loads(out.stdout)
    assert payload["growth_vector"] == [3, 6]
    assert payload["weights"] == [1, 1, 1, 2, 2, 2]
