"""Local nilpotent models of a system at float points, for iterative steering.

A :class:`LocalModel` bundles what one iteration of the mathematics page, §7, needs at a base
point ``p``: the nilpotent approximation as a float
:class:`~nilpotent.planning.triangular.TriangularSystem` in privileged
coordinates ``y``, and the maps ``x ↦ y(x)`` and ``y ↦ x(y)``.

Two builders (registry :data:`BUILDERS`):

``"numeric"`` (step ≤ 2, e.g. the trident snake; fast)
    Linear adapted coordinates, computed from float values only.  The frame
    is ``Y_1..Y_{n_1}`` = the first fields ``X_i`` independent at ``p`` and
    ``Y_{n_1+1}..Y_n`` = the first brackets ``[X_a,X_b]`` (``a < b``,
    lexicographic: the length-2 Hall words) completing a basis, with
    ``[X_a,X_b](p) = DX_b(p)X_a(p) − DX_a(p)X_b(p)``.  With ``F`` the matrix
    of the frame at ``p`` and ``A = F⁻¹``: ``y = A(x − p)``, ``x = p + F y``
    (privileged when the step is ≤ 2, the mathematics page, §4).  In these coordinates
    ``X_i`` reads ``A X_i(p + F y)``; keeping the terms of weighted degree
    ``w_j − 1`` gives ``X̂_i``: the constants ``(A X_i(p))_j`` for ``w_j = 1``,
    and ``Σ_{w_l = 1} (A DX_i(p) F)_{jl} y_l`` for ``w_j = 2``.  Costs a few
    evaluations of compiled fields and Jacobians (about 0.1 ms), so it can be
    redone at every iterate.

``"symbolic"`` (any step)
    :func:`nilpotent.core.coordinates.approximation.approximate` at the point (exact
    symbolic work, cached per point), its fields converted to floats and its
    coordinate maps compiled by :func:`nilpotent.numeric.compile.compile_map`.

Regularity is checked numerically: the growth vector at ``p`` (ranks of the
fields and of fields plus brackets, decided by the one float-rank engine
:func:`nilpotent.core.decide.numeric_rank`: scale-free, relative tolerance)
must equal the one at random points nearby; otherwise
:class:`~nilpotent.errors.SingularPointError`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import NotBracketGeneratingError, PlanningError, SingularPointError
from nilpotent.numeric.compile import CompiledSystem, compile_map, compile_system
from nilpotent.numeric.types import State
from nilpotent.planning.triangular import TriangularSystem


@dataclass(frozen=True, eq=False)
class LocalModel:
    """The nilpotent approximation at a float point, ready for steering.

    Attributes
    ----------
    point:
        The base point ``p`` (model coordinates).
    nilpotent:
        ``X̂_i`` in privileged coordinates ``y`` (``y(p) = 0``).
    forward:
        ``x ↦ y(x)`` (float arrays ``(n,)``).
    inverse:
        ``y ↦ x(y)``.
    growth_vector:
        ``(n_1(p), …)`` as computed numerically (or by the symbolic approximation).
    builder:
        ``"numeric"`` or ``"symbolic"``.
    """

    point: tuple[float, ...]
    nilpotent: TriangularSystem
    forward: Callable[[np.ndarray], np.ndarray]
    inverse: Callable[[np.ndarray], np.ndarray]
    growth_vector: tuple[int, ...]
    builder: str


def _rank(mat: np.ndarray) -> int:
    """Rank of the columns of ``mat`` by the one float-rank engine (scale-free: each column
    normalised, relative tolerance ``FLOAT_RELATIVE_TOLERANCE``)."""
    from nilpotent.core.decide import numeric_rank  # the one float-rank engine

    return numeric_rank(mat.T.tolist()) if mat.size else 0


def _values(compiled: CompiledSystem, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    with np.errstate(all="ignore"):
        fields = compiled.field_values(p)[0]  # (n, m)
        jac = compiled.jacobian(p)[0]  # (m, n, n)
    if not (np.all(np.isfinite(fields)) and np.all(np.isfinite(jac))):
        raise SingularPointError(
            f"the fields of {compiled.name} are not defined (not finite) at {_fmt(p)}"
        )
    m = fields.shape[1]
    brackets = [
        jac[b] @ fields[:, a] - jac[a] @ fields[:, b] for a in range(m) for b in range(a + 1, m)
    ]
    return fields, np.array(brackets).T.reshape(fields.shape[0], -1)


def numeric_growth(compiled: CompiledSystem, p: np.ndarray) -> tuple[int, int]:
    """``(n_1(p), n_2(p))``: ranks of the fields and of the fields with their brackets."""
    fields, brackets = _values(compiled, p)
    return _rank(fields), _rank(np.hstack([fields, brackets]))


def compiled_system(system: ControlSystem) -> CompiledSystem:
    """The compiled fields of ``system`` (parameters substituted; memoised by
    :func:`~nilpotent.numeric.compile.compile_system`)."""
    return compile_system(system)


#: Random points of :func:`generic_growth`, their spread around the point, and how many
#: times a point where the fields are not defined is redrawn (each time twice closer).
GENERIC_SAMPLES = 3
GENERIC_SPREAD = 0.1
GENERIC_REDRAWS = 12


def generic_growth(compiled: CompiledSystem, p: np.ndarray, seed: int = 0) -> tuple[int, int]:
    """The largest ``(n_1, n_2)`` at :data:`GENERIC_SAMPLES` random points near ``p``.

    The points are drawn within about :data:`GENERIC_SPREAD` of ``p``; one where the
    fields are not defined (outside the model's domain, e.g. a chart ``|v| < 1``) is
    discarded and redrawn twice closer, up to :data:`GENERIC_REDRAWS` times.

    Raises
    ------
    SingularPointError
        No drawn point near ``p`` is in the domain (``p`` is on its edge).
    """
    rng = np.random.default_rng(seed)
    best = (0, 0)
    usable = 0
    closest = GENERIC_SPREAD
    for _ in range(GENERIC_SAMPLES):
        spread = GENERIC_SPREAD
        for _ in range(GENERIC_REDRAWS):
            q = p + spread * rng.standard_normal(p.shape)
            try:
                g = numeric_growth(compiled, q)
            except SingularPointError:  # not defined there: redraw closer
                closest = min(closest, spread)
                spread /= 2
                continue
            best = max(best, g)
            usable += 1
            break
    if not usable:
        raise SingularPointError(
            f"no point near {_fmt(p)} where the fields of {compiled.name} are defined: "
            f"{GENERIC_SAMPLES * GENERIC_REDRAWS} random points within {GENERIC_SPREAD:g} down "
            f"to {closest / 2:.2g} of it were all outside the model's domain (not finite); "
            "the point is on the edge of the domain, where steering cannot start"
        )
    return best


def check_regular(
    system: ControlSystem, point: Sequence[float] | State, what: str
) -> tuple[int, int]:
    """Raise :class:`SingularPointError` if ``point`` is singular for the first two steps.

    Returns ``(n_1, n_2)`` at the point.
    """
    compiled = compiled_system(system)
    p = np.asarray(point, dtype=float)
    here = numeric_growth(compiled, p)
    generic = generic_growth(compiled, p)
    if here != generic:
        raise SingularPointError(
            f"the {what} {_fmt(p)} is a singular point of {system.name}: dimensions of the "
            f"fields and first brackets there are {here}, nearby {generic}; steering needs "
            "regular start, goal and path"
        )
    return here


def _fmt(p: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.6g}" for v in p) + ")"


def numeric_model(system: ControlSystem, point: Sequence[object] | State) -> LocalModel:
    """The step-2 nilpotent approximation at ``point`` in linear adapted coordinates (floats).

    Raises
    ------
    SingularPointError
        The growth vector at the point differs from the generic one nearby.
    PlanningError
        The step at the point is more than 2 (use the ``"symbolic"`` builder), or the
        adapted frame or the approximation is not representable in double precision.
    """
    compiled = compiled_system(system)
    p = np.array([float(v) for v in point])  # type: ignore[arg-type]
    n = p.size
    fields, brackets = _values(compiled, p)
    n1 = _rank(fields)
    n2 = _rank(np.hstack([fields, brackets]))
    if n2 < n:
        if generic_growth(compiled, p)[1] == n:
            raise SingularPointError(
                f"{_fmt(p)} is a singular point of {system.name}: fields and first brackets "
                f"span {n2} of {n} dimensions there, {n} nearby"
            )
        raise PlanningError(
            f"{system.name} has step > 2 at {_fmt(p)} (fields and first brackets span {n2} of "
            f"{n}): the numeric builder needs step <= 2, use the symbolic one"
        )
    if (n1, n2) != generic_growth(compiled, p):
        raise SingularPointError(
            f"{_fmt(p)} is a singular point of {system.name}: growth ({n1}, {n2}) there, "
            f"{generic_growth(compiled, p)} nearby"
        )
    frame: list[np.ndarray] = []
    for col in [*fields.T, *brackets.T]:
        if len(frame) == n:
            break
        if _rank(np.array([*frame, col]).T) == len(frame) + 1:
            frame.append(col)
    f = np.array(frame).T
    a = np.linalg.inv(f)
    if not np.all(np.isfinite(a)):  # a frame of subnormal size (a field ~1e-320)
        raise PlanningError(
            f"the adapted frame of {system.name} at {_fmt(p)} cannot be inverted in double "
            "precision (its entries are too small or too large); rescale the model's fields"
        )
    weights = tuple([1] * n1 + [2] * (n - n1))
    names = tuple(f"y{j + 1}" for j in range(n))
    jac = compiled.jacobian(p)[0]
    ax = a @ fields  # (n, m)
    terms = []
    for i in range(fields.shape[1]):
        lin = a @ jac[i] @ f  # (n, n): ∂(A X_i(p + F y))_j / ∂y_l at 0
        row = []
        for j in range(n):
            if weights[j] == 1:
                row.append(((float(ax[j, i]), (0,) * n),) if ax[j, i] != 0 else ())
            else:
                row.append(
                    tuple(
                        (float(lin[j, l_]), tuple(int(k == l_) for k in range(n)))
                        for l_ in range(n1)
                        if lin[j, l_] != 0
                    )
                )
        terms.append(tuple(row))
    if not all(math.isfinite(c) for row in terms for entry in row for c, _ in entry):
        raise PlanningError(
            f"the nilpotent approximation of {system.name} at {_fmt(p)} overflows double "
            "precision; rescale the model's fields"
        )
    tri = TriangularSystem(names, weights, tuple(terms))

    def forward(x: np.ndarray) -> np.ndarray:
        return a @ (np.asarray(x, dtype=float) - p)

    def inverse(y: np.ndarray) -> np.ndarray:
        return p + f @ np.asarray(y, dtype=float)

    growth = (n1, n) if n1 < n else (n1,)
    return LocalModel(tuple(p), tri, forward, inverse, growth, "numeric")


def exact_point(point: Sequence[object] | State) -> tuple[sp.Expr, ...]:
    """The point as exact sympy numbers: exact values kept, floats by their shortest decimal."""
    out = []
    for v in point:
        if isinstance(v, sp.Basic) and v.is_number and not v.has(sp.Float):
            out.append(v)
        else:
            out.append(sp.Rational(repr(float(v))))  # type: ignore[arg-type]
    return tuple(out)


def symbolic_model(system: ControlSystem, point: Sequence[object] | State) -> LocalModel:
    """The nilpotent approximation (:func:`nilpotent.core.coordinates.approximate`) at ``point``.

    The point is made exact (:func:`exact_point`) and the symbolic work is
    cached per (system, point); the result is converted to a
    :class:`TriangularSystem` and compiled coordinate maps.

    An exact point that is not rational (``pi/2``, ``sqrt(2)``) is used as its
    float (shortest decimal), as a decimal input is: the exact approximation at an
    algebraic point costs minutes of symbolic work where the floating-point one
    takes a second, and a local model only guides the steering (every plan is
    re-simulated on the true system).  What the float would blur, whether the
    point is regular, is decided first at the exact point (:func:`exact_regularity`).

    Raises
    ------
    SingularPointError
        The point is singular (decided exactly at an exact point).
    NotBracketGeneratingError
        The system is not bracket generating there.
    """
    exact = exact_point(point)
    if not all(v.is_Rational for v in exact):
        exact_regularity(system, exact)
        exact = tuple(sp.Rational(repr(float(v))) for v in exact)
    return _symbolic_model(system, exact)


@lru_cache(maxsize=32)
def exact_regularity(system: ControlSystem, point: tuple[sp.Expr, ...]) -> tuple[int, ...]:
    """The growth vector at an exact ``point`` (:func:`nilpotent.core.analysis.filtration.analyze`,
    the certified decisions), after checking that the point is regular.

    Raises
    ------
    SingularPointError
        The point is singular.
    NotBracketGeneratingError
        The system is not bracket generating there.
    """
    from nilpotent.core.analysis.filtration import ANALYSIS_TIME_BUDGET, analyze
    from nilpotent.planning import budget

    left = budget.seconds_left()
    filt = analyze(system, point, time_budget=min(ANALYSIS_TIME_BUDGET, max(0.5, left)))
    fpoint = np.array([float(v) for v in point])
    _require_regular(system, filt, fpoint)
    return tuple(filt.growth_vector)


def _require_regular(system: ControlSystem, filt: Any, fpoint: np.ndarray) -> None:
    """Raise unless ``filt`` (the filtration at ``fpoint``) is bracket generating and regular."""
    if not filt.bracket_generating:
        raise NotBracketGeneratingError(
            f"{system.name} is not bracket generating at {_fmt(fpoint)}"
        )
    if not filt.regular:
        raise SingularPointError(
            f"{_fmt(fpoint)} is a singular point of {system.name} "
            f"(growth {tuple(filt.growth_vector)}, generic {tuple(filt.generic_growth_vector)})"
        )


@lru_cache(maxsize=32)
def _symbolic_model(system: ControlSystem, point: tuple[sp.Expr, ...]) -> LocalModel:
    from nilpotent.core.coordinates.approximation import approximate

    approx = approximate(system, point)
    filt = approx.filtration
    fpoint = np.array([float(v) for v in point])
    _require_regular(system, filt, fpoint)
    names = tuple(approx.coordinates.names)
    tri = TriangularSystem.from_fields(approx.fields, names, tuple(filt.weights))
    params: dict[str | sp.Symbol, sp.Expr] = {sp.Symbol(k): v for k, v in system.parameters}
    forward = compile_map(system.coordinates, approx.coordinates.forward, params,
                          name=f"{system.name}-forward")
    inverse = compile_map(names, approx.coordinates.inverse, params,
                          name=f"{system.name}-inverse")
    return LocalModel(
        tuple(fpoint), tri, forward, inverse, tuple(filt.growth_vector), "symbolic"
    )


#: Local-model builders by name.
BUILDERS: dict[str, Callable[[ControlSystem, Sequence[object] | State], LocalModel]] = {
    "numeric": numeric_model,
    "symbolic": symbolic_model,
}


def choose_builder(system: ControlSystem, point: Sequence[float] | State) -> str:
    """``"numeric"`` where the system has step ≤ 2 generically near ``point``.

    That is, fields and first brackets span the space at random points nearby
    (at the point itself they may not: it is then singular, which the
    numeric builder reports).  Else ``"symbolic"``.
    """
    compiled = compiled_system(system)
    p = np.array([float(v) for v in point])  # type: ignore[arg-type]
    if numeric_growth(compiled, p)[1] == system.n:
        return "numeric"
    return "numeric" if generic_growth(compiled, p)[1] == system.n else "symbolic"
