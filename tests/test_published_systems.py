"""The seventeen published driftless systems of issue 23, each against independent values.

Each system is a built-in model or a model file in ``tests/data/published/`` (its header states the
source and the derivation).  The oracles here are independent of ``nilpotent.core``:

* the growth vector by ranks of right-normed brackets computed with plain sympy at a point: exact
  ranks where the field values are rational or algebraic, 50-digit singular values (rank = those
  above 1e-30) where they are sines of rationals;
* each file's fields re-derived from their source (a linear change of Engel's and Cartan's
  systems, the quaternion kinematics ``q' = q ⊗ ω / 2``, conservation of angular momentum, the
  no-side-slip constraints, a first integral);
* the literature's growth vectors (Engel, Cartan, Witt's dimensions of the free Lie algebra).

Analysis runs at exact points; approximation at exact rational points only (float-mode points are
the subject of issue 23 item 1, fixed in ``core/privileged.py`` elsewhere).
"""

from __future__ import annotations

import itertools
from pathlib import Path

import mpmath
import pytest
import sympy as sp

import nilpotent as nil
from nilpotent.models import get_model
from polynomial_systems import free_nilpotent, witt_dimension

DATA = Path(__file__).parent / "data" / "published"


def load(name: str):
    return nil.load_model_file(DATA / f"{name}.toml")


# --- the independent growth vector -------------------------------------------------------------


def _bracket(a, b, coords):
    """[A, B] = DB·A − DA·B with plain sympy, unexpanded."""
    ma, mb = sp.Matrix(a), sp.Matrix(b)
    return list(mb.jacobian(coords) * ma - ma.jacobian(coords) * mb)


def _rank(rows, exact: bool) -> int:
    if exact:
        return sp.Matrix(rows).rank()
    with mpmath.workdps(50):
        m = mpmath.matrix([[mpmath.mpf(str(v)) for v in r] for r in rows])
        return sum(1 for s in mpmath.svd_r(m, compute_uv=False) if s > mpmath.mpf(10) ** -30)


def growth_at(system, point, *, exact: bool = True, max_length: int = 8) -> tuple[int, tuple]:
    """(growth vector, reached dimension) at ``point`` from right-normed brackets (plain sympy).

    Stops when the rank reaches n, or stays the same for two lengths while the new brackets are
    all zero at generic order (the orbit dimension is then the last rank); ``exact=False``
    evaluates to 50 digits.
    """
    coords = system.coordinates
    subs = dict(zip(coords, point, strict=True))
    fields = [list(f) for f in system.specialized_fields]
    rational = all(sp.S(e).is_rational_function(*coords) for f in fields for e in f)

    def value(v):
        if not exact:
            return [sp.N(e.xreplace(subs), 50) for e in v]
        if rational:  # a rational function at a rational point: plain arithmetic
            return [sp.S(e).xreplace(subs) for e in v]
        return [sp.nsimplify(sp.simplify(e.xreplace(subs))) for e in v]

    def bracket(a, b):
        out = _bracket(a, b, coords)
        return [sp.cancel(e) for e in out] if rational else out

    layer, rows, growth = fields, [], []
    for _ in range(max_length):
        rows += [value(v) for v in layer]
        growth.append(_rank(rows, exact))
        if growth[-1] == system.n:
            break
        layer = [bracket(x, v) for x in fields for v in layer]
    while len(growth) > 1 and growth[-1] == growth[-2]:
        growth.pop()
    return tuple(growth), growth[-1]


def weights_of(growth) -> tuple[int, ...]:
    steps = [growth[0]] + [b - a for a, b in itertools.pairwise(growth)]
    return tuple(k + 1 for k, c in enumerate(steps) for _ in range(c))


# --- the systems, their points and their right values -------------------------------------------

R = sp.Rational
PI = sp.pi

#: id → (system factory, point (by name), exact ranks?, growth vector, regular there?)
CASES = {
    "car-rear-drive": (lambda: get_model("car"), {"theta": R(2, 3), "phi": PI / 6}, True,
                       (2, 3, 4), True),
    "car-front-drive": (lambda: load("car-front-drive"), {"theta": PI / 4, "phi": PI / 3}, True,
                        (2, 3, 4), True),
    "car-steer-trailer": (lambda: load("car-steer-trailer"),
                          {"theta0": R(1, 2), "phi": R(1, 5), "theta1": R(-1, 3)}, False,
                          (2, 3, 4, 5), True),
    "kinematic-snake": (lambda: get_model("kinematic-snake"),
                        {"theta": R(1, 3), "alpha1": R(-116, 100), "alpha2": R(-103, 100)},
                        False, (2, 3, 5), True),
    "kinematic-snake-file": (lambda: load("kinematic-snake"),
                             {"alpha1": PI / 2, "alpha2": PI / 3}, False, (2, 3, 5), True),
    "snakeboard": (lambda: get_model("snakeboard"), {"theta": R(1, 2), "phi": R(-2, 3)}, False,
                   (3, 4, 5), True),
    "so3-euler": (lambda: get_model("rigid-body"), {"roll": PI / 3, "pitch": PI / 4}, True,
                  (2, 3), True),
    "so3-quaternion": (lambda: load("so3-quaternion"), {"q1": R(1, 3), "q2": R(2, 3)}, True,
                       (2, 3), True),  # |v| = √5/3 < 1, w = 2/3 (a rational point of the chart)
    "space-robot": (lambda: load("space-robot"), {"q1": PI / 3, "q2": PI / 2}, True, (2, 3),
                    True),
    "space-robot-stretched": (lambda: load("space-robot"), {}, True, (2, 2, 3), False),
    "space-robot-built-in": (lambda: get_model("space-robot", {"a": R(3, 2)}),
                             {"q1": PI / 2, "q2": PI / 4}, True, (2, 3), True),
    "roto-translation": (lambda: get_model("roto-translation"), {"theta": PI / 6}, True, (2, 3),
                         True),
    "engel-scrambled": (lambda: load("engel-scrambled"), {"y1": R(3, 7), "y3": R(-2, 5)}, True,
                        (2, 3, 4), True),
    "cartan-scrambled": (lambda: load("cartan-scrambled"), {"y2": R(1, 3), "y5": R(-5, 4)}, True,
                         (2, 3, 5), True),
    "cartan-martinet-off": (lambda: load("cartan-martinet"), {"x1": R(1, 2), "x2": R(3, 4)}, True,
                            (2, 3, 5), True),
    "cartan-martinet-on": (lambda: load("cartan-martinet"), {"x2": R(3, 4)}, True, (2, 2, 3, 5),
                           False),
    "free-2-4": (lambda: free_nilpotent(2, 4), {}, True,
                 tuple(itertools.accumulate(witt_dimension(2, k) for k in range(1, 5))), True),
    "quaternionic-heisenberg": (lambda: load("quaternionic-heisenberg"),
                                {"x1": R(1, 2), "x3": R(-2, 3), "t2": R(5, 1)}, True, (4, 7),
                                True),
    "step6-mixed-origin": (lambda: load("step6-mixed"), {}, True, (2, 2, 2, 2, 2, 3), False),
    "step6-mixed-generic": (lambda: load("step6-mixed"), {"x1": R(1, 2), "x2": R(-1, 3)}, True,
                            (2, 3), True),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_growth_vector_weights_and_regularity(case):
    factory, at, exact, expected, regular = CASES[case]
    system = factory()
    point = system.point(at)
    assert growth_at(system, point, exact=exact) == (expected, system.n)  # the oracle, first
    result = nil.analyze(system, point)
    assert result.growth_vector == expected
    assert result.weights == weights_of(expected)
    assert result.bracket_generating is True
    assert result.regular == regular


def test_free_nilpotent_2_3_5_8_is_witts():
    assert tuple(itertools.accumulate(witt_dimension(2, k) for k in range(1, 5))) == (2, 3, 5, 8)


def test_hidden_first_integral_is_found_not_bracket_generating():
    system = load("hidden-first-integral")
    x1, x2, x3, x4 = system.coordinates
    h = (x4 - x1**3 + x1**2 * x3 - x2 * x3) / (1 - x1 * x2 + x1**3)  # y4 in the x coordinates
    for f in system.specialized_fields:
        assert sp.simplify(sum(c * sp.diff(h, v) for c, v in zip(f, system.coordinates,
                                                                     strict=True))) == 0
    point = system.point({"x1": R(1, 3), "x3": R(2, 5)})
    growth, reached = growth_at(system, point, max_length=4)
    assert (growth, reached) == ((2, 3), 3)
    result = nil.analyze(system, point)
    assert result.bracket_generating is False
    assert result.growth_vector == (2, 3)


# --- each file's fields re-derived from its source ----------------------------------------------


@pytest.mark.parametrize(
    ("name", "base", "matrix"),
    [
        ("engel-scrambled", "engel", [[1, 1, 0, 0], [0, 1, 2, 0], [1, 0, 1, 1], [0, 0, 1, 2]]),
        ("cartan-scrambled", "cartan", [[1, 0, 1, 0, 0], [1, 1, 0, 0, 1], [0, 1, 1, 1, 0],
                                        [0, 0, 0, 1, 1], [1, 0, 0, 0, 2]]),
    ],
)
def test_scrambled_systems_are_linear_changes_of_engel_and_cartan(name, base, matrix):
    system, original = load(name), get_model(base)
    m = sp.Matrix(matrix)
    assert m.det() != 0
    sub = dict(zip(original.coordinates, m * sp.Matrix(system.coordinates), strict=True))
    for f, g in zip(system.specialized_fields, original.fields, strict=True):
        pushed = m.inv() * sp.Matrix(g).xreplace(sub)
        assert (sp.Matrix(f) - pushed).applyfunc(sp.expand) == sp.zeros(system.n, 1)


def test_quaternion_chart_fields_are_half_q_times_omega():
    system = load("so3-quaternion")
    v = sp.Matrix(system.coordinates)
    w = sp.sqrt(1 - (v.T * v)[0])
    for f, omega in zip(system.fields, (sp.Matrix([1, 0, 0]), sp.Matrix([0, 1, 0])), strict=True):
        vdot = (w * omega + v.cross(omega)) / 2  # vector part of q ⊗ (0, ω) / 2
        assert (sp.Matrix(f) - vdot).applyfunc(sp.simplify) == sp.zeros(3, 1)


SPACE_ROBOTS = {  # (system, (base mass, base inertia, joint offset, link mass, link length))
    "file": (lambda: load("space-robot"), (2, R(1, 3), R(1, 2), 1, 1)),
    "built-in": (lambda: get_model("space-robot", {"m0": 3, "J0": R(1, 2), "a": R(1, 3),
                                                   "m": 2, "l": R(3, 2)}),
                 (3, R(1, 2), R(1, 3), 2, R(3, 2))),
}


@pytest.mark.parametrize("which", sorted(SPACE_ROBOTS))
def test_space_robot_conserves_angular_momentum(which):
    """A base and two uniform rods: with zero linear momentum, the angular momentum about the
    centre of mass (built here from positions and velocities) is 0 along X1 and X2."""
    factory, constants = SPACE_ROBOTS[which]
    m0, j0, a, m, ln = (sp.S(c) for c in constants)  # exact (1/12 is not 0.0833...)
    system = factory()
    th, q1, q2 = system.coordinates
    rates = sp.symbols("r0 r1 r2")
    e = lambda t: sp.Matrix([sp.cos(t), sp.sin(t)])  # noqa: E731
    joint1 = a * e(th)
    joint2 = joint1 + ln * e(th + q1)
    centres = [sp.zeros(2, 1), joint1 + ln * e(th + q1) / 2, joint2 + ln * e(th + q1 + q2) / 2]
    masses, inertias = (m0, m, m), (j0, m * ln**2 / 12, m * ln**2 / 12)
    weighted = sum((mi * c for mi, c in zip(masses, centres, strict=True)), sp.zeros(2, 1))
    com = weighted / (m0 + 2 * m)
    spins = (rates[0], rates[0] + rates[1], rates[0] + rates[1] + rates[2])
    momentum = sum(i * s for i, s in zip(inertias, spins, strict=True))
    for mi, c in zip(masses, centres, strict=True):
        rel = c - com
        vel = rel.jacobian(system.coordinates) * sp.Matrix(rates)
        momentum += mi * (rel[0] * vel[1] - rel[1] * vel[0])
    for f in system.specialized_fields:
        along = momentum.subs(dict(zip(rates, f, strict=True)))
        for shape in ((R(1, 3), R(-7, 5)), (R(2, 1), R(1, 2)), (R(-3, 4), R(5, 2))):
            at = dict(zip(system.coordinates, (R(1, 7), *shape), strict=True))
            assert abs(sp.N(along.xreplace(at), 50)) < 1e-45  # zero to 50 digits
    assert all(f[1:] in ((1, 0), (0, 1)) for f in system.fields)  # the joint rates are the inputs


def _lateral(point, heading, field, coords):
    vx, vy = (sum(c * sp.diff(p, v) for c, v in zip(field, coords, strict=True)) for p in point)
    return -sp.sin(heading) * vx + sp.cos(heading) * vy


def test_cars_do_not_slip():
    front = load("car-front-drive")
    x, y, th, phi = front.coordinates
    wheelbase = front.parameter_values["L"]
    for f in front.specialized_fields:
        assert sp.simplify(_lateral((x, y), th, f, front.coordinates)) == 0
        tip = (x + wheelbase * sp.cos(th), y + wheelbase * sp.sin(th))
        assert sp.simplify(_lateral(tip, th + phi, f, front.coordinates)) == 0
    drive = front.specialized_fields[0]  # the front wheel moves at unit speed
    tip_speed = [sum(c * sp.diff(p, v) for c, v in zip(drive, front.coordinates, strict=True))
                 for p in (x + wheelbase * sp.cos(th), y + wheelbase * sp.sin(th))]
    assert sp.simplify(tip_speed[0] ** 2 + tip_speed[1] ** 2) == 1
    trailer = load("car-steer-trailer")
    x, y, th0, phi, th1 = trailer.coordinates
    d, wheelbase = trailer.parameter_values["d"], trailer.parameter_values["L"]
    axles = (((x, y), th0), ((x + wheelbase * sp.cos(th0), y + wheelbase * sp.sin(th0)), th0 + phi),
             ((x - d * sp.cos(th1), y - d * sp.sin(th1)), th1))
    for f in trailer.specialized_fields:
        for p, heading in axles:
            assert sp.simplify(_lateral(p, heading, f, trailer.coordinates)) == 0


def test_the_snake_file_is_the_built_in():
    file, built_in = load("kinematic-snake"), get_model("kinematic-snake")
    assert file.coordinate_names == built_in.coordinate_names
    for f, g in zip(file.specialized_fields, built_in.specialized_fields, strict=True):
        assert [sp.simplify(a - b) for a, b in zip(f, g, strict=True)] == [0] * 5


def test_quaternionic_heisenberg_brackets_are_the_quaternion_structure():
    """[X_i, X_j] = Σ_k (J_k)_{ji} ∂t_k: three independent constant brackets, step 2."""
    system = load("quaternionic-heisenberg")
    coords, f = system.coordinates, system.fields
    tops = {(i, j): _bracket(f[i], f[j], coords) for i in range(4) for j in range(i + 1, 4)}
    assert all(sp.Matrix(b).free_symbols == set() for b in tops.values())
    assert sp.Matrix([b for b in tops.values()]).rank() == 3
    assert all(all(sp.expand(c) == 0 for c in _bracket(f[i], b, coords))
               for i in range(4) for b in tops.values())


# --- approximations at exact rational points ----------------------------------------------------

APPROXIMATE = {
    "engel-scrambled": {"y1": R(3, 7), "y3": R(-2, 5)},
    "cartan-scrambled": {"y2": R(1, 3)},
    "cartan-martinet": {"x2": R(3, 4)},  # singular: weights (1,1,3,4,4)
    "quaternionic-heisenberg": {"x1": R(1, 2), "t2": R(5, 1)},
    "step6-mixed": {},
    "so3-quaternion": {"q1": R(1, 3), "q2": R(2, 3)},
    "car-front-drive": {"theta": R(1, 3), "phi": R(1, 5)},
}


@pytest.mark.parametrize("name", sorted(APPROXIMATE))
def test_certified_approximation_at_an_exact_point(name):
    system = load(name)
    point = system.point(APPROXIMATE[name])
    expected, _ = growth_at(system, point, exact=name != "car-front-drive")
    a = nil.approximate(system, point)
    assert a.certificate.ok, a.certificate.failures()
    assert a.weights == weights_of(expected)
    assert a.certificate.growth_vector_at_0 == expected
    assert a.certificate.nilpotent_step == len(expected)


#: Rational points where the field values are transcendental (sines of rationals): the product
#: evaluates them in float mode, where today's frame inverse (sympy LU on 15-digit Floats,
#: ``core/privileged.py``) is unstable: issue 23 items 1-2, fixed elsewhere.  The right answers
#: (growth and weights by the 50-digit oracle above) are asserted; the cases pass once it is fixed.
FLOAT_MODE = {
    "snake-lu-crash": ("kinematic-snake", {"alpha1": R(-116, 100), "alpha2": R(-103, 100),
                                           "theta": R(134, 100)}),
    "snake-cert": ("kinematic-snake", {"alpha1": R(119, 100), "alpha2": R(-31, 100),
                                       "theta": R(-121, 100)}),
    "snakeboard": ("snakeboard", {"theta": R(1, 2), "phi": R(-2, 3)}),
}


@pytest.mark.slow  # up to 13 s for the certificate's report of the snake
@pytest.mark.parametrize("case", sorted(FLOAT_MODE))
def test_certified_approximation_at_float_mode_points(case):
    name, at = FLOAT_MODE[case]
    system = get_model(name)
    point = system.point(at)
    expected, _ = growth_at(system, point, exact=False)
    a = nil.approximate(system, point)
    assert a.weights == weights_of(expected)
    assert a.certificate.ok, a.certificate.failures()
