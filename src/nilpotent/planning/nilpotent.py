"""Exact steering of nilpotent systems in privileged coordinates (the mathematics page, §7).

Input: a :class:`~nilpotent.planning.triangular.TriangularSystem` (the fields
``X̂_i`` of a nilpotent approximation as polynomials in privileged coordinates
``y`` with weights ``w_j``), a start and a goal.  Output: controls
(:class:`~nilpotent.planning.controls.Segment`) that steer the *nilpotent*
system from start to goal, checked with the closed-form flow of
:mod:`nilpotent.planning.exact_flow` to reach the goal to machine precision.

Two methods, chosen by name from :data:`METHODS`:

``"step2"`` (closed form, step ≤ 2, e.g. the trident snake)
    1. a straight segment: constant inputs ``u = B⁺ Δ`` for one time unit, with
       ``B`` the (constant) weight-1 components of the ``X̂_i`` and ``Δ`` the
       weight-1 displacement.  Its weight-2 drift is computed exactly;
    2. one segment of loops: for every pair ``a < b`` of inputs a sinusoid of
       its own harmonic ``k``, ``u_a = α sin(kωt)``, ``u_b = β cos(kωt)``, over
       one period of the base frequency ``ω``.  The loop in the plane
       ``(∫u_a, ∫u_b)`` is closed and encloses the signed (Lévy) area
       ``S_ab = ½∫(U_a u_b − U_b u_a) dt = −αβπ/(kω²)``; distinct harmonics do
       not interact, and in a step-2 nilpotent system the displacement is
       exactly ``Σ_{a<b} S_ab [X̂_a, X̂_b]`` (constant brackets, convention
       ``[X,Y] = DY·X − DX·Y``).  The areas solve the linear system
       ``G S = (remaining weight-2 displacement)`` (minimum norm), where the
       column of ``G`` for a pair is the displacement of its unit-area loop,
       itself computed with the exact flow (so no sign convention can slip).

``"newton"`` (any step)
    The step-2 solution (or a straight segment) plus sinusoids of harmonics
    ``1..K`` (``K`` = the step) on every input is the initial guess; the
    coefficients are corrected by damped Gauss–Newton (Levenberg–Marquardt,
    minimum-norm steps) on the *exact* endpoint map and its exact Jacobian
    (forward-mode through the closed-form flow) until the goal is reached to
    rounding; deterministic restarts from seeded random guesses if needed.
    This is an exact method in the sense that the equations solved are those of
    the true nilpotent flow (no truncated Chen–Fliess series): it replaces
    Lafferriere–Sussmann's backward Hall-basis (P. Hall basis) computation for
    triangular polynomial systems.

Both exploit homogeneity: the problem is first dilated by ``δ_{1/λ}``
(``λ`` the quasi-norm ``max_j |y_j|^{1/w_j}`` of start and goal) so that it has
unit size; if ``u`` steers ``a → b`` then ``λu`` steers ``δ_λ a → δ_λ b``.
Controls therefore scale like the distance to the goal.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from nilpotent.errors import PlanningError
from nilpotent.numeric.types import State
from nilpotent.planning import budget
from nilpotent.planning.controls import (
    InputSignal,
    Segment,
    coefficients,
    constant_segment,
    from_coefficients,
)
from nilpotent.planning.exact_flow import endpoint, endpoint_and_jacobian
from nilpotent.planning.triangular import TriangularSystem


class StepTooHighError(PlanningError):
    """A steering method of step ≤ 2 (``"step2"``) asked of a higher step.

    Not a failure of one steering: callers that retry smaller pieces or other
    dampings re-raise it, so the user sees this message rather than a
    "pieces down to ..." refusal.
    """

#: Base frequency of the loop segments (one period in one time unit).
LOOP_OMEGA = 2 * math.pi
#: Target accuracy, relative to the unit-size dilated problem.
UNIT_TOL = 1e-13


@dataclass(frozen=True)
class NilpotentSteering:
    """Controls steering a nilpotent system, with their exact check.

    Attributes
    ----------
    system:
        The triangular system steered.
    start, goal:
        In privileged coordinates ``y``.
    segments:
        The controls (t restarts at 0 in every segment).
    reached:
        ``y`` at the end, from the closed-form flow.
    error:
        ``‖reached − goal‖_∞``.
    method:
        ``"step2"`` or ``"newton"``.
    scale:
        The dilation factor ``λ`` used (0 when start = goal).
    """

    system: TriangularSystem
    start: tuple[float, ...]
    goal: tuple[float, ...]
    segments: tuple[Segment, ...]
    reached: tuple[float, ...]
    error: float
    method: str
    scale: float


def _weight_slices(system: TriangularSystem) -> tuple[list[int], list[int]]:
    w1 = [j for j in range(system.n) if system.weights[j] == 1]
    w2 = [j for j in range(system.n) if system.weights[j] == 2]
    return w1, w2


def _straight(system: TriangularSystem, y_start: np.ndarray, y_goal: np.ndarray) -> Segment | None:
    w1, _ = _weight_slices(system)
    delta = y_goal[w1] - y_start[w1]
    if not np.any(delta):
        return None
    b = system.weight_one_matrix()
    u, *_ = np.linalg.lstsq(b, delta, rcond=None)
    if np.max(np.abs(b @ u - delta)) > 1e-12 * max(1.0, float(np.max(np.abs(delta)))):
        raise PlanningError(
            "the weight-1 components of the approximation do not span the weight-1 "
            "coordinates: not a nilpotent approximation in privileged coordinates"
        )
    return constant_segment(u, 1.0)


def _loop_inputs(
    m: int, pairs: Sequence[tuple[int, int]], areas: Sequence[float], omega: float
) -> tuple[InputSignal, ...]:
    """Inputs of one loop segment: pair ``p`` uses harmonic ``p+1`` and encloses ``areas[p]``."""
    k_max = len(pairs)
    cos = np.zeros((m, k_max))
    sin = np.zeros((m, k_max))
    for p, ((a, b), s) in enumerate(zip(pairs, areas, strict=True)):
        k = p + 1
        rho = math.sqrt(k * omega**2 * abs(s) / math.pi)
        sin[a, p] += -math.copysign(rho, s)
        cos[b, p] += rho
    return tuple(InputSignal(0.0, tuple(cos[i]), tuple(sin[i])) for i in range(m))


def bracket_matrix(system: TriangularSystem) -> np.ndarray:
    """Columns ``[X̂_a, X̂_b](0)`` for the pairs ``a < b`` (lexicographic), shape ``(n, pairs)``.

    ``[X,Y] = DY·X − DX·Y``; only the terms of total degree ≤ 1 of the ``P_ij``
    matter at 0.  For a step-2 system these brackets are constant fields.
    """
    n, m = system.n, system.m
    const = np.zeros((m, n))
    lin = np.zeros((m, n, n))  # lin[i, j, l] = coefficient of y_l in P_ij
    for i in range(m):
        for j in range(n):
            for c, e in system.terms[i][j]:
                deg = sum(e)
                if deg == 0:
                    const[i, j] += c
                elif deg == 1:
                    lin[i, j, e.index(1)] += c
    cols = [
        lin[b] @ const[a] - lin[a] @ const[b] for a in range(m) for b in range(a + 1, m)
    ]
    return np.array(cols).T.reshape(n, -1)


def _loop_segment(
    system: TriangularSystem, y_from: np.ndarray, y_goal: np.ndarray
) -> Segment | None:
    """Loops whose areas produce the weight-2 displacement ``y_goal − y_from`` (closed form)."""
    _, w2 = _weight_slices(system)
    if not w2:
        return None
    residual = (y_goal - y_from)[w2]
    if not np.any(residual):
        return None
    m = system.m
    pairs = [(a, b) for a in range(m) for b in range(a + 1, m)]
    g = bracket_matrix(system)[w2]
    areas, *_ = np.linalg.lstsq(g, residual, rcond=None)
    if np.max(np.abs(g @ areas - residual)) > 1e-10 * max(1.0, float(np.max(np.abs(residual)))):
        raise PlanningError(
            "the brackets [X̂a,X̂b] do not span the weight-2 coordinates: "
            "the approximation is not bracket generating in two steps"
        )
    keep = [p for p in range(len(pairs)) if abs(areas[p]) > 0]
    # keep harmonics consecutive for the pairs actually used
    used_pairs = [pairs[p] for p in keep]
    used_areas = [float(areas[p]) for p in keep]
    return Segment(1.0, LOOP_OMEGA, _loop_inputs(m, used_pairs, used_areas, LOOP_OMEGA))


def _closed_form(system: TriangularSystem, ys: np.ndarray, yg: np.ndarray) -> list[Segment]:
    segments: list[Segment] = []
    straight = _straight(system, ys, yg)
    y = ys
    if straight is not None:
        segments.append(straight)
        y = endpoint(system, ys, segments)
    loops = _loop_segment(system, y, yg)
    if loops is not None:
        segments.append(loops)
    return segments


# --- Newton on the exact endpoint map --------------------------------------------------------
def _layout(segments: Sequence[Segment]) -> list[int]:
    return [max((s.harmonics for s in seg.inputs), default=0) for seg in segments]


_flatten = coefficients
_unflatten = from_coefficients


def _levenberg_marquardt(
    system: TriangularSystem,
    ys: np.ndarray,
    yg: np.ndarray,
    template: Sequence[Segment],
    harmonics: Sequence[int],
    theta: np.ndarray,
    max_iter: int = 60,
) -> tuple[np.ndarray, float]:
    mu = 1e-3
    segs = _unflatten(theta, template, harmonics, system.m)
    val, jac = endpoint_and_jacobian(system, ys, segs, harmonics)
    res = yg - val
    err = float(np.max(np.abs(res)))
    for _ in range(max_iter):
        if err <= UNIT_TOL:
            break
        budget.check("steering the nilpotent approximation (Levenberg-Marquardt)")
        jjt = jac @ jac.T
        improved = False
        for _ in range(12):
            step = jac.T @ np.linalg.solve(jjt + mu * np.eye(len(res)), res)
            cand = theta + step
            c_segs = _unflatten(cand, template, harmonics, system.m)
            c_val, c_jac = endpoint_and_jacobian(system, ys, c_segs, harmonics)
            c_res = yg - c_val
            c_err = float(np.max(np.abs(c_res)))
            if c_err < err:
                theta, res, jac, err = cand, c_res, c_jac, c_err
                mu = max(mu / 10, 1e-15)
                improved = True
                break
            mu *= 10
        if not improved:
            break
    return theta, err


def _newton(system: TriangularSystem, ys: np.ndarray, yg: np.ndarray, seed: int) -> list[Segment]:
    m = system.m
    straight = _straight(system, ys, yg)
    y_mid = ys if straight is None else endpoint(system, ys, [straight])
    loops = _loop_segment(system, y_mid, yg)
    empty = Segment(1.0, LOOP_OMEGA, tuple(InputSignal() for _ in range(m)))
    k = max(system.step, m * (m - 1) // 2)
    head = [] if straight is None else [straight]
    template = [*head, empty]
    harmonics = [0] * len(head) + [k]
    theta0 = _flatten([*head, loops or empty], harmonics)
    rng = np.random.default_rng(seed)
    best_theta, best_err = theta0, math.inf
    for attempt in range(10):
        start = theta0
        if attempt > 0 or system.step > 2:
            start = theta0 + rng.normal(scale=0.5 if attempt < 5 else 1.5, size=theta0.shape)
        theta, err = _levenberg_marquardt(system, ys, yg, template, harmonics, start)
        if err < best_err:
            best_theta, best_err = theta, err
        if best_err <= UNIT_TOL:
            break
    return _unflatten(best_theta, template, harmonics, m)


def _geodesic(system: TriangularSystem, ys: np.ndarray, yg: np.ndarray, seed: int) -> list[Segment]:
    if system.step > 2:  # normal-geodesic shooting (imports this module's types)
        from nilpotent.planning.shooting import shooting_segments

        return shooting_segments(system, ys, yg, seed)
    from nilpotent.planning.geodesic import geodesic_segments  # imports this module's types

    return geodesic_segments(system, ys, yg, seed)


#: Steering methods by name: ``f(system, y_start_unit, y_goal_unit, seed) -> segments``.
#: ``"geodesic"``: the shortest normal geodesic found: closed form for step ≤ 2
#: (:mod:`nilpotent.planning.geodesic`), shooting above (:mod:`nilpotent.planning.shooting`).
METHODS: dict[str, Callable[[TriangularSystem, np.ndarray, np.ndarray, int], list[Segment]]] = {
    "step2": lambda system, ys, yg, seed: _closed_form(system, ys, yg),
    "newton": _newton,
    "geodesic": _geodesic,
}


_NEGLIGIBLE_SCALE = 1e-100
"""Start and goal within this quasi-norm of 0 are not steered (they are 0 to rounding)."""


def steer_nilpotent(
    system: TriangularSystem,
    y_start: Sequence[float] | State,
    y_goal: Sequence[float] | State,
    *,
    method: str = "auto",
    seed: int = 0,
) -> NilpotentSteering:
    """Controls that steer the nilpotent ``system`` from ``y_start`` to ``y_goal`` exactly.

    Parameters
    ----------
    system:
        Fields ``X̂_i`` polynomial and triangular in privileged coordinates.
    y_start, y_goal:
        Points in those coordinates.
    method:
        ``"step2"`` (closed form; step ≤ 2), ``"newton"`` (any step),
        ``"geodesic"`` (shortest normal geodesic; closed form for step ≤ 2,
        shooting above) or
        ``"auto"`` (``"step2"`` when the step is ≤ 2, else ``"newton"``).
    seed:
        Seed of the random restarts of ``"newton"`` (results are reproducible).

    Returns
    -------
    NilpotentSteering
        With ``error = ‖reached − goal‖_∞`` from the closed-form flow; a
        :class:`~nilpotent.errors.PlanningError` is raised if the goal is not
        reached to ``1e-12·max(1, ‖goal‖)``.

    Raises
    ------
    PlanningError
        Start or goal of the wrong size, an unknown method, ``"step2"`` for a
        system of step > 2, or a goal the method does not reach to the
        tolerance above.

    Examples
    --------
    >>> import sympy as sp
    >>> y1, y2, y3 = sp.symbols("y1 y2 y3")
    >>> h = TriangularSystem.from_fields(((1, 0, -y2/2), (0, 1, y1/2)), (y1, y2, y3), (1, 1, 2))
    >>> s = steer_nilpotent(h, (0, 0, 0), (0.1, -0.2, 0.3))
    >>> s.error < 1e-14, len(s.segments)
    (True, 2)
    """
    if method == "auto":
        method = "step2" if system.step <= 2 else "newton"
    if method not in METHODS:
        raise PlanningError(f"unknown steering method {method!r} (known: {', '.join(METHODS)})")
    if method == "step2" and system.step > 2:
        raise StepTooHighError(
            f"the {method!r} method needs step <= 2; this nilpotent approximation has step "
            f"{system.step}"
        )
    ys = np.asarray(y_start, dtype=float)
    yg = np.asarray(y_goal, dtype=float)
    if ys.shape != (system.n,) or yg.shape != (system.n,):
        raise PlanningError(f"start and goal need {system.n} privileged coordinates")
    scale = max(system.quasi_norm(ys), system.quasi_norm(yg))
    if scale < _NEGLIGIBLE_SCALE or np.array_equal(ys, yg):
        # nothing to steer (below this scale the dilation to the unit sphere overflows)
        err = float(np.max(np.abs(ys - yg)))
        return NilpotentSteering(system, tuple(ys), tuple(yg), (), tuple(ys), err, method, 0.0)
    unit_s = system.dilate(ys, 1 / scale)
    unit_g = system.dilate(yg, 1 / scale)
    segments = METHODS[method](system, unit_s, unit_g, seed)
    unit_reached = endpoint(system, unit_s, segments)
    if method == "step2" and np.max(np.abs(unit_reached - unit_g)) > UNIT_TOL:
        # polish rounding of the closed form with the exact Newton
        template = list(segments)
        harmonics = _layout(template)
        theta, _ = _levenberg_marquardt(
            system, unit_s, unit_g, template, harmonics, _flatten(template, harmonics)
        )
        segments = _unflatten(theta, template, harmonics, system.m)
    segments = [s.scaled(scale) for s in segments]
    reached = endpoint(system, ys, segments)
    error = float(np.max(np.abs(reached - yg)))
    if error > 1e-12 * max(1.0, float(np.max(np.abs(yg)))):
        raise PlanningError(
            f"exact steering of the nilpotent system did not converge (error {error:.3g}, "
            f"method {method})"
        )
    return NilpotentSteering(
        system, tuple(ys), tuple(yg), tuple(segments), tuple(reached), error, method, scale
    )
