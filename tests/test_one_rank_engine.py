"""Issue 18, item 3: one rank engine.  Every float rank is decided by
:func:`nilpotent.core.decide.numeric_rank` (scale-free), exact ranks by
:func:`nilpotent.core.decide.rank`; no module keeps a rank function of its own."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from nilpotent.core.model.modelfile import load_model_file
from nilpotent.planning.local_model import (
    check_regular,
    compiled_system,
    numeric_growth,
    numeric_model,
)

SRC = Path(__file__).resolve().parents[1] / "src" / "nilpotent"
DATA = Path(__file__).resolve().parent / "data"
POINT = (0.5, -1.0, 2.0)


def unicycle(tmp_path: Path, scale: str) -> object:
    """The unicycle with both fields multiplied by ``scale`` (a model file)."""
    path = tmp_path / f"unicycle-{scale}.toml"
    path.write_text(
        'coordinates = ["x", "y", "theta"]\n'
        f'[[fields]]\nx = "{scale}*cos(theta)"\ny = "{scale}*sin(theta)"\n'
        f'[[fields]]\ntheta = "{scale}"\n'
    )
    return load_model_file(path)


@pytest.mark.parametrize("scale", ["1", "1e-12", "1e-6", "1e6"])
def test_the_planning_local_model_is_scale_invariant(tmp_path, scale):
    # By hand: X1, X2 independent everywhere, [X1, X2] = (sin θ, −cos θ, 0)·s² completes
    # a basis, whatever the scale s ≠ 0: growth (2, 3) at every point.
    system = unicycle(tmp_path, scale)
    p = np.array(POINT)
    assert numeric_growth(compiled_system(system), p) == (2, 3)
    assert check_regular(system, POINT, "point") == (2, 3)
    model = numeric_model(system, POINT)
    assert model.growth_vector == (2, 3)
    # the coordinate maps are inverse to each other (x ↦ y ↦ x, in model units)
    x = p + np.array([1e-3, -2e-3, 3e-3])
    assert np.allclose(model.inverse(model.forward(x)), x, rtol=0, atol=1e-12)


def test_the_hostile_tiny_scale_case_has_the_unscaled_growth():
    # tests/data/cases/tiny-scale-1e-18.toml: the unicycle with fields times 1e-18
    # (brackets ~1e-36): same growth as unscaled, no singular point reported.
    system = load_model_file(DATA / "cases" / "tiny-scale-1e-18.toml")
    assert numeric_growth(compiled_system(system), np.array(POINT)) == (2, 3)
    assert numeric_model(system, POINT).growth_vector == (2, 3)


def defined_functions(name: str) -> list[str]:
    found = []
    for path in sorted(SRC.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.name == name:
                found.append(str(path.relative_to(SRC)))
    return found


def test_exactly_one_numeric_rank_in_src():
    assert defined_functions("numeric_rank") == ["core/decide/spans.py"]


def test_no_module_keeps_its_own_rank_tolerance():
    # the float-rank tolerance has one home (evaluation.FLOAT_RELATIVE_TOLERANCE)
    for path in sorted(SRC.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Assign):
                names = [t.id for t in node.targets if isinstance(t, ast.Name)]
                assert "RANK_TOL" not in names, path
            if isinstance(node, ast.Attribute) and node.attr == "matrix_rank":
                raise AssertionError(f"{path}: np.linalg.matrix_rank decides a rank on its own")
