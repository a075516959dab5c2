"""The model registry and the classic models, checked against hand derivations.

Growth vectors are computed here by an independent small rank computation
(all brackets of length k as ``[X_i, B]`` with ``B`` of length k − 1, which
span the k-th layer), not with ``nilpotent.core.analysis.filtration``.
"""

from __future__ import annotations

import json
import random

import pytest
import sympy as sp

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ModelError
from nilpotent.models import MODELS, get_model, list_models, load_system

# --- an independent bracket / growth-vector oracle ---------------------------------------


def bracket(a, b, coords):
    """[A, B] = DB·A − DA·B (the project convention)."""
    return tuple(
        sp.expand(
            sum(
                a[j] * sp.diff(b[i], coords[j]) - b[j] * sp.diff(a[i], coords[j])
                for j in range(len(coords))
            )
        )
        for i in range(len(coords))
    )


def growth_vector(sys: ControlSystem, point, max_step: int = 8) -> tuple[int, ...]:
    coords = sys.coordinates
    fields = [tuple(f) for f in sys.specialized_fields]
    subs = dict(zip(coords, point, strict=True))
    layer = list(fields)
    spanning = list(fields)
    growth = []
    for _ in range(max_step):
        mat = sp.Matrix([[sp.nsimplify(sp.simplify(c.subs(subs))) for c in f] for f in spanning])
        rank = mat.rank(simplify=True)
        if growth and rank == growth[-1] and len(growth) > 1 and rank == growth[-2]:
            break
        growth.append(rank)
        if rank == len(coords):
            break
        layer = [bracket(x, b, coords) for x in fields for b in layer]
        spanning = spanning + layer
    # drop the trailing repeat, if the sequence stalled
    while len(growth) > 1 and growth[-1] == growth[-2]:
        growth.pop()
    return tuple(growth)


def vanishes(expr, coords, trials: int = 6) -> bool:
    """``expr`` is 0 (simplify), or at least |expr| < 1e-12 at random points (40 digits)."""
    if sp.simplify(expr) == 0:
        return True
    rng = random.Random(1234)
    for _ in range(trials):
        pt = {c: sp.Rational(rng.randint(-900, 900), 1000) for c in coords}
        if abs(sp.N(expr.subs(pt), 40)) > 1e-12:
            return False
    return True


# --- registry --------------------------------------------------------------------------


def test_registry_names_are_the_interface_list():
    assert set(MODELS) == {
        "trident-snake",
        "trident-snake-paper",
        "trident-snake-joints",
        "unicycle",
        "car-trailers",
        "heisenberg",
        "engel",
        "cartan",
        "martinet",
    }
    assert list_models() == tuple(MODELS.values())


def test_unknown_model_lists_known_names():
    with pytest.raises(ModelError) as err:
        get_model("bicycle")
    msg = str(err.value)
    assert "'bicycle'" in msg
    for name in ("trident-snake", "unicycle", "car-trailers:K", "martinet"):
        assert name in msg


@pytest.mark.parametrize(
    "spec",
    [
        "car-trailers",
        "car-trailers:0",
        "car-trailers:-1",
        "car-trailers:1.5",
        "car-trailers:x",
        "car-trailers:",
        "car-trailers:51",
        "unicycle:2",
    ],
)
def test_bad_family_argument(spec):
    with pytest.raises(ModelError) as err:
        get_model(spec)
    assert repr(spec) in str(err.value)


def test_parameters_are_applied_and_unknown_ones_refused():
    sys = get_model("trident-snake", {"r": sp.Rational(1, 2), "l": 2})
    assert sys.parameter_values == {"r": sp.Rational(1, 2), "l": sp.Integer(2)}
    with pytest.raises(ModelError):
        get_model("trident-snake", {"k": 1})
    with pytest.raises(ModelError):
        get_model("unicycle", {"r": 1})


def test_load_system_builtin_and_errors(tmp_path):
    assert load_system("heisenberg").name == "heisenberg"
    assert load_system("car-trailers:3", {"d2": 2}).parameter_values["d2"] == 2
    with pytest.raises(ModelError) as err:
        load_system("no-such-thing")
    assert "unknown model" in str(err.value) and "unicycle" in str(err.value)
    with pytest.raises(ModelError) as err:
        load_system(str(tmp_path / "missing.toml"))
    assert "not found" in str(err.value)


def test_load_system_reads_a_model_file(tmp_path):
    pytest.importorskip("nilpotent.core.model.modelfile")
    path = tmp_path / "uni.toml"
    path.write_text(
        'name = "uni"\ncoordinates = ["x", "y", "theta"]\n[parameters]\nv = 2\n'
        '[[fields]]\nx = "v*cos(theta)"\ny = "v*sin(theta)"\n[[fields]]\ntheta = "1"\n'
    )
    sys = load_system(str(path), {"v": 3})
    assert sys.coordinate_names == ("x", "y", "theta")
    assert sys.parameter_values["v"] == 3


# --- classic models: fields and growth vectors against hand derivations ----------------


def test_unicycle_rolls_without_side_slip():
    sys = get_model("unicycle")
    th = sys.coordinates[2]
    for f in sys.fields:
        assert sp.simplify(-sp.sin(th) * f[0] + sp.cos(th) * f[1]) == 0


def test_heisenberg_x3_is_the_swept_area():
    sys = get_model("heisenberg")
    x1, x2, _ = sys.coordinates
    for f in sys.fields:  # x3' = (x1 x2' − x2 x1') / 2 along every field
        assert sp.simplify(f[2] - (x1 * f[1] - x2 * f[0]) / 2) == 0


GROWTH_AT_ORIGIN = {
    "unicycle": (2, 3),
    "heisenberg": (2, 3),
    "engel": (2, 3, 4),
    "cartan": (2, 3, 5),
    "martinet": (2, 2, 3),  # the origin lies on the Martinet surface x2 = 0
    "car-trailers:1": (2, 3, 4),
    "car-trailers:2": (2, 3, 4, 5),
    "car-trailers:3": (2, 3, 4, 5, 6),
}


@pytest.mark.parametrize("spec", sorted(GROWTH_AT_ORIGIN))
def test_growth_vector_at_origin(spec):
    sys = get_model(spec)
    assert growth_vector(sys, sys.origin()) == GROWTH_AT_ORIGIN[spec]


def test_martinet_regular_off_the_surface():
    sys = get_model("martinet")
    assert growth_vector(sys, (sp.Integer(0), sp.Rational(1, 3), sp.Integer(2))) == (2, 3)


def test_engel_and_cartan_brackets_by_hand():
    eng = get_model("engel")
    c = eng.coordinates
    x1, x2 = eng.fields
    x12 = bracket(x1, x2, c)
    assert x12 == (0, 0, 1, c[0])
    assert bracket(x1, x12, c) == (0, 0, 0, 1)
    assert bracket(x2, x12, c) == (0, 0, 0, 0)
    car = get_model("cartan")
    c = car.coordinates
    y1, y2 = car.fields
    y3 = bracket(y1, y2, c)
    assert bracket(y1, y3, c) == (0, 0, 0, 1, 0)
    assert bracket(y2, y3, c) == (0, 0, 0, 0, 1)


# --- car with trailers -------------------------------------------------------------------


@pytest.mark.parametrize("k", [1, 2, 3])
def test_trailers_do_not_slip(k):
    """Axle centres P_i = P_{i-1} − d_i (cos θ_i, sin θ_i) move along their headings."""
    sys = get_model(f"car-trailers:{k}", {f"d{i}": sp.Rational(i + 1, 2) for i in range(1, k + 1)})
    coords = sys.coordinates
    thetas = coords[2:]
    d = [sp.Rational(i + 1, 2) for i in range(1, k + 1)]
    p = [sp.Matrix([coords[0], coords[1]])]
    for i in range(1, k + 1):
        p.append(p[-1] - d[i - 1] * sp.Matrix([sp.cos(thetas[i]), sp.sin(thetas[i])]))
    for field in sys.specialized_fields:
        for i in range(k + 1):
            vel = sum((sp.diff(p[i], c) * field[j] for j, c in enumerate(coords)), sp.zeros(2, 1))
            lateral = -sp.sin(thetas[i]) * vel[0] + sp.cos(thetas[i]) * vel[1]
            assert sp.simplify(lateral) == 0


def test_one_trailer_fields_by_hand_and_chained_form():
    """K = 1: fields by hand, and Sørdalen's chained form built on the trailer's axle centre.

    z1 = x1, z2 = tan(θ0 − θ1) / (d cos³θ1), z3 = tan θ1, z4 = y1 with
    (x1, y1) = (x, y) − d (cos θ1, sin θ1): along every field
    ż3 = z2 ż1 and ż4 = z3 ż1 (the chained form), and (ż1, ż2) is an
    invertible function of the inputs near the origin.
    """
    d = sp.Rational(3, 2)
    sys = get_model("car-trailers:1", {"d1": d})
    x, y, t0, t1 = sys.coordinates
    assert sys.specialized_fields[0] == (sp.cos(t0), sp.sin(t0), 0, sp.sin(t0 - t1) / d)
    assert sys.specialized_fields[1] == (0, 0, 1, 0)
    z1 = x - d * sp.cos(t1)
    z2 = sp.tan(t0 - t1) / (d * sp.cos(t1) ** 3)
    z3 = sp.tan(t1)
    z4 = y - d * sp.sin(t1)

    def lie(f, h):
        return sum(f[j] * sp.diff(h, c) for j, c in enumerate(sys.coordinates))

    for f in sys.specialized_fields:
        assert vanishes(lie(f, z3) - z2 * lie(f, z1), sys.coordinates)
        assert vanishes(lie(f, z4) - z3 * lie(f, z1), sys.coordinates)
    jac = sp.Matrix([[lie(f, z) for f in sys.specialized_fields] for z in (z1, z2)])
    assert sp.simplify(jac.det().subs({x: 0, y: 0, t0: 0, t1: 0})) != 0


CROSS_CHECK = {
    **GROWTH_AT_ORIGIN,
    "trident-snake": (3, 6),
    "trident-snake-paper": (3, 6),
    "trident-snake-joints": (3, 6),
}


@pytest.mark.parametrize("spec", sorted(CROSS_CHECK))
def test_core_filtration_agrees_with_the_hand_derived_growth(spec):
    filtration = pytest.importorskip("nilpotent.core.analysis.filtration")
    result = filtration.analyze(get_model(spec))
    assert result.growth_vector == CROSS_CHECK[spec]
    assert result.regular == (spec != "martinet")


@pytest.mark.parametrize(
    ("spec", "params"),
    [
        ("trident-snake", {"l": 0}),
        ("trident-snake-joints", {"r": -1}),
        ("car-trailers:2", {"d2": 0}),
    ],
)
def test_lengths_must_be_positive(spec, params):
    with pytest.raises(ModelError) as err:
        get_model(spec, params)
    assert "positive" in str(err.value) and next(iter(params)) in str(err.value)


def test_every_model_and_parameter_is_documented():
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "models.md").read_text()
    for info in list_models():
        assert f"`{info.usage}`" in text
        for name in info.parameters:
            assert name in text


def test_the_registry_builds_nothing_at_import():
    """Descriptions are read lazily: importing the registry builds no model."""
    import subprocess
    import sys

    code = (
        "from nilpotent.models import MODELS\n"
        "print(sum('example' in info.__dict__ for info in MODELS.values()))\n"
        "MODELS['unicycle'].description\n"
        "print(sum('example' in info.__dict__ for info in MODELS.values()))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["0", "1"]


def test_models_json_is_built_by_the_registry():
    from nilpotent.models import MODELS_SCHEMA, models_to_json

    data = json.loads(json.dumps(models_to_json()))
    assert data["schema"] == MODELS_SCHEMA == "nilpotent/models@1"
    assert [m["name"] for m in data["models"]] == [i.usage for i in MODELS.values()]
    for entry in data["models"]:
        assert set(entry) == {"name", "example", "description", "parameters", "parameter_rule"}
