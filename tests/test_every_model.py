"""Properties every built-in model must have, run on every model of the registry.

Each test carries ``@pytest.mark.every_model`` (``tests/conftest.py``): it runs
once per entry of :data:`nilpotent.models.MODELS`, the joint-form trident
included.  The oracles are independent of the code under test: brackets and
growth vectors by plain sympy (``tests/polynomial_systems.py``), the bracket
motion by the convention's closed form ``πA²[X_1, X_2](p)``.
"""

from __future__ import annotations

import itertools
import json
import math
import random

import numpy as np
import pytest
import sympy as sp

import nilpotent as nil
from conftest import model_point
from nilpotent.core.model.modelfile import dump_model_file
from nilpotent.models import MODELS

pytestmark = pytest.mark.every_model


def _random_point(model, seed: int = 7) -> dict[sp.Symbol, sp.Rational]:
    rng = random.Random(seed)
    return {c: sp.Rational(rng.randint(-40, 40), 97) for c in model.coordinates}


def _at(vector, point) -> np.ndarray:
    return np.array([float(sp.N(sp.S(e).xreplace(point), 30)) for e in vector])


def test_registry_entry_describes_what_it_builds(model) -> None:
    info = MODELS[model.name.partition(":")[0]]
    assert info.description and "\n" not in info.description
    if not info.summary:
        assert info.description == model.description
    assert dict(info.parameters) == dict(model.parameters)
    assert all(v.is_Rational for v in info.parameters.values())  # exact defaults
    used = set().union(*(e.free_symbols for f in model.fields for e in f)) - set(model.coordinates)
    assert {str(s) for s in used} <= set(info.parameters)
    entry = json.loads(json.dumps(info.to_json()))
    assert entry["name"] == info.usage and nil.get_model(entry["example"]).name == model.name


def test_fields_are_well_formed(model) -> None:
    assert model.n == len(model.coordinates) == len(set(model.coordinates))
    assert all(len(f) == model.n for f in model.fields)
    assert 1 <= model.m < model.n  # driftless, underactuated


def _plain_bracket(x, y, coords) -> list:
    """``[X, Y] = DY·X − DX·Y`` by plain sympy, unexpanded (cheap to evaluate at a point)."""
    jx, jy = sp.Matrix(x).jacobian(coords), sp.Matrix(y).jacobian(coords)
    return list(jy * sp.Matrix(x) - jx * sp.Matrix(y))


def _plain_growth_vector(model) -> tuple[int, ...]:
    """Ranks at the example point (:func:`conftest.model_point`, mostly the origin) of the
    right-normed brackets up to each length (exact sympy)."""
    coords, fields = model.coordinates, [list(f) for f in model.specialized_fields]
    origin = dict(zip(coords, model_point(model), strict=True))
    layer, values, growth = fields, [], []
    while len(growth) < 2 * model.n:
        values += [[sp.nsimplify(sp.simplify(e.xreplace(origin))) for e in v] for v in layer]
        growth.append(sp.Matrix(values).rank(simplify=True))
        if growth[-1] == model.n or (len(growth) > 1 and growth[-1] == growth[-2] == len(values)):
            break
        layer = [_plain_bracket(x, v, coords) for x in fields for v in layer]
    return tuple(growth)


# length-3 brackets: trident joints 3.7M operations, the snake 11 s
@pytest.mark.every_model(slow=("trident-snake-joints", "kinematic-snake"))
def test_brackets_match_plain_sympy_and_satisfy_jacobi(model) -> None:
    coords, f = model.coordinates, model.specialized_fields
    point = _random_point(model)
    xy = nil.word_field(model, (1, 2))
    np.testing.assert_allclose(
        _at(xy, point), _at(_plain_bracket(f[0], f[1], coords), point), atol=1e-20
    )
    np.testing.assert_allclose(_at(nil.word_field(model, (2, 1)), point), -_at(xy, point))
    z = 3 if model.m >= 3 else (1, 2)  # X3, or [X1, X2] for two inputs
    terms = [nil.word_field(model, w) for w in ((1, (2, z)), (2, (z, 1)), (z, (1, 2)))]
    jacobi = [sp.N(sum(parts).xreplace(point), 40) for parts in zip(*terms, strict=True)]
    assert all(abs(v) < 1e-30 for v in jacobi), jacobi


def test_growth_vector_and_weights_match_plain_sympy(model) -> None:
    filtration = nil.analyze(model, model_point(model))
    expected = _plain_growth_vector(model)
    assert filtration.growth_vector == expected
    assert filtration.bracket_generating and expected[-1] == model.n
    # weights: w = k for g_k − g_{k−1} coordinates, in order
    steps = [expected[0]] + [b - a for a, b in itertools.pairwise(expected)]
    assert filtration.weights == tuple(k + 1 for k, c in enumerate(steps) for _ in range(c))


def test_model_file_round_trip(model, tmp_path) -> None:
    path = tmp_path / "model.toml"
    dump_model_file(model, path)
    back = nil.load_model_file(path)
    assert back.coordinate_names == model.coordinate_names
    assert back.parameter_values == model.parameter_values
    point = _random_point(model, seed=3)
    names = {c.name: c for c in model.coordinates}
    back_point = {c: point[names[c.name]] for c in back.coordinates}
    for f, g in zip(model.specialized_fields, back.specialized_fields, strict=True):
        np.testing.assert_allclose(_at(g, back_point), _at(f, point), atol=1e-25)


def test_bracket_loop_moves_the_state_by_pi_a_squared_times_the_bracket(model) -> None:
    """``u1 = −Aω sin ωt, u2 = Aω cos ωt``: ``Δx = πA²[X1, X2](0) + O(A³)`` (the convention)."""
    origin = dict(zip(model.coordinates, model_point(model), strict=True))
    f = model.specialized_fields
    expected = _at(_plain_bracket(f[0], f[1], model.coordinates), origin)
    errors = []
    for amp in (0.04, 0.02):
        run = nil.compare_bracket_motion(
            model, (1, 2), amp, samples=3, point=model_point(model)
        )
        moved = np.asarray(run.original[-1]) - np.asarray(run.original[0])
        errors.append(np.max(np.abs(moved / (math.pi * amp**2) - expected)))
    # the remainder is O(A): halving A at least roughly halves it (or it is round-off)
    assert errors[1] <= 0.6 * errors[0] + 1e-7, errors
    assert errors[1] <= 0.05 * (1 + np.max(np.abs(expected))), errors
