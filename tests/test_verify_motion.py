"""The motion check between samples (``Checker.valid_motion``): a motion that starts or
ends exactly on a limit and stays inside is admitted; one whose samples are all admissible
but which leaves a limit or the free space between them is refused.

Every verdict is compared with the truth, computed independently: the same motion
evaluated densely (a closed form of ``t``), not from the checker's samples.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from nilpotent.core.model.outline import Limits
from nilpotent.core.model.system import ControlSystem
from nilpotent.models import get_model
from nilpotent.planning.verify import Checker
from nilpotent.planning.world import World

LO, HI = -1.0, 1.0


def _plane() -> ControlSystem:
    """A holonomic point in the plane (x, y), no outline: only the limits are checked."""
    x, y = sp.symbols("x y")
    return ControlSystem("plane", (x, y), ((1, 0), (0, 1)))


def _checkers() -> list[tuple[str, Checker]]:
    x, y = sp.symbols("x y")
    box = Checker(_plane(), limits=Limits((("x", LO, HI),)))
    # x - y/2 + 1/2 in [LO + 1/2, HI + 1/2], written scaled: the same set as the box on x
    # along y = 1 (the relative limit is normalised; the check must see the same limit)
    rel = Checker(_plane(), limits=Limits((), (("2*x - y + 1", 2 * x - y + 1,
                                                 2 * LO, 2 * HI),)))
    return [("box", box), ("relative", rel)]


def _states(g: np.ndarray, name: str) -> np.ndarray:
    """Configurations where the limited quantity equals ``g``: ``x = g`` (and ``y = 1``
    for the relative limit ``2x - y + 1 = 2g``)."""
    return np.stack([g, np.ones_like(g)], axis=1)


@pytest.mark.parametrize(("name", "checker"), _checkers())
@pytest.mark.parametrize("bound", [LO, HI])
def test_a_motion_from_or_to_a_limit_inside_is_admitted(name, checker, bound):
    inward = np.sign(-bound)
    s = np.linspace(0.0, 1.0, 41)
    for g in (bound + inward * 0.3 * s,            # leaves the limit, linearly
              bound + inward * 0.3 * s[::-1],      # arrives on it
              bound + inward * 0.3 * np.sin(0.5 * np.pi * s)):  # leaves it, slowing down
        truth = bound + inward * 0.3 * np.sin(0.5 * np.pi * np.linspace(0, 1, 4001))
        assert np.all((truth >= LO) & (truth <= HI))
        assert checker.valid_motion(_states(g, name)), (name, bound)


@pytest.mark.parametrize(("name", "checker"), _checkers())
def test_a_motion_leaving_a_limit_between_its_samples_is_refused(name, checker):
    # g(t) = HI + 0.001 - (t - 1/2)^2 peaks 0.001 outside at t = 1/2, between two samples
    def g(t: np.ndarray) -> np.ndarray:
        return HI + 0.001 - (t - 0.5) ** 2

    t = 0.05 + 0.1 * np.arange(10)
    assert np.all(g(t) <= HI)  # every sample inside
    assert g(np.linspace(0, 1, 10001)).max() > HI  # the motion is not
    assert not checker.valid_motion(_states(g(t), name))


@pytest.mark.parametrize(("name", "checker"), _checkers())
def test_admitted_motions_stay_inside_between_samples(name, checker):
    """Random smooth motions near the limits: every one admitted stays inside when
    evaluated densely; the well-sampled ones that stay inside with room are admitted."""
    rng = np.random.default_rng(20)
    admitted = 0
    for _ in range(300):
        c, a = rng.uniform(0.3, 1.2), rng.uniform(0.0, 0.6)
        w, p = rng.uniform(0.5, 12.0), rng.uniform(0, 2 * np.pi)
        n = int(rng.integers(3, 60))
        sign = rng.choice([-1.0, 1.0])

        def g(t: np.ndarray) -> np.ndarray:
            return sign * (c + a * np.sin(w * t + p) - 0.5 * a)  # noqa: B023

        dense = g(np.linspace(0.0, 1.0, 20001))
        ok = checker.valid_motion(_states(g(np.linspace(0.0, 1.0, n)), name))
        if ok:
            admitted += 1
            assert np.all((dense >= LO - 1e-12) & (dense <= HI + 1e-12)), (c, a, w, p, n)
        if n >= 40 and w <= 4 and np.all((dense > LO + 0.05) & (dense < HI - 0.05)):
            assert ok, (c, a, w, p, n)
    assert admitted > 50  # the property is not vacuous


def _disc_robot() -> ControlSystem:
    """A point robot (a disc of radius 0) in the plane, its outline read from a model dict."""
    from nilpotent.core.model.modelfile import system_from_dict

    return system_from_dict({
        "name": "dot", "coordinates": ["x", "y"],
        "fields": [{"x": "1"}, {"y": "1"}],
        "geometry": {"discs": [{"center": ["x", "y"], "radius": "0"}]},
    }, "dot")


def test_a_motion_through_an_obstacle_between_samples_is_refused():
    world = World("one disc", ((-5.0, 5.0), (-5.0, 5.0)), discs=(((0.0, 0.0), 0.5),))
    checker = Checker(_disc_robot(), world)
    x = np.array([-1.5, -0.5, 0.5, 1.5])
    line = np.stack([x, np.full(4, 0.45)], axis=1)  # samples 0.17 clear; x = 0 is inside
    assert np.all(checker.valid(line))
    assert not checker.valid_motion(line)
    xs = np.linspace(-1.5, 1.5, 201)  # the same line passing at y = 0.9 instead: clear
    assert np.hypot(xs, 0.9).min() > 0.5
    assert checker.valid_motion(np.stack([xs, np.full(xs.size, 0.9)], axis=1))


def test_the_built_in_trailer_leaves_its_hitch_limit_by_driving_forward():
    """car-trailers:1 at the hitch limit theta0 - theta1 = 1.4, driving forward: the hitch
    angle phi obeys phi' = -sin(phi) (d = 1, u1 = 1), so it decreases: admitted; driving
    backward it increases past the limit: refused (its samples already say so)."""
    checker = Checker(get_model("car-trailers:1"))
    t = np.linspace(0.0, 0.5, 60)
    # the hitch angle of phi' = -sin(phi), phi(0) = 1.4: tan(phi/2) = tan(0.7) e^{-t}
    phi = 2.0 * np.arctan(np.tan(0.7) * np.exp(-t))
    th1 = 1.4 - phi  # theta0 held (u2 = 0); theta1 = theta0 - phi
    forward = np.stack([np.cos(1.4) * t, np.sin(1.4) * t, np.full_like(t, 1.4), th1], axis=1)
    assert checker.valid_motion(forward)
    backward_phi = 2.0 * np.arctan(np.tan(0.7) * np.exp(t))
    backward = forward.copy()
    backward[:, 3] = 1.4 - backward_phi
    assert not checker.valid_motion(backward)


# --- planners from a start on a limit: a plan that keeps it, checked by scipy --------------
# Whether the steering finds a motion from a start on a bound is a knife edge: with the
# compiled (numba) integrator it did, with the cold-cache default engine of a fresh clone its
# loops overshot the bound and every halving failed.  Either is honest: a plan returned keeps
# the limit (checked by scipy), a refusal names the bound it is on.


def _keeps(system, start, goal, limit_of, bound):
    from nilpotent.errors import PlanningError
    from nilpotent.planning.global_planner import plan_global
    from replay import resimulate

    try:
        out = plan_global(system, start, goal, 1e-6, time_limit=600, seed=0)
    except PlanningError as err:
        assert "is on its bound" in str(err), str(err)
        return
    q = resimulate(system, start, [s.to_dict() for s in out.plan.segments], samples=200)
    assert np.linalg.norm(q[-1] - np.asarray(goal)) <= 1e-5
    assert np.all(np.abs(limit_of(q)) <= bound + 1e-9), np.abs(limit_of(q)).max() - bound


@pytest.mark.slow
def test_a_trailer_starting_on_its_hitch_limit_is_planned_within_it():
    """``car-trailers:1`` from the hitch angle 1.4, its limit (refused before: every
    motion from it failed the half-step margin)."""
    _keeps(get_model("car-trailers:1"), (0.0, 0.0, 1.4, 0.0), (1.0, 0.5, 0.0, 0.0),
           lambda q: q[:, 2] - q[:, 3], 1.4)


@pytest.mark.slow
def test_a_car_starting_on_its_steering_limit_is_planned_within_it():
    """The built-in car (L = 3/5, least turning radius 1: |phi| <= atan(3/5)) from
    ``phi = atan(3/5)``."""
    bound = float(np.arctan(0.6))
    _keeps(get_model("car"), (0.0, 0.0, 0.0, bound), (1.0, 0.3, 0.0, 0.0),
           lambda q: q[:, 3], bound)


def test_a_refusal_names_the_constraint_that_is_near():
    """``constraints_near`` (the planner's refusal when pieces fail) names the limit a
    configuration is on, and blames nothing where nothing is near."""
    box = Checker(_plane(), limits=Limits((("x", LO, HI),)))
    assert "x = 1 is on its bound 1" in box.constraints_near([HI, 0.0])
    assert "0.01 from its bound -1" in box.constraints_near([LO + 0.01, 0.0])
    assert box.constraints_near([0.0, 0.0]).startswith("no limit, obstacle or body within")
    world = World("one disc", ((-5.0, 5.0), (-5.0, 5.0)), discs=(((0.0, 0.0), 0.5),))
    near = Checker(_disc_robot(), world).constraints_near([0.51, 0.0])
    assert "clearance to the obstacles is 0.01" in near


def test_a_state_that_is_not_finite_is_named_as_such():
    checker = Checker(_plane(), limits=Limits((("x", LO, HI),)))
    assert not checker.valid(np.array([[np.nan, 0.0]]))[0]
    assert "not all finite" in checker.why_invalid([np.nan, 0.0])
