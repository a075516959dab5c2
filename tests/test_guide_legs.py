"""The Reeds–Shepp guide's legs (``planning.guide``): closed-form legs against numerical
integration, legs recovered from samples of curves composed of known legs and of OMPL's
own Reeds–Shepp curves, and the lifted waypoints ending exactly at the goal."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nilpotent.errors import PlanningError
from nilpotent.planning.guide import (
    LEG_LENGTH_TOL,
    LEG_SAMPLE_STEP,
    PHI_STEP,
    Leg,
    edge_legs,
    leg_end,
    lift_legs,
    merge_legs,
)

RADIUS = 0.6 / math.tan(math.atan(0.6) - 2.5e-3)  # the built-in car's guide radius
WHEELBASE = 0.6


def integrated(pose, kappa: float, s: float) -> np.ndarray:
    """The unicycle ``x' = cos θ, y' = sin θ, θ' = κ`` in arc length, from ``pose`` over
    the signed arc length ``s`` (scipy DOP853, tight tolerances)."""
    sol = solve_ivp(lambda _t, q: [math.cos(q[2]), math.sin(q[2]), kappa], (0.0, s),
                    np.asarray(pose, dtype=float), method="DOP853", rtol=1e-12, atol=1e-12)
    return sol.y[:, -1]


@pytest.mark.parametrize("kappa", [0.0, 1.0, -1.0, 1 / RADIUS, -0.37, 2.5])
@pytest.mark.parametrize("s", [0.7, -1.3, 4.0])
def test_leg_end_is_the_integrated_unicycle(kappa, s):
    pose = (0.3, -1.2, 2.9)  # near π: the heading is not wrapped
    assert np.allclose(leg_end(pose, kappa, s), integrated(pose, kappa, s), atol=1e-9)


def compose(start, legs) -> np.ndarray:
    """The end pose of ``legs`` (curvature, signed length) driven from ``start``, by
    integration (independent of :func:`leg_end`)."""
    q = np.asarray(start, dtype=float)
    for kappa, s in legs:
        q = integrated(q, kappa, s)
    return q


def samples(start, legs, step: float, offset: float = 0.37) -> np.ndarray:
    """Poses ``(N, 3)`` along the composed ``legs`` every ``step`` of arc length or less,
    not aligned with the switches (``offset`` of a step), yaw wrapped to ``(−π, π]`` as
    OMPL gives it; the first and last are the ends."""
    ends = [np.asarray(start, dtype=float)]
    for kappa, s in legs:
        ends.append(integrated(ends[-1], kappa, s))
    total = sum(abs(s) for _, s in legs)
    cuts = np.concatenate(([0.0], np.arange(offset * step, total, step), [total]))
    out = []
    bounds = np.cumsum([0.0] + [abs(s) for _, s in legs])
    for c in cuts:
        i = min(int(np.searchsorted(bounds, c, side="right")) - 1, len(legs) - 1)
        kappa, s = legs[i]
        out.append(integrated(ends[i], kappa, math.copysign(c - bounds[i], s))
                   if c > bounds[i] else ends[i])
    poses = np.array(out)
    poses[:, 2] = np.angle(np.exp(1j * poses[:, 2]))
    return poses


K = 1 / RADIUS
#: Curves of at most three legs whose lengths the end pose determines (not two legs on one
#: circle: only their sum is).
KNOWN = {
    "left-straight-right": [(K, 0.8), (0.0, 1.1), (-K, 0.5)],
    "cusp, straight then left backwards": [(0.0, 0.8), (K, -0.7)],
    "cusp, left then right backwards": [(K, 1.2), (-K, -0.7), (0.0, -0.4)],
    "heading through pi": [(K, 2.9), (0.0, 0.3)],
    "backwards first": [(-K, -0.5), (0.0, 0.8), (K, 0.6)],
    "a leg shorter than a step": [(K, 0.5), (-K, 0.0015), (0.0, 0.7)],
    "a short first leg": [(-K, 0.0013), (K, -0.9), (0.0, -0.6)],
    "a short last leg": [(0.0, -1.7), (-K, -0.4), (K, -0.0011)],
}


@pytest.mark.parametrize("name", sorted(KNOWN))
def test_edge_legs_recover_known_legs(name):
    legs = KNOWN[name]
    start = (0.4, -0.2, 2.6)
    poses = samples(start, legs, LEG_SAMPLE_STEP)
    got = edge_legs(poses, RADIUS, sum(abs(s) for _, s in legs))
    assert [g.kappa for g in got] == pytest.approx([k for k, _ in legs], abs=1e-12)
    assert [g.length for g in got] == pytest.approx([s for _, s in legs], abs=1e-8)


def test_edge_legs_refuse_a_curve_longer_than_its_length():
    legs = KNOWN["left-straight-right"]
    poses = samples((0.0, 0.0, 0.0), legs, LEG_SAMPLE_STEP)
    with pytest.raises(PlanningError):
        edge_legs(poses, RADIUS, 0.5 * sum(abs(s) for _, s in legs))


def rs_state(space, q):
    st = space.allocState()
    st.setX(float(q[0]))
    st.setY(float(q[1]))
    st.setYaw(float(q[2]))
    return st


def ompl_samples(space, a, b) -> np.ndarray:
    """OMPL's Reeds–Shepp curve from ``a`` to ``b`` sampled every ``LEG_SAMPLE_STEP``."""
    n = max(2, math.ceil(space.distance(a, b) / LEG_SAMPLE_STEP) + 1)
    out = space.allocState()
    poses = []
    for t in np.linspace(0.0, 1.0, n):
        space.interpolate(a, b, float(t), out)
        poses.append((out.getX(), out.getY(), out.getYaw()))
    return np.array(poses)


def test_edge_legs_of_ompl_curves():
    """Random pairs of poses (far, and near: short legs): the legs end at OMPL's curve's
    end, have curvature 0 or ±1/r, and their total length is OMPL's distance."""
    ob = pytest.importorskip("ompl.base")
    space = ob.ReedsSheppStateSpace(RADIUS)
    rng = np.random.default_rng(7)
    lo, hi = np.array([-3, -3, -math.pi]), np.array([3, 3, math.pi])
    for k in range(60):
        qa = rng.uniform(lo, hi)
        qb = qa + rng.normal(0, 0.1, 3) if k % 3 == 0 else rng.uniform(lo, hi)
        a, b = rs_state(space, qa), rs_state(space, qb)
        distance = space.distance(a, b)
        poses = ompl_samples(space, a, b)
        legs = edge_legs(poses, RADIUS, distance)
        assert {round(leg.kappa * RADIUS) for leg in legs} <= {-1, 0, 1}
        assert all(leg.kappa * RADIUS in (-1.0, 0.0, 1.0) for leg in legs)
        end = compose(poses[0], [(leg.kappa, leg.length) for leg in legs])
        assert np.allclose(end[:2], poses[-1, :2], atol=1e-8)
        assert math.remainder(end[2] - poses[-1, 2], 2 * math.pi) == pytest.approx(0, abs=1e-8)
        total = sum(abs(leg.length) for leg in legs)
        assert distance - 1e-9 <= total <= distance + LEG_LENGTH_TOL


def test_merge_legs():
    legs = [Leg(K, 0.3), Leg(K, 0.2), Leg(K, -0.1), Leg(0.0, -0.2), Leg(0.0, -0.3)]
    assert merge_legs(legs) == [Leg(K, 0.5), Leg(K, -0.1), Leg(0.0, -0.5)]


def test_lift_legs_end_exactly_at_the_goal():
    """Waypoints of known legs: the last is the goal; between consecutive ones the car
    either turns its wheels at rest (by at most PHI_STEP) or drives with ``φ`` fixed along
    the integrated arc of curvature ``tan φ / L``."""
    legs = [Leg(kappa, s) for kappa, s in KNOWN["cusp, left then right backwards"]]
    x0 = np.array([0.4, -0.2, 2.6, 0.3])
    end = compose(x0[:3], [(leg.kappa, leg.length) for leg in legs])
    xg = np.array([*end, -0.2])
    pts = lift_legs(legs, x0, xg, WHEELBASE)
    assert np.array_equal(pts[0], x0) and np.array_equal(pts[-1], xg)
    for p, q in itertools.pairwise(pts):
        if np.allclose(p[:3], q[:3], atol=1e-12):
            assert 0 < abs(q[3] - p[3]) <= PHI_STEP + 1e-12
            continue
        assert q[3] == p[3]
        kappa = math.tan(p[3]) / WHEELBASE
        s = (q[2] - p[2]) / kappa if abs(kappa) > 1e-12 else float(
            np.dot(q[:2] - p[:2], [math.cos(p[2]), math.sin(p[2])]))
        assert np.allclose(integrated(p[:3], kappa, s), q[:3], atol=1e-8)
    # the steering angle on each leg is the leg's: atan(L κ)
    phis = {round(float(p[3]), 12) for p in pts}
    assert round(math.atan(WHEELBASE * K), 12) in phis
    assert round(math.atan(-WHEELBASE * K), 12) in phis


def test_lift_legs_refuse_another_turn_of_the_heading():
    legs = [Leg(K, 0.5)]
    x0 = np.zeros(4)
    end = leg_end(x0[:3], K, 0.5)
    with pytest.raises(PlanningError, match="heading"):
        lift_legs(legs, x0, np.array([*end[:2], end[2] + 2 * math.pi, 0.0]), WHEELBASE)
    with pytest.raises(PlanningError, match="goal"):
        lift_legs(legs, x0, np.array([end[0] + 1e-3, end[1], end[2], 0.0]), WHEELBASE)


def test_guide_path_in_the_open_is_driven_exactly_to_the_goal():
    """Without obstacles the guide is (near) the Reeds–Shepp curve of its radius, and its
    waypoints, driven piece by piece by the exact flows (``exact_piece``, each from the
    state the last one reached), end at the goal."""
    pytest.importorskip("ompl")
    from nilpotent.models import get_model
    from nilpotent.planning.guide import exact_piece, guide_path
    from nilpotent.planning.verify import Checker

    system = get_model("car")
    checker = Checker(system)
    x0, xg = np.array([0.0, 0.0, 0.0, 0.2]), np.array([1.5, 0.8, 2.0, 0.0])
    # the first path comes in milliseconds in the open; the rest of the 2 s improves it
    guide = guide_path(checker, x0, xg, seconds=2.0, seed=0)
    assert guide.radius == pytest.approx(RADIUS, rel=1e-12)
    ob = pytest.importorskip("ompl.base")
    space = ob.ReedsSheppStateSpace(RADIUS)
    distance = space.distance(rs_state(space, x0), rs_state(space, xg))
    assert distance - 1e-9 <= guide.length <= 1.05 * distance
    pts = [np.array(p) for p in guide.points]
    assert np.array_equal(pts[0], x0) and np.array_equal(pts[-1], xg)
    x = x0
    for prev, w in itertools.pairwise(pts):
        piece = exact_piece(checker, x, prev, w, 1e-8, 20, WHEELBASE)
        assert piece is not None
        x = np.array(piece.reached)
    assert np.allclose(x, xg, atol=1e-8)


def test_guide_grown_from_a_goal_in_the_slot_is_driven_from_the_start(monkeypatch):
    """A goal in the parking slot (less clearance than the start): the search grows from the
    goal and the path is reversed (each leg's curvature kept, its signed length negated).
    The waypoints, driven piece by piece by the exact flows from the start, end at the goal,
    and every waypoint is admissible (a piece the exact flow cannot drive, which the planner
    would steer, is allowed twice at most)."""
    pytest.importorskip("ompl")
    from nilpotent.models import get_model
    from nilpotent.planning.guide import exact_piece, guide_path
    from nilpotent.planning.verify import Checker
    from nilpotent.planning.world import load_world

    system = get_model("car")
    checker = Checker(system, load_world("parking"))
    x0, xg = np.array([-2.0, 1.0, 0.0, 0.0]), np.array([1.0, -0.55, 0.0, 0.0])
    assert checker.measures(xg[None])[0][0] < checker.measures(x0[None])[0][0]
    import nilpotent.planning.guide as guide_module

    # a generous time for the first path (a loaded CI machine), a short improvement
    monkeypatch.setattr(guide_module, "IMPROVE_SECONDS", 1.0)
    guide = guide_path(checker, x0, xg, seconds=60.0, seed=3)
    pts = [np.array(p) for p in guide.points]
    assert np.array_equal(pts[0], x0) and np.array_equal(pts[-1], xg)
    assert np.all(checker.valid(np.array(pts)))
    x, steered = x0, []
    for i, (prev, w) in enumerate(itertools.pairwise(pts)):
        piece = exact_piece(checker, x, prev, w, 1e-8, 20, WHEELBASE)
        if piece is None:  # allowed (the planner then steers it), but rare
            steered.append((i, checker.why_invalid(w)))
            x = w
        else:
            x = np.array(piece.reached)
    assert len(steered) <= 2, steered
    assert np.allclose(x, xg, atol=1e-8)
