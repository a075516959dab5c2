"""The compiled pair (original + approximation + maps) and compile_map: maps against
sympy at random points, pickling (what Dask does) giving the same numbers, and a
nilpotent system that is its own approximation (errors at the tolerance)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
import sympy as sp

from nilpotent.core.coordinates.approximation import approximate
from nilpotent.errors import ModelError
from nilpotent.models import get_model
from nilpotent.numeric.compile import compile_map
from nilpotent.numeric.signals import bracket_inputs
from nilpotent.simulation.pair import CompiledPair, weight_groups


def test_compile_map_agrees_with_sympy_and_survives_pickling():
    x, y, th = sp.symbols("x y theta")
    exprs = [x * sp.cos(th) + y * sp.sin(th), sp.exp(x) - y**2 / 3, sp.atan2(y, 1 + x**2) + th]
    fmap = compile_map((x, y, th), exprs, name="test-map")
    rng = np.random.default_rng(0)
    pts = rng.uniform(-1, 1, (7, 3))
    expected = np.array([[float(e.subs({x: p[0], y: p[1], th: p[2]})) for e in exprs]
                         for p in pts])
    np.testing.assert_allclose(fmap(pts), expected, rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(fmap(pts[0]), expected[0], rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(fmap(pts.reshape(7, 1, 3))[:, 0], expected, rtol=1e-13)
    again = pickle.loads(pickle.dumps(fmap))
    np.testing.assert_array_equal(again(pts), fmap(pts))
    with pytest.raises(ModelError):
        compile_map((x, y), [x])


def test_forward_and_inverse_maps_are_inverse_near_p():
    system = get_model("trident-snake").specialized()
    pair = CompiledPair.build(system, approximate(system))
    rng = np.random.default_rng(1)
    q = rng.uniform(-0.05, 0.05, (5, system.n))
    np.testing.assert_allclose(pair.inverse(pair.forward(q)), q, atol=1e-12)
    np.testing.assert_allclose(pair.forward(np.zeros(system.n)), 0.0, atol=1e-15)


def test_pair_pickles_to_the_same_run():
    system = get_model("unicycle").specialized()
    pair = CompiledPair.build(system, approximate(system))
    shipped = pickle.loads(pickle.dumps(pair))
    starts = np.array([[0.0, 0.0, 0.0], [0.01, -0.02, 0.03]])
    inputs = bracket_inputs(2, 1, 2, [0.1, 0.2])
    times = np.linspace(0.0, 2 * np.pi, 9)
    a = pair.run(starts, inputs, times, engine="scipy")
    b = shipped.run(starts, inputs, times, engine="scipy")
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.y_hat, b.y_hat)
    assert a.ok.all() and b.ok.all()


def test_a_nilpotent_system_is_its_own_approximation():
    """Heisenberg is homogeneous nilpotent: the pair's errors are integration noise."""
    system = get_model("heisenberg").specialized()
    pair = CompiledPair.build(system, approximate(system))
    assert weight_groups(pair.weights) == ((1, (0, 1)), (2, (2,)))
    starts = np.zeros((3, 3))
    run = pair.run(starts, bracket_inputs(2, 1, 2, [0.1, 0.5, 1.0]), np.linspace(0, 2 * np.pi, 5),
                   engine="scipy", rtol=1e-12, atol=1e-14)
    diff = np.abs(run.y() - run.y_hat)
    for err in run.by_weight(diff, (1,)).values():
        assert np.all(err < 1e-10)


def test_layers_import_only_downward():
    """numeric loads no simulation; simulation loads no planning, viz, report or cli."""
    import subprocess
    import sys

    code = (
        "import sys, nilpotent.numeric, nilpotent.numeric.engines;"
        "bad = [m for m in sys.modules if m.startswith('nilpotent.simulation')];"
        "import nilpotent.simulation;"
        "bad += [m for m in sys.modules if m.split('.')[1:2] and m.split('.')[1] in "
        "('planning', 'viz', 'report', 'cli')];"
        "print(bad)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


def test_the_top_level_names_are_the_simulation_functions():
    """``nilpotent.simulate``/``scaling``/``sweep`` are the functions of the commands (the
    modules of those names are gone), the one home being :mod:`nilpotent.simulation`."""
    import nilpotent
    import nilpotent.simulation as simulation

    assert nilpotent.simulate is simulation.compare_bracket_motion
    assert nilpotent.scaling is simulation.scaling_study
    assert nilpotent.sweep is simulation.sweep


def test_a_trajectory_from_samples_alone():
    """Trajectory(times, states): samples computed elsewhere (a planner's verifier)."""
    from nilpotent.simulation import Trajectory

    times = np.linspace(0.0, 1.0, 4)
    states = np.column_stack([times, times**2])
    traj = Trajectory(times, states)
    np.testing.assert_array_equal(traj.x0, [0.0, 0.0])
    np.testing.assert_array_equal(traj.final, [1.0, 1.0])
    _fig, ax = traj.plot()
    assert len(ax.lines) == 2
    with pytest.raises(Exception, match="states"):
        Trajectory(times, states[:2])
