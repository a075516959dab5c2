"""Issue 18, item 4: one control evaluator, one compiler for outlines, caches owned by the
modules that need them (a ControlSystem holds no state)."""

from __future__ import annotations

import dataclasses
import gc
import math

import numpy as np
import pytest
import sympy as sp

from nilpotent.core.analysis.filtration import analyze
from nilpotent.core.coordinates.approximation import approximate
from nilpotent.core.lie import brackets
from nilpotent.core.model.memo import IdentityMemo
from nilpotent.core.model.outline import Outline
from nilpotent.core.model.system import ControlSystem
from nilpotent.models import get_model
from nilpotent.numeric.signals import InputSignal, Segment, Signal
from nilpotent.planning import robot as robot_module

# --- the boundary convention of controls ----------------------------------------------

D0, D1 = 1.0, 2.0
W0, W1 = 2.0, math.pi


def hand_built(t: float) -> np.ndarray:
    """The two-segment control written out by hand: right-continuous (a boundary time
    belongs to the segment that starts there), the end time to the last segment."""
    if t < D0:
        return np.array([1.0 + 0.5 * math.cos(W0 * t), 0.0])
    tau = t - D0
    return np.array([0.0, 2.0 + 0.25 * math.sin(2 * W1 * tau)])


SEGMENTS = (
    Segment(D0, W0, (InputSignal(1.0, (0.5,)), InputSignal(0.0))),
    Segment(D1, W1, (InputSignal(0.0), InputSignal(2.0, (), (0.0, 0.25)))),
)


@pytest.mark.parametrize("t", [0.0, 0.3, D0, np.nextafter(D0, 0), 1.7, D0 + D1])
def test_a_signal_is_right_continuous_at_its_boundaries(t):
    sig = Signal.from_segments(SEGMENTS)
    assert np.allclose(sig.evaluate(t), hand_built(t), rtol=0, atol=1e-15)


def test_the_boundary_value_is_the_next_segment_and_the_batch_agrees():
    sig = Signal.from_segments(SEGMENTS)
    assert np.array_equal(sig.evaluate(D0), [0.0, 2.0])  # the case ([1 0] was wrong)
    batch = Signal.stack([SEGMENTS, SEGMENTS])
    assert np.array_equal(batch.evaluate(D0), [[0.0, 2.0], [0.0, 2.0]])


def test_planning_has_no_second_control_evaluator():
    import nilpotent.planning.controls as controls

    assert not hasattr(controls, "input_at")


# --- outlines compiled once, through compile_map ---------------------------------------

x, y, th = sp.symbols("x y theta")
L = sp.Symbol("L")


def outlined_system() -> ControlSystem:
    c, s = sp.cos(th), sp.sin(th)
    outline = Outline(
        polygons=(((x + L * c, y + L * s), (x - L * s / 2, y + L * c / 2),
                   (x + L * s / 2, y - L * c / 2)),),
        segments=(((x, y), (x + 2 * L * c, y + 2 * L * s)),),
        discs=(((x, y), L), ((x - L * c, y - L * s), 1 + sp.sin(th) ** 2 / 4)),
    )
    return ControlSystem("outlined", (x, y, th), ((c, s, 0), (0, 0, 1)),
                         (("L", sp.Rational(1, 2)),), geometry=outline)


def expected_points(q: np.ndarray) -> dict[str, np.ndarray]:
    """The outline above at ``q (N, 3)``, with numpy only."""
    lv = 0.5
    px, py, t = q[:, 0], q[:, 1], q[:, 2]
    c, s = np.cos(t), np.sin(t)
    poly = np.stack([np.stack([px + lv * c, py + lv * s], 1),
                     np.stack([px - lv * s / 2, py + lv * c / 2], 1),
                     np.stack([px + lv * s / 2, py - lv * c / 2], 1)], 1)
    seg = np.stack([np.stack([px, py], 1), np.stack([px + 2 * lv * c, py + 2 * lv * s], 1)], 1)
    discs = np.stack([np.stack([px, py], 1), np.stack([px - lv * c, py - lv * s], 1)], 1)
    radii = np.stack([np.full_like(px, lv), 1 + np.sin(t) ** 2 / 4], 1)
    return {"polygon": poly, "segments": seg[:, None], "discs": discs, "radii": radii}


def test_outline_values_at_random_configurations_match_numpy(monkeypatch):
    calls = []
    real = robot_module.compile_map

    def counting(*args, **kwargs):
        calls.append(kwargs.get("outputs"))
        return real(*args, **kwargs)

    monkeypatch.setattr(robot_module, "compile_map", counting)

    def no_lambdify(*_args, **_kwargs):
        raise AssertionError("outlines are compiled by compile_map, not lambdify")

    monkeypatch.setattr(sp, "lambdify", no_lambdify)
    rob = robot_module.Robot(outlined_system())
    rng = np.random.default_rng(18)
    for _ in range(3):
        q = rng.uniform(-3, 3, size=(7, 3))
        got = rob.points(q)
        want = expected_points(q)
        assert np.allclose(got["polygons"][0], want["polygon"], rtol=1e-14, atol=1e-14)
        assert np.allclose(got["segments"], want["segments"], rtol=1e-14, atol=1e-14)
        assert np.allclose(got["discs"], want["discs"], rtol=1e-14, atol=1e-14)
        assert np.allclose(got["radii"], want["radii"], rtol=1e-14, atol=1e-14)
    assert calls == [16]  # compiled once, for the 16 outline values


def test_a_built_in_outline_matches_its_expressions_evaluated_by_sympy():
    system = get_model("trident-snake")
    if system.geometry is None:
        pytest.skip("no outline")
    rob = robot_module.Robot(system)
    q = np.random.default_rng(5).uniform(-0.5, 0.5, size=(4, system.n))
    values = rob._values(q)
    subs = {sp.Symbol(k): v for k, v in system.parameters}
    for row in range(q.shape[0]):
        at = {**subs, **dict(zip(system.coordinates, q[row], strict=True))}
        for col, e in enumerate(system.geometry.expressions()):
            want = float(sp.sympify(e).subs(at).evalf(30))
            assert math.isclose(values[row, col], want, rel_tol=1e-12, abs_tol=1e-12)


# --- a ControlSystem holds no state ------------------------------------------------------


def test_a_system_is_unchanged_by_analysis():
    sys = get_model("car-trailers:1")
    names = [f.name for f in dataclasses.fields(sys)]
    before = (hash(sys), dict(vars(sys)))
    analyze(sys)
    approximate(sys)
    brackets.word_field(sys, (1, (1, 2)))
    assert [f.name for f in dataclasses.fields(sys)] == names
    assert not any("cache" in n for n in names)
    assert hash(sys) == before[0]
    after = vars(sys)
    assert after.keys() == before[1].keys()
    assert all(after[k] is before[1][k] for k in after)


def test_the_memo_of_a_module_goes_with_its_system():
    class Thing:
        pass

    memo: IdentityMemo[list] = IdentityMemo()
    a, b = Thing(), Thing()
    assert memo.get(a, list) is memo.get(a, list)
    assert memo.get(a, list) is not memo.get(b, list)
    del a
    gc.collect()
    assert len(memo) == 1
    bounded: IdentityMemo[int] = IdentityMemo(maxsize=2)
    things = [Thing() for _ in range(3)]
    for k, t in enumerate(things):
        bounded.get(t, lambda k=k: k)
    assert len(bounded) == 2 and bounded.peek(things[0]) is None
    assert bounded.peek(things[2]) == 2
