"""Is a configuration, or a re-simulated motion, admissible: limits, collisions, self-collision,
singular margin.

:class:`Checker` bundles what a plan must respect — the box limits, the
world's obstacles and bounds (through the robot's outline), and a margin from
the singular set where the model has one — and evaluates it on arrays of
configurations ``(N, n)`` (vectorised: one shapely call per batch).

:func:`verify_segments` re-simulates controls on the true system densely and
measures the motion: minimum clearance to the obstacles, minimum limit margin,
minimum self-clearance, minimum singular margin, final error.  Every plan the global planner returns
is checked this way.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
import shapely.ops

from nilpotent.core.model.outline import Limits
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import IntegrationError, OptionError
from nilpotent.numeric.settings import IntegrationSettings
from nilpotent.numeric.types import State
from nilpotent.planning.controls import Segment
from nilpotent.planning.robot import Robot, singular_margin_function
from nilpotent.planning.simulation import PLANNING_SETTINGS, simulate_path
from nilpotent.planning.world import World

__all__ = ["NEAR", "Checker", "Verification", "limits_between", "verify_segments", "verify_states"]

#: How near a constraint must be to be named by :meth:`Checker.constraints_near` (model
#: units / radians): about the reach of a steered piece of the shortest length.
NEAR = 0.05


@dataclass(frozen=True, eq=False)
class Checker:
    """Admissibility of configurations for a system in a world.

    Parameters
    ----------
    system:
        The model (its ``geometry`` is its outline; needed when ``world`` is given).
    world:
        Obstacles and bounds, or ``None``.
    limits:
        Box limits (default: the system's).
    singular_margin:
        Required ``margin(q) ≥ singular_margin`` where the model defines a margin
        (:func:`~nilpotent.planning.robot.singular_margin_function`); 0: none required.
    clearance:
        Required distance to the obstacles (> this value; default 0: no contact).

    Raises
    ------
    OptionError
        A world for a model without outline, or a singular margin for a model
        that defines none.
    """

    system: ControlSystem
    world: World | None = None
    limits: Limits | None = None
    singular_margin: float = 0.0
    clearance: float = 0.0

    def __post_init__(self) -> None:
        robot = Robot(self.system, self.limits)
        object.__setattr__(self, "limits", robot.limits)
        object.__setattr__(self, "robot", robot)
        if self.world is not None and not robot.has_outline:
            raise OptionError(
                f"model {self.system.name} has no robot outline: add a [geometry] table to the "
                "model file to plan in a world (docs/model-files.md)"
            )
        margin_fn = singular_margin_function(self.system)
        if self.singular_margin and margin_fn is None:
            raise OptionError(
                f"--singular-margin: model {self.system.name} defines no singular margin "
                "(trident-snake-joints does: |det M|)"
            )
        if not (math.isfinite(self.singular_margin) and self.singular_margin >= 0):
            raise OptionError(f"--singular-margin must be >= 0, got {self.singular_margin}")
        object.__setattr__(self, "margin_fn", margin_fn)

    def measures(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(clearance, limit margin, singular margin)`` at ``q (N, n)``, each ``(N,)``.

        ``+inf`` for what does not apply (no world, no limits, no singular set).
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        clear = np.full(q.shape[0], np.inf)
        if self.world is not None:
            geoms, radii = self.robot.parts(q)  # type: ignore[attr-defined]
            clear = self.world.clearance(geoms, radii).min(axis=1)
        lim = self.robot.limit_margin(q)  # type: ignore[attr-defined]
        sing = np.full(q.shape[0], np.inf)
        if self.margin_fn is not None:  # type: ignore[attr-defined]
            sing = self.margin_fn(q)  # type: ignore[attr-defined]
        return clear, lim, sing

    def valid(
        self, q: np.ndarray, extra_clearance: float | np.ndarray = 0.0,
        limit_slack: float = 0.0, self_slack: float | np.ndarray = 0.0,
    ) -> np.ndarray:
        """Boolean ``(N,)``: every limit holds, no contact, singular margin kept.

        The same verdict as :meth:`measures` (clearance ``> self.clearance``,
        limit margin ``≥ 0``, singular margin ``≥ self.singular_margin``), with
        shapely's predicates instead of distances (faster).  ``extra_clearance``
        (obstacles), ``limit_slack`` (limits) and ``self_slack`` (distance between bodies
        that must not touch) demand more (the first and last may be ``(N,)`` arrays, one
        value per configuration: :meth:`valid_motion`).
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        extra = np.broadcast_to(np.asarray(extra_clearance, dtype=float), q.shape[:1])
        self_extra = np.broadcast_to(np.asarray(self_slack, dtype=float), q.shape[:1])
        ok = np.all(np.isfinite(q), axis=1)
        ok &= self.robot.limit_margin(q) >= limit_slack  # type: ignore[attr-defined]
        if self.margin_fn is not None:  # type: ignore[attr-defined]
            ok &= self.margin_fn(q) >= self.singular_margin  # type: ignore[attr-defined]
        robot: Robot = self.robot  # type: ignore[attr-defined]
        selfish = robot.has_self_collision
        if (self.world is not None or selfish) and ok.any():
            parts = robot.parts(q[ok])
            hit = np.zeros(parts[0].shape[0], dtype=bool)
            if selfish:
                hit |= robot.self_collides(q[ok], parts, self_extra[ok][:, None])
            if self.world is not None:
                geoms, radii = parts
                hit |= self.world.collides(geoms, radii,
                                           self.clearance + extra[ok][:, None]).any(axis=1)
            ok[np.flatnonzero(ok)[hit]] = False
        return ok

    def self_clearance(self, q: np.ndarray) -> np.ndarray:
        """Smallest distance between two parts that must not touch, ``(N,)`` (``≤ 0``:
        self-collision; ``+inf`` where the model names no such pair)."""
        return self.robot.self_clearance(q)  # type: ignore[attr-defined]

    def limit_values(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The limited quantities at ``q (N, n)`` and their bounds: ``(values (N, K), lo (K,),
        hi (K,))``, the box-limited coordinates then the relative-limit expressions (NaN
        where an expression is not defined)."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        names = self.system.coordinate_names
        assert self.limits is not None
        cols = [names.index(k) for k, _, _ in self.limits.bounds]
        values = np.concatenate([q[:, cols],
                                 self.robot.relative_values(q)], axis=1)  # type: ignore[attr-defined]
        lo = np.array([b[1] for b in self.limits.bounds]
                      + [r[2] for r in self.limits.relative], dtype=float)
        hi = np.array([b[2] for b in self.limits.bounds]
                      + [r[3] for r in self.limits.relative], dtype=float)
        return values, lo, hi

    def valid_motion(self, states: np.ndarray) -> bool:
        r"""Whether a motion sampled at ``states (N, n)`` (consecutive samples of one
        continuous motion, evenly spaced in time within each segment) is admissible
        between its samples too.

        Every sample must be admissible (:meth:`valid`).  Between two consecutive samples
        ``i, i + 1`` the motion is covered interval by interval, so that a motion that
        starts or ends exactly on a limit (margin 0) and stays inside is admitted, and one
        that leaves the limits or the free space between samples is not:

        * **What bounds the motion between samples.**  For a quantity ``g(t)`` of the
          motion (a limited coordinate, a relative-limit expression, a coordinate of an
          outline point), twice differentiable with ``|g''| ≤ M`` on ``[t_i, t_{i+1}]``
          (``h`` apart), the interpolation error gives, at ``t = t_i + s h``,
          ``|g(t) − ((1 − s) g_i + s g_{i+1})| ≤ s (1 − s) E`` with ``E = h² M / 2``.
          ``E`` is estimated from the samples as the larger second difference
          ``|g_{j+1} − 2 g_j + g_{j−1}| ≈ h² |g''(t_j)|`` at the interval's two ends
          (a factor 2 above ``h² |g''| / 2``: sound while ``|g''|`` varies by less than a
          factor 2 over two steps, i.e. while the samples resolve the motion; two samples
          alone: ``E`` is their step).
        * **Limits** (per bound, per interval): with the margins ``a = m_i, b = m_{i+1} ≥ 0``
          of the samples to that bound, the margin at ``s`` is at least
          ``(1 − s) a + s b − s (1 − s) E``, non-negative for every ``s ∈ [0, 1]`` iff
          ``√a + √b ≥ √E``: the test made.  A motion linear between samples (``E = 0``)
          needs only its samples inside; one starting on a bound needs the next sample
          ``E`` inside it.
        * **Obstacles and self-collision**: the distance from a part to an obstacle is
          1-Lipschitz in its points, and every point of a part (a fixed convex
          combination of its vertices, or a disc's centre) moves between the samples
          along a path no longer than ``ℓ_i``, the largest displacement of a vertex or
          centre plus its ``E`` (a path's excess over its chord is at most ``h² M / 3``).
          A point at path length ``α`` from sample ``i`` is then within ``α`` of it and
          ``ℓ_i − α`` of sample ``i + 1``, so the clearance there is at least
          ``(d_i + d_{i+1} − ℓ_i) / 2``: each sample is required to keep ``ℓ / 2`` more
          than :attr:`clearance` (``ℓ`` the larger of its two intervals'), and between
          two parts that must not touch (both may move) ``ℓ``.

        The whole plan is verified again by a dense re-simulation (:func:`verify_segments`).
        """
        q = np.atleast_2d(np.asarray(states, dtype=float))
        robot: Robot = self.robot  # type: ignore[attr-defined]
        if len(q) < 2 or (self.world is None and not robot.has_self_collision):
            if not np.all(self.valid(q)):
                return False
            if len(q) < 2:
                return True
        assert self.limits is not None
        if self.limits and not limits_between(*self.limit_values(q)):
            return False
        if self.world is None and not robot.has_self_collision:
            return True
        pts = robot.points(q)
        arrays = [*pts["polygons"], pts["segments"].reshape(len(q), -1, 2), pts["discs"]]
        steps = np.zeros(len(q) - 1)
        for a in arrays:
            if a.size:
                moved = np.linalg.norm(np.diff(a, axis=0), axis=-1)  # (N - 1, P)
                bent = np.linalg.norm(_bend(a.reshape(len(q), -1)).reshape(*moved.shape, 2),
                                      axis=-1)
                steps = np.maximum(steps, (moved + bent).max(axis=1))
        if not np.all(np.isfinite(steps)):
            return False
        cover = np.maximum(np.r_[steps, 0.0], np.r_[0.0, steps])  # each sample's two intervals
        return bool(np.all(self.valid(q, 0.5 * cover, 0.0, cover)))

    def why_invalid(self, q: Sequence[float] | State) -> str:
        """One sentence saying why the configuration ``q`` is not admissible ('' if it is)."""
        if not np.all(np.isfinite(np.asarray(q, dtype=float))):
            return "its coordinates are not all finite numbers (the motion diverged)"
        clear, lim, sing = (float(v[0]) for v in self.measures(np.asarray(q)[None, :]))
        reasons = []
        if not clear > self.clearance:  # NaN: not seen as free
            reasons.append(self._contact(np.asarray(q, dtype=float), clear))
        if lim < 0:
            names = self.system.coordinate_names
            assert self.limits is not None
            bad = [_outside(k, q[names.index(k)], lo, hi)
                   for k, lo, hi in self.limits.bounds
                   if not lo <= q[names.index(k)] <= hi]
            g = self.robot.relative_values(np.asarray(q, dtype=float)[None, :])[0]  # type: ignore[attr-defined]
            bad += [_outside(label, v, lo, hi)
                    for (label, _, lo, hi), v in zip(self.limits.relative, g, strict=True)
                    if not lo <= v <= hi]
            reasons.append("limits violated: " + ", ".join(bad))
        self_clear = float(self.self_clearance(np.asarray(q, dtype=float)[None, :])[0])
        if not self_clear > 0:
            reasons.append(f"it collides with itself ({self._self_pair(q)}; self-clearance "
                           f"{self_clear:.3g})")
        if self.margin_fn is not None and sing < self.singular_margin:  # type: ignore[attr-defined]
            reasons.append(f"singular margin {sing:.3g} below {self.singular_margin:g}")
        return "; ".join(reasons)

    def _contact(self, q: np.ndarray, clear: float) -> str:
        """What the configuration ``q`` touches (clearance ``clear`` at most the required):
        each obstacle the outline overlaps, by how deep (the farthest point of the overlap
        from the obstacle's boundary), or that it leaves the bounds, by how far; else the
        nearest obstacle or bound within the required clearance."""
        world = self.world
        assert world is not None
        geoms, radii = self.robot.parts(q[None, :])  # type: ignore[attr-defined]
        body = shapely.union_all([shapely.buffer(g, r, 16) if r > 0 else g
                                  for g, r in zip(geoms[0], radii[0], strict=True)])
        found = []
        shapes = [(shapely.Polygon(p), "the polygon obstacle with vertices " + ", ".join(
            f"({x:.3g}, {y:.3g})" for x, y in p[:3]) + (", …" if len(p) > 3 else ""))
            for p in world.polygons]
        shapes += [(shapely.Point(c).buffer(r, 64), f"the disc obstacle at ({c[0]:.3g}, "
                    f"{c[1]:.3g}) of radius {r:.3g}") for c, r in world.discs]
        for shape, name in shapes:
            overlap = body.intersection(shape)
            if not overlap.is_empty:
                # the overlap's vertices, the middles of its lines and the points of its
                # areas farthest from their own edges (polylabel)
                corners: Any = shapely.points(shapely.get_coordinates(overlap))
                pts: list[Any] = list(corners)
                for part in shapely.get_parts(overlap):
                    if part.geom_type == "Polygon":
                        pts.append(shapely.ops.polylabel(part, 1e-3))
                    elif part.geom_type == "LineString":
                        pts.append(part.interpolate(0.5, normalized=True))
                depth = float(shapely.distance(shape.boundary, pts).max())
                found.append(f"it overlaps {name} (by {depth:.3g})")
        if world.bounds is not None:
            (xlo, xhi), (ylo, yhi) = world.bounds
            xs, ys = shapely.get_coordinates(body).T
            out = max(xlo - xs.min(), xs.max() - xhi, ylo - ys.min(), ys.max() - yhi)
            if out > 0:
                found.append(f"it leaves the bounds x in [{xlo:g}, {xhi:g}], y in [{ylo:g}, "
                             f"{yhi:g}] (by {out:.3g})")
        if found:
            return "; ".join(found)
        near = min(shapes, key=lambda s: float(body.distance(s[0])), default=None)
        what = "an obstacle or the bounds" if near is None else near[1] + " or the bounds"
        return (f"it comes within {clear:.3g} of {what}, not more than the required "
                f"clearance {self.clearance:g}")

    def constraints_near(self, q: Sequence[float] | State, within: float = NEAR) -> str:
        """What constrains the configuration ``q`` within ``within`` (model units / radians),
        in words: the limits whose margin is at most ``within`` (``"phi = 0.3 is 0 from its
        bound 0.3"``), the clearance to the obstacles, the self-clearance, the singular
        margin; ``"nothing within …"`` when none is that near (then the steering itself,
        not a constraint, failed there).  For refusals that must not blame the wrong thing.
        """
        row = np.asarray(q, dtype=float)[None, :]
        clear, _, sing = (float(v[0]) for v in self.measures(row))
        out = []
        if self.limits:
            g, lo, hi = self.limit_values(row)
            labels = [k for k, _, _ in self.limits.bounds] + [k for k, *_ in self.limits.relative]
            for label, v, a, b in zip(labels, g[0], lo, hi, strict=True):
                bound = a if abs(v - a) <= abs(b - v) else b
                if not abs(v - bound) > within:  # NaN: named too
                    off = "on" if v == bound else f"{abs(v - bound):.2g} from"
                    out.append(f"{label} = {v:.4g} is {off} its bound {bound:.4g}")
        if self.world is not None and not clear - self.clearance > within:
            out.append(f"the clearance to the obstacles is {clear:.2g}")
        self_clear = float(self.self_clearance(row)[0])
        if not self_clear > within:
            out.append(f"two bodies are {self_clear:.2g} apart")
        if self.margin_fn is not None and not sing - self.singular_margin > within:  # type: ignore[attr-defined]
            out.append(f"the singular margin is {sing:.2g}")
        return "; ".join(out) or f"no limit, obstacle or body within {within:g} there"

    def _self_pair(self, q: Sequence[float] | State) -> str:
        """The first pair of bodies in contact at ``q``, in words."""
        robot: Robot = self.robot  # type: ignore[attr-defined]
        outline = robot.outline
        assert outline is not None
        geoms, radii = robot.parts(np.asarray(q, dtype=float)[None, :])
        for a, b in outline.self_collision:
            for i, j in outline.self_collision_parts():
                if outline.bodies[i] == a and outline.bodies[j] == b:
                    d = float(shapely.distance(geoms[0, i], geoms[0, j]))
                    if not d - radii[0, i] - radii[0, j] > 0:
                        return f"{a} touches {b}"
        return "two bodies touch"


@dataclass(frozen=True, eq=False)
class Verification:
    """What a dense re-simulation of controls shows.

    Attributes
    ----------
    times, states:
        The samples ``(N,)``, ``(N, n)``.
    clearance:
        Minimum distance robot–obstacles along the motion (model length
        units); ``None`` without a world.
    limit_margin:
        Minimum signed distance to the limits (``< 0``: violated); ``None``
        without limits.
    limits_ok:
        Every sample within the limits.
    min_singular_margin:
        Minimum singular margin; ``None`` where the model defines none.
    admissible:
        Every sample admissible for the checker.
    reached, error:
        Last state and its distance to the goal (from :func:`verify_segments`: plus the
        integration error estimated by a second, tighter re-simulation).
    self_clearance:
        Minimum distance between two bodies that must not touch (``≤ 0``: a
        self-collision); ``None`` where the model names no such pair.
    self_collision_ok:
        No sample collides with itself.
    """

    times: np.ndarray
    states: np.ndarray
    clearance: float | None
    limit_margin: float | None
    limits_ok: bool
    min_singular_margin: float | None
    admissible: bool
    reached: tuple[float, ...]
    error: float
    self_clearance: float | None = None
    self_collision_ok: bool = True


def verify_states(
    checker: Checker, times: np.ndarray, states: np.ndarray, goal: Sequence[float] | State
) -> Verification:
    """Measure sampled states ``(N, n)`` against ``checker`` (see :class:`Verification`)."""
    clear, lim, sing = checker.measures(states)
    ok = checker.valid(states)
    selfish = checker.robot.has_self_collision  # type: ignore[attr-defined]
    self_clear = checker.self_clearance(states) if selfish else None
    limits = checker.limits
    assert limits is not None
    return Verification(
        times=times,
        states=states,
        clearance=float(clear.min()) if checker.world is not None else None,
        limit_margin=float(lim.min()) if limits else None,
        limits_ok=bool(np.all(lim >= 0)),
        min_singular_margin=(float(sing.min()) if checker.margin_fn is not None  # type: ignore[attr-defined]
                             else None),
        admissible=bool(np.all(ok)),
        reached=tuple(float(v) for v in states[-1]),
        error=float(np.linalg.norm(states[-1] - np.asarray(goal, dtype=float))),
        self_clearance=float(self_clear.min()) if self_clear is not None else None,
        self_collision_ok=bool(self_clear is None or np.all(self_clear > 0)),
    )


def limits_between(g: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    """Whether limited quantities ``g (N, K)`` sampled along one continuous motion (evenly
    in time; :meth:`Checker.limit_values`) keep within ``[lo, hi] (K,)`` at the samples and
    between them: the limit test of :meth:`Checker.valid_motion`, ``√a + √b ≥ √E`` per
    interval (``a, b`` the two samples' margins to a bound, ``E`` the interpolation error's
    estimate), so that a motion starting or ending on a bound and staying inside passes."""
    g = np.atleast_2d(np.asarray(g, dtype=float))
    if not np.all(np.isfinite(g)):
        return False
    bend = np.sqrt(_bend(g)) if len(g) > 1 else np.zeros((0, g.shape[1]))
    for m in (g - lo, hi - g):
        if not np.all(m >= 0.0):
            return False
        root = np.sqrt(m)
        if not np.all(root[:-1] + root[1:] >= bend):
            return False
    return True


def _bend(values: np.ndarray) -> np.ndarray:
    """Per interval of ``values (N, K)`` (``N ≥ 2``), the larger absolute second difference at
    its two ends, ``(N − 1, K)`` (:meth:`Checker.valid_motion`: it estimates ``h² |g''|``);
    with two samples, the step itself."""
    if len(values) < 3:
        return np.abs(np.diff(values, axis=0))
    d2 = np.abs(values[2:] - 2.0 * values[1:-1] + values[:-2])  # at samples 1 .. N - 2
    at = np.concatenate([d2[:1], d2, d2[-1:]])  # the ends take their neighbour's
    return np.maximum(at[:-1], at[1:])


def _outside(label: str, v: float, lo: float, hi: float) -> str:
    """``"x = 0.2 outside [0, 0.2]"``, with by how much when 4 digits do not show it."""
    text = f"{label} = {v:.4g} outside [{lo:.4g}, {hi:.4g}]"
    if f"{v:.4g}" in (f"{lo:.4g}", f"{hi:.4g}"):
        text += f" (by {max(lo - v, v - hi):.2g})"
    return text


def verify_segments(
    checker: Checker,
    start: Sequence[float] | State,
    segments: Sequence[Segment],
    goal: Sequence[float] | State,
    points_per_segment: int = 200,
    settings: IntegrationSettings = PLANNING_SETTINGS,
) -> Verification:
    """Re-simulate ``segments`` from ``start`` on the true system (``settings``, by default
    :data:`~nilpotent.planning.simulation.PLANNING_SETTINGS`: DOP853, rtol 1e-12), sample
    ``points_per_segment`` per segment, and measure the motion (:func:`verify_states`).

    The ``error`` returned is not one integrator's number: it is the distance of the
    re-simulated end to ``goal`` plus an estimate of that run's integration error, the
    distance between its end and the end of a second re-simulation at ten times tighter
    ``rtol`` and ``atol`` (where that run cannot be made, e.g. its steps would fall below the
    integrator's least step, the distance to a run at ten times looser tolerances, an
    estimate of the looser run's error, which is larger).
    Ill-conditioned controls (a change of ``1e-9`` at the start moving the end ``10⁴``
    times as much, as optimal-control pieces fitted on one integrator can be) were reported
    within a ``tol`` of ``1e-8`` that an independent scipy replay missed by ``6e-8``; with
    the estimate added such a plan is refused instead."""
    times, states = simulate_path(checker.system, start, list(segments), points_per_segment,
                                  settings, hard=True)  # a plan found in time: verified in time
    v = verify_states(checker, times, states, goal)
    if not segments:
        return v
    tight = settings.replace(rtol=settings.rtol / 10, atol=settings.atol / 10)
    try:
        _, ends = simulate_path(checker.system, start, list(segments), 2, tight, hard=True)
    except IntegrationError:
        loose = settings.replace(rtol=settings.rtol * 10, atol=settings.atol * 10)
        _, ends = simulate_path(checker.system, start, list(segments), 2, loose, hard=True)
    spread = float(np.linalg.norm(ends[-1] - states[-1]))
    if not math.isfinite(spread):
        spread = math.inf
    return dataclasses.replace(v, error=v.error + spread)
