"""``anytime_solve``'s restarts: a tree that finds no exact solution within ``restart``
seconds is cleared and grown anew (the trailer guide's stalled trees at the parking slot).

Independent result: a stand-in planner that solves only on its third tree (counted by its
``clear`` calls) and a fixed slice time; the restarts are read off the calls made.
"""

from __future__ import annotations

import pytest

import nilpotent.planning.holonomic_path as hp
from nilpotent.errors import PlanningError


class _Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


class _Planner:
    """Solves on its ``solve_on``-th tree (1-based), one slice after it starts."""

    def __init__(self, clock: _Clock, solve_on: int) -> None:
        self.clock, self.solve_on = clock, solve_on
        self.trees, self.slices, self.solved = 1, 0, False

    def clear(self) -> None:
        self.trees += 1
        self.slices = 0
        self.solved = False

    def solve(self, seconds: float) -> None:
        self.clock.t += seconds
        self.slices += 1
        if self.trees >= self.solve_on and self.slices >= 1:
            self.solved = True

    def bestCost(self):
        return type("Cost", (), {"value": lambda _: 7.0})()


class _Pdef:
    def __init__(self, planner: _Planner) -> None:
        self.planner, self.cleared = planner, 0

    def hasExactSolution(self) -> bool:
        return self.planner.solved

    def clearSolutionPaths(self) -> None:
        self.cleared += 1


@pytest.fixture
def clock(monkeypatch):
    c = _Clock()
    monkeypatch.setattr(hp.time, "perf_counter", c)
    return c


def test_a_stalled_tree_is_cleared_after_restart_seconds(clock):
    planner = _Planner(clock, solve_on=3)
    pdef = _Pdef(planner)
    history = hp.anytime_solve(planner, pdef, 60.0, 0.0, "a path", restart=2.0)
    assert planner.trees == 3 and pdef.cleared == 2
    # trees cleared at 2 s and 4 s, the third solves in its first slice
    assert history[0][0] == pytest.approx(4.0 + hp.SLICE_SECONDS)


def test_without_restart_one_tree_and_the_same_error(clock):
    planner = _Planner(clock, solve_on=3)
    with pytest.raises(PlanningError, match="no collision-free path"):
        hp.anytime_solve(planner, _Pdef(planner), 10.0, 0.0, "a path")
    assert planner.trees == 1


def test_no_restart_after_a_first_solution(clock):
    planner = _Planner(clock, solve_on=1)
    pdef = _Pdef(planner)
    history = hp.anytime_solve(planner, pdef, 60.0, 5.0, "a path", restart=1.0)
    assert planner.trees == 1 and pdef.cleared == 0
    assert history[-1][0] == pytest.approx(hp.SLICE_SECONDS + 5.0)


def test_improvement_stops_at_improve_by(clock):
    """A first path found late (third tree, after 4.25 s) is improved only until
    ``improve_by`` seconds from the start, not ``improve`` seconds after it: the stages
    after the search keep their time."""
    planner = _Planner(clock, solve_on=3)
    history = hp.anytime_solve(planner, _Pdef(planner), 60.0, 30.0, "a path", restart=2.0,
                               improve_by=6.0)
    assert history[0][0] == pytest.approx(4.0 + hp.SLICE_SECONDS)
    assert history[-1][0] == pytest.approx(6.0)
    assert clock.t == pytest.approx(6.0)


def test_improve_by_before_the_first_path_does_not_stop_the_search(clock):
    planner = _Planner(clock, solve_on=3)
    history = hp.anytime_solve(planner, _Pdef(planner), 60.0, 30.0, "a path", restart=2.0,
                               improve_by=1.0)
    assert len(history) == 1 and history[0][0] == pytest.approx(4.0 + hp.SLICE_SECONDS)
