"""A relative limit is the same limit whatever linear form its key is written in.

``"2*theta0 - 2*theta1" = [-2.8, 2.8]``, ``"theta1 - theta0" = [-1.4, 1.4]``,
``"-(theta1-theta0)"``, ``"theta0 - theta1 + 0"``, ``"(theta0 - theta1)/2" = [-0.7, 0.7]``
and ``"theta0 - theta1 + 1" = [-0.4, 2.4]`` all say ``|theta0 - theta1| <= 1.4``: the
checker, the trailer guide and the output must all read that hitch limit (the guide used to
see none in the scaled forms).  A nonlinear form the guide cannot read is named when it
refuses; two limits of the same quantity are refused with exit status 2.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from nilpotent.core.model.modelfile import dump_model_file, load_model_file
from nilpotent.errors import ModelError, OptionError, PlanningError
from nilpotent.planning.trailer_guide import trailer_geometry, trailer_guide_path
from nilpotent.planning.verify import Checker

TRAILER = ('coordinates = ["x", "y", "theta0", "theta1"]\n[parameters]\nd = 1.0\n'
           '[[fields]]\nx = "cos(theta0)"\ny = "sin(theta0)"\n'
           'theta1 = "sin(theta0 - theta1)/d"\n[[fields]]\ntheta0 = 1\n'
           '[relative_limits]\n')

#: key, bounds, and the user's own quantity evaluated by hand (independent of the parser)
FORMS = [
    ("theta0 - theta1", "[-1.4, 1.4]", lambda a, b: a - b),
    ("2*theta0 - 2*theta1", "[-2.8, 2.8]", lambda a, b: 2 * a - 2 * b),
    ("theta1 - theta0", "[-1.4, 1.4]", lambda a, b: b - a),
    ("-(theta1-theta0)", "[-1.4, 1.4]", lambda a, b: -(b - a)),
    ("theta0 - theta1 + 0", "[-1.4, 1.4]", lambda a, b: a - b + 0),
    ("(theta0 - theta1)/2", "[-0.7, 0.7]", lambda a, b: (a - b) / 2),
    ("theta0 - theta1 + 1", "[-0.4, 2.4]", lambda a, b: a - b + 1),
    ("-3*theta1 + 3*theta0", "[-4.2, 4.2]", lambda a, b: -3 * b + 3 * a),
]


def _model(tmp_path, body: str, name: str = "m.toml"):
    path = tmp_path / name
    path.write_text(TRAILER + body, encoding="utf-8")
    return load_model_file(path)


@pytest.mark.parametrize(("key", "bounds", "quantity"), FORMS)
def test_every_linear_form_of_the_hitch_limit_is_the_same_limit(tmp_path, key, bounds,
                                                                 quantity):
    system = _model(tmp_path, f'"{key}" = {bounds}\n')
    checker = Checker(system)
    lo, hi = json.loads(bounds)
    # the checker: its verdict is the user's own inequality, at random configurations
    rng = np.random.default_rng(1)
    q = rng.uniform(-2.0, 2.0, size=(400, 4))
    g = quantity(q[:, 2], q[:, 3])
    truth = (lo <= g) & (g <= hi)
    clear = np.minimum(np.abs(g - lo), np.abs(g - hi)) > 1e-9  # not decided by rounding
    assert truth[clear].any() and not truth[clear].all()
    assert np.array_equal(checker.valid(q)[clear], truth[clear])
    # the trailer guide: the hitch limit 1.4 (up to rounding of the bounds)
    assert trailer_geometry(system, checker).phi_max == pytest.approx(1.4, abs=1e-12)
    # the output and a written model file: one key, the hitch angle, its bounds
    (label, (a, b)), = system.limits.relative_dict().items()
    assert label == "theta0 - theta1"
    assert (a, b) == (pytest.approx(-1.4, abs=1e-12), pytest.approx(1.4, abs=1e-12))
    dump_model_file(system, tmp_path / "back.toml")
    assert load_model_file(tmp_path / "back.toml").limits.relative_dict() == \
        system.limits.relative_dict()


def test_an_offset_hitch_limit_is_read_with_its_asymmetric_bounds(tmp_path):
    """``theta0 - theta1 + 1`` in ``[-1.4, 1.4]`` is ``theta0 - theta1`` in ``[-2.4, 0.4]``:
    the guide's symmetric hitch limit is the nearer bound, 0.4."""
    system = _model(tmp_path, '"theta0 - theta1 + 1" = [-1.4, 1.4]\n')
    assert trailer_geometry(system, Checker(system)).phi_max == pytest.approx(0.4, abs=1e-12)


def test_two_limits_of_the_same_quantity_are_refused(tmp_path):
    body = '"theta0 - theta1" = [-1.4, 1.4]\n"2*theta0 - 2*theta1" = [-2, 2]\n'
    with pytest.raises(ModelError, match=r"m\.toml.*same quantity.*theta0 - theta1"):
        _model(tmp_path, body)
    path = tmp_path / "twice.toml"
    path.write_text(TRAILER + body, encoding="utf-8")
    run = subprocess.run([sys.executable, "-m", "nilpotent", "analyze", str(path)],
                         capture_output=True, text=True, env=os.environ, timeout=120)
    assert run.returncode == 2, run.stderr
    assert "same quantity" in run.stderr and "Traceback" not in run.stderr


def test_a_nonlinear_hitch_limit_is_named_when_the_guide_cannot_read_it(tmp_path):
    system = _model(tmp_path, '"sin(theta0 - theta1)" = [-0.9, 0.9]\n')
    assert system.limits.relative_dict() == {"sin(theta0 - theta1)": (-0.9, 0.9)}
    with pytest.raises(OptionError, match=r"linear one.*'sin\(theta0 - theta1\)'"):
        trailer_geometry(system, Checker(system))


def test_a_short_hitch_is_refused_naming_the_self_collision():
    """``car-trailers:1`` with ``d1 = 0.45``: the car touches its trailer well before the
    guide's hitch angle 1.2 (no world: nothing else can fail), and the refusal says so
    instead of blaming the free space."""
    import sympy as sp

    from nilpotent.models import get_model

    system = get_model("car-trailers:1", {"d1": sp.Rational(45, 100)})
    checker = Checker(system)
    assert checker.why_invalid([0, 0, 0, 0]) == ""
    turned = np.array([[0.0, 0.0, phi, 0.0] for phi in (1.2, -1.2)])
    assert np.all(checker.self_clearance(turned) <= 0)  # the bodies overlap there
    with pytest.raises(PlanningError) as err:
        trailer_guide_path(checker, np.zeros(4), np.array([1.0, 0.5, 0.0, 0.0]), 30.0,
                           seed=0)
    message = str(err.value)
    assert "collides with itself" in message and "car touches trailer1" in message
    assert "free space" not in message
