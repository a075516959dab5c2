"""What a plan costs: its sub-Riemannian length, and the shortest length of the approximation.

* :data:`OBJECTIVES` — what the local steering optimises: ``"reach"`` (today's
  straight segment and loops, or Newton for step ≥ 3: reach the goal, no
  length criterion) or ``"length"`` (the shortest normal geodesic of the
  nilpotent approximation: closed form for step 2,
  :mod:`nilpotent.planning.geodesic`; shooting for step ≥ 3,
  :mod:`nilpotent.planning.shooting`);
* :func:`length_report` — the ``length``, ``lower_bound``, ``length_ratio`` and
  ``abnormal`` fields every plan's JSON carries.

``lower_bound`` is the sub-Riemannian distance from start to goal of the
nilpotent approximation at the start, computed as the length of the shortest
normal geodesic found (:func:`~nilpotent.planning.geodesic.shortest_geodesic`,
or :func:`~nilpotent.planning.shooting.shortest_normal_geodesic` for step ≥ 3).
Where the approximation reproduces the system (its fields agree with the
system's at the goal and at seeded random points, to 1e-12: ``heisenberg``)
this is the exact distance of the system, so ``length ≥ lower_bound`` holds for
every plan (``lower_bound_kind = "exact"``).  For other systems it is the
distance of the first-order approximation: equal to the true distance to first
order in the distance, not a certified bound (``"approximation"``); for step
≥ 3 the shooting's multi-start may also miss the shortest branch, so it is not
certified even for the approximation.  ``abnormal`` (step ≥ 3) says whether
that geodesic is also a singular curve (the endpoint map's differential along
it has rank < n); ``null`` for step 2 (not checked).  ``null`` (with a reason)
at singular points, or when no geodesic converged.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ComputationLimitError, NilpotentError, PlanningError
from nilpotent.planning import budget
from nilpotent.planning.controls import Segment
from nilpotent.planning.geodesic import control_length, shortest_geodesic

__all__ = ["OBJECTIVES", "length_report", "method_for"]

#: Objectives of the local steering: name → the nilpotent steering method it uses.
OBJECTIVES: dict[str, str] = {"reach": "auto", "length": "geodesic"}

#: Most seconds the plan report spends shooting the approximation's geodesic (step >= 3)
#: for its ``lower_bound``; beyond, the bound is null with the reason.
LOWER_BOUND_SECONDS = 20.0


def method_for(objective: str, method: str = "auto") -> str:
    """The nilpotent steering method (:data:`nilpotent.planning.nilpotent.METHODS`) of an objective.

    Parameters
    ----------
    objective : str
        ``"reach"`` or ``"length"``.
    method : str
        An explicit method (only with ``"reach"``), or ``"auto"``.

    Returns
    -------
    str

    Raises
    ------
    PlanningError
        An unknown objective, or an explicit method that contradicts ``"length"``.
    """
    if objective not in OBJECTIVES:
        raise PlanningError(
            f"unknown objective {objective!r} (choose from {', '.join(OBJECTIVES)})"
        )
    if objective == "length":
        if method not in ("auto", "geodesic"):
            raise PlanningError(
                f"objective 'length' steers along geodesics; method {method!r} contradicts it"
            )
        return "geodesic"
    return method


def _reproduces(system: ControlSystem, model: Any, goal: np.ndarray) -> bool:
    """Whether the approximation *is* the system (fields equal at sample points, 1e-12).

    Checked at the goal and at seeded random points around start and goal: the
    fields of a nilpotent system in linear adapted coordinates are polynomials
    of degree ≤ 1 in ``y``, so agreement at generic points means equality.
    """
    from nilpotent.planning.local_model import compiled_system

    compiled = compiled_system(system)
    p = np.asarray(model.point, dtype=float)
    rng = np.random.default_rng(0)
    scale = 1.0 + float(np.max(np.abs(goal - p)))
    points = [goal, *(p + scale * rng.normal(size=p.size) for _ in range(3))]
    for x in points:
        with np.errstate(all="ignore"):
            true = compiled.field_values(x)[0]
        y = model.forward(x)
        # pull the approximation back: X_i = F X̂_i(y) with F the inverse of the linear map
        f = np.array([model.inverse(e) - p for e in np.eye(p.size)]).T
        pulled = f @ model.nilpotent.field_values(y)
        if not np.all(np.isfinite(true)) or np.max(np.abs(true - pulled)) > 1e-12 * (
            1.0 + float(np.max(np.abs(true)))
        ):
            return False
    return True


def _approximation_distance(
    system: ControlSystem, start: Sequence[float], goal: Sequence[float], objective: str
) -> tuple[float | None, str, bool, bool | None]:
    """Length of the shortest geodesic found of the approximation at the start, why not,
    whether the approximation is the system, and whether the geodesic is abnormal.

    For step >= 3 the shooting costs seconds: it runs only for plans of objective
    ``"length"``, within :data:`LOWER_BOUND_SECONDS` (and the budget in force)."""
    from nilpotent.planning.local_model import choose_builder, numeric_model, symbolic_model

    x0 = np.asarray(start, dtype=float)
    xg = np.asarray(goal, dtype=float)
    try:
        if choose_builder(system, x0) != "numeric":
            if objective != "length":
                return (None, "for step >= 3 the approximation's geodesic (the shooting, "
                        "seconds of work) is computed for --objective length only", False, None)
            from nilpotent.planning.shooting import shortest_normal_geodesic

            model = symbolic_model(system, x0)
            try:
                with budget.time_budget(LOWER_BOUND_SECONDS):
                    shot = shortest_normal_geodesic(model.nilpotent, np.zeros(system.n),
                                                    model.forward(xg))
            except ComputationLimitError:
                return (None, f"the shooting of the approximation's geodesic did not end "
                        f"within {LOWER_BOUND_SECONDS:g} s (or the time limit)", False, None)
            return shot.length, "", False, shot.abnormal
        model = numeric_model(system, x0)
        geo = shortest_geodesic(model.nilpotent, np.zeros(system.n), model.forward(xg))
    except NilpotentError as exc:
        return None, f"no geodesic of the approximation at the start: {exc}", False, None
    return geo.length, "", _reproduces(system, model, xg), None


def length_report(
    system: ControlSystem,
    start: Sequence[float],
    goal: Sequence[float],
    segments: Sequence[Segment],
    objective: str = "reach",
) -> tuple[dict[str, Any], dict[str, str]]:
    """The plan JSON's ``length``, ``lower_bound``, ``lower_bound_kind``, ``length_ratio``
    and ``abnormal``.

    Parameters
    ----------
    system : ControlSystem
        The model planned for.
    start, goal : sequence of float
        Model coordinates.
    segments : sequence of Segment
        The plan's controls.
    objective : str
        The plan's objective; for step >= 3 the bound is computed for ``"length"`` only.

    Returns
    -------
    fields, null_reasons : dict
        The fields, and for each one that is ``None`` the reason.
    """
    length = control_length(segments)
    bound, why, exact, abnormal = _approximation_distance(system, start, goal, objective)
    reasons: dict[str, str] = {}
    if abnormal is None:
        reasons["abnormal"] = why or "checked for step >= 3 (the shooting) only"
    kind: str | None = None
    ratio: float | None = None
    if bound is None:
        reasons["lower_bound"] = why
        reasons["length_ratio"] = why
    else:
        kind = "exact" if exact else "approximation"
        if bound > 0:
            ratio = length / bound
        else:
            reasons["length_ratio"] = "start and goal coincide"
    return {
        "length": length,
        "lower_bound": bound,
        "lower_bound_kind": kind,
        "length_ratio": ratio,
        "abnormal": abnormal,
    }, reasons


def check_objective(objective: str) -> None:
    """Raise :class:`PlanningError` unless ``objective`` is one of :data:`OBJECTIVES`.

    Parameters
    ----------
    objective : str
        The name to check.

    Raises
    ------
    PlanningError
        Unknown name.
    """
    method_for(objective)
