"""The filtration $\\Delta^1 \\subset \\Delta^2 \\subset \\cdots$ of a system at a point.

$\\Delta^1 = \\mathrm{span}\\{X_i\\}$, $\\Delta^{s+1} = \\Delta^s + [\\Delta^1, \\Delta^s]$;
$n_s(p) = \\dim \\Delta^s(p)$ is spanned by the values at $p$ of the bracket words
of length $\\le s$ (of the Hall basis, :func:`nilpotent.core.lie.brackets.hall_basis`).
:func:`analyze` gives the growth vector, the weights, the step, an adapted frame
made of Hall words, whether $p$ is regular and whether the system is
bracket-generating there.  Bracket convention $[X,Y] = DY\\cdot X - DX\\cdot Y$.

How it is computed
------------------
1. *Generic growth vector*, at a pseudo-random rational point $q$ near $p$
   (fixed seed), confirmed at a second one.  A random point is regular with
   probability one, so near $q$ the words chosen up to length $s$ span
   $\\Delta^s$ as a module and $\\Delta^{s+1}(q)$ is spanned by them and the
   brackets $[X_i, Y]$ with $Y$ a word chosen at length $s$.  Words are
   evaluated by :class:`~nilpotent.core.lie.word_values.WordValues`: from their
   fields as polynomials in the coordinates and elementary atoms
   (:mod:`nilpotent.core.lie.polynomial_fields`; exact rationals where the atoms
   are rational, certified arb balls elsewhere), or, for fields outside those
   atoms, from the symengine fields of their halves by forward-mode
   directional derivatives.
2. *At p* the Hall words of each length are scanned in order and kept when
   their value at $p$ is independent of those already kept (greedy, earliest
   first).  Since $n_s(p) \\le n_s(q)$, the scan of length $s$ stops as soon as
   the rank reaches the generic $n_s$; otherwise it runs through every Hall
   word of that length, so $n_s(p)$ is exact also at singular points, where
   the span can stall for some lengths and grow later (Martinet at 0:
   growth $(2, 2, 3)$).
3. Every decision is made by the one rank engine :mod:`nilpotent.core.decide.spans`:
   independence proved by ball arithmetic (scale-invariant: normalised Gram
   determinants), dependence proved by exact arithmetic; what cannot be
   proved is *undetermined* and reported (``Filtration.undetermined``), never
   turned into a verdict.  "Not bracket-generating" is said only when the
   span at random points stops growing below $n$.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import sympy as sp

from nilpotent import typeset
from nilpotent.core.analysis.growth import generic_growth_vector, normalise_point
from nilpotent.core.analysis.orbit import ORBIT_TIME_BUDGET, OrbitCertificate, certify_by_orbit
from nilpotent.core.decide.spans import START_PRECISION_BITS, Decision, Span
from nilpotent.core.lie.brackets import (
    Word,
    format_word,
    hall_basis,
    word_length,
    word_values_at,
)
from nilpotent.core.lie.hall_budget import (
    HALL_WORD_BUDGET,
    budget_length,
    check_hall_budget,
    default_max_length,
    default_max_length_for_budget,
)
from nilpotent.core.lie.word_values import Undefined, WordValues
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import (
    ComputationLimitError,
    PointError,
)
from nilpotent.progress import progress
from nilpotent.strict_json import json_object


@dataclass(frozen=True)
class Filtration:
    """The filtration of a system at a point.

    Attributes
    ----------
    system:
        The system analysed.
    point:
        The point $p$ (sympy numbers aligned with ``system.coordinates``).
    bracket_generating:
        Whether the brackets span $\\mathbb{R}^n$ at ``p``: True (proved), False
        (the span at random points near ``p`` stops below $n$) or None
        (undetermined: see ``undetermined``).
    growth_vector:
        $(n_1(p), \\dots, n_r(p))$; ends where the span stops growing ($n$ when
        bracket-generating).
    weights:
        $w_1 \\le \\dots$, $w_j = s$ for $n_{s-1} < j \\le n_s$ (one per frame word).
    step:
        $r(p)$, the length of ``growth_vector`` (when ``growth_vector_known_up_to``
        is set, only the length of the proved prefix: $r(p)$ is larger).
    frame:
        Adapted frame: Hall words $Y_1, \\dots$ with $|Y_j| = w_j$ whose values at
        ``p`` form a basis of $\\Delta^s(p)$ for every $s$.
    frame_values:
        ``frame_values[k][j]`` is the $x_{j+1}$-component of $Y_{k+1}(p)$.
    regular:
        Whether the growth vector at ``p`` equals the generic one near ``p``
        (None when a rank at ``p`` is undetermined).
    generic_growth_vector:
        The growth vector at random points near ``p``.
    exact:
        Whether every "dependent" decision at ``p`` was proved by exact arithmetic
        (independence is always proved, by ball arithmetic or exactly).
    max_length:
        The longest bracket length examined at ``p``.
    undetermined:
        None when every decision was proved; else what could not be decided and
        what was tried: ``max_length`` (bracket length searched),
        ``precision_bits`` (highest ball precision), ``undetermined_words``
        (per length, the words whose independence was not decided),
        ``reason`` (a sentence) and ``raise_with`` (the option that searches further).
    invariant_hypersurface:
        Where the brackets span $\\mathbb{R}^n$ nearby but not at ``p``: a
        polynomial $g$ with $g(p) = 0$, $\\nabla g(p) \\ne 0$ whose zero set is
        invariant under every field, proving ``bracket_generating`` false
        (:func:`nilpotent.core.analysis.singular.invariant_hypersurface`); else None.
    certified_by:
        When the bracket search at ``p`` ended short of $n$ but the brackets
        were proved to span $\\mathbb{R}^n$ at a point of the orbit of ``p``
        (hence at ``p``, by Nagano's orbit theorem for analytic fields): the
        :class:`~nilpotent.core.analysis.orbit.OrbitCertificate`; else None.
    growth_vector_known_up_to:
        None when ``growth_vector`` is complete; else the bracket length up to
        which it is proved (it is then a prefix: the lengths at which the span
        reaches $n$ are unknown, see ``undetermined``).
    """

    system: ControlSystem
    point: tuple[sp.Expr, ...]
    bracket_generating: bool | None
    growth_vector: tuple[int, ...]
    weights: tuple[int, ...]
    step: int
    frame: tuple[Word, ...]
    frame_values: tuple[tuple[sp.Expr, ...], ...]
    regular: bool | None
    generic_growth_vector: tuple[int, ...]
    exact: bool
    max_length: int = 0
    undetermined: Mapping[str, object] | None = None
    invariant_hypersurface: sp.Expr | None = None
    certified_by: OrbitCertificate | None = None
    growth_vector_known_up_to: int | None = None

    @property
    def frame_names(self) -> tuple[str, ...]:
        """The frame words as users write them (``"[X1,X2]"``)."""
        return tuple(format_word(w) for w in self.frame)

    # --- display (nilpotent.typeset) -------------------------------------------------
    def to_latex(self) -> str:
        """Growth vector, weights and the adapted frame (a table) as LaTeX (``align*``)."""
        return typeset.filtration_display(self).latex()

    def _repr_latex_(self) -> str:
        return self.to_latex()

    def _repr_html_(self) -> str:
        return typeset.filtration_display(self).html()

    def to_json(self) -> dict[str, object]:
        """The ``nilpotent/analysis@1`` JSON object (the interface page).

        ``bracket_generating`` and ``regular`` are ``null`` when undetermined;
        ``undetermined`` is then an object saying what was tried (else ``null``).
        """
        from nilpotent.core.model.expressions import format_expression
        from nilpotent.core.model.points import format_point

        sys = self.system
        return json_object({
            "schema": "nilpotent/analysis@1",
            "model": sys.name,
            "coordinates": list(sys.coordinate_names),
            "parameters": {k: format_expression(v) for k, v in sys.parameters},
            "point": format_point(sys, self.point),
            "bracket_generating": self.bracket_generating,
            "growth_vector": list(self.growth_vector),
            "weights": list(self.weights),
            "step": self.step,
            "regular": self.regular,
            "generic_growth_vector": list(self.generic_growth_vector),
            "exact": self.exact,
            "max_length": self.max_length,
            "frame": list(self.frame_names),
            "frame_values": [[format_expression(v) for v in col] for col in self.frame_values],
            "undetermined": dict(self.undetermined) if self.undetermined is not None else None,
            "invariant_hypersurface": (
                format_expression(self.invariant_hypersurface)
                if self.invariant_hypersurface is not None
                else None
            ),
            "certified_by": (
                self.certified_by.to_json(sys.coordinate_names)
                if self.certified_by is not None
                else None
            ),
            "growth_vector_known_up_to": self.growth_vector_known_up_to,
        })


ANALYSIS_TIME_BUDGET = 60.0
"""Seconds the bracket search at a point may take before its result is undetermined."""


# --- analysis at p ------------------------------------------------------------


def analyze(
    sys: ControlSystem,
    point: Sequence[object] | None = None,
    *,
    max_length: int | None = None,
    time_budget: float = ANALYSIS_TIME_BUDGET,
) -> Filtration:
    """Growth vector, weights, adapted frame and regularity of ``sys`` at ``point``.

    Parameters
    ----------
    sys:
        The system (parameters are substituted).
    point:
        The point $p$, a sequence of sympy numbers aligned with the coordinates
        (default: the origin).  Decimals are read as the rationals they denote.
    max_length:
        Longest bracket length examined at ``p``.  By default (``None``) the
        search starts with :func:`default_max_length` and, when it is exhausted
        before the brackets span (only possible at a singular point), is
        raised automatically while the Hall words stay within
        :data:`HALL_WORD_BUDGET` and the time within ``time_budget``.  Given
        explicitly, it is not raised.
    time_budget:
        Seconds after which the search at ``p`` stops (the result is then
        *undetermined* beyond the length reached).

    Returns
    -------
    Filtration
        See its attributes.  ``bracket_generating`` is True (proved), False
        (the generic span stops below $n$: not bracket-generating) or None
        (*undetermined*: the search up to ``max_length`` was exhausted at a
        singular point, or a rank decision could not be certified; what was
        tried is in ``Filtration.undetermined``).

    Raises
    ------
    PointError
        If the point has the wrong length or the fields are undefined there.

    Examples
    --------
    >>> x1, x2, x3 = sp.symbols("x1 x2 x3")
    >>> martinet = ControlSystem("martinet", (x1, x2, x3), ((1, 0, x2**2 / 2), (0, 1, 0)))
    >>> f = analyze(martinet)
    >>> f.growth_vector, f.weights, f.regular
    ((2, 2, 3), (1, 1, 3), False)
    >>> f.frame_names
    ('X1', 'X2', '[X2,[X1,X2]]')
    """
    started = time.monotonic()
    p = normalise_point(sys, point)
    n, m = sys.n, sys.m
    generic = generic_growth_vector(sys, p)
    final = generic[-1]
    automatic = max_length is None
    if max_length is not None:
        check_hall_budget(m, max_length)
    limit = default_max_length(n, m) if automatic else int(max_length)  # type: ignore[arg-type]
    limit = max(limit, len(generic))
    ceiling = max(limit, budget_length(m)) if automatic else limit
    at = WordValues(sys, p, symbolic=True)
    span = Span()
    frame: list[Word] = []
    growth: list[int] = []
    unsure: dict[int, list[Word]] = {}
    stopped_by = ""
    s = 0
    with progress(f"brackets at the point of {sys.name}", total=None) as bar:
        while True:
            s += 1
            target = generic[s - 1] if s <= len(generic) else final
            if span.rank < target:
                unsure_here: list[Word] = []
                for w in hall_basis(m, s):
                    if word_length(w) != s:
                        continue
                    try:
                        decision = span.add(at.vector(w))
                    except ComputationLimitError as exc:
                        if s <= len(generic):
                            raise
                        stopped_by = f"a size budget ({exc})"
                        break
                    except Undefined as exc:
                        raise PointError(
                            f"the fields of {sys.name!r} are not defined at the point "
                            f"({', '.join(str(v) for v in p)}): {exc}"
                        ) from None
                    bar.advance(detail=f"length {s}")
                    if decision is Decision.INDEPENDENT:
                        frame.append(w)
                        if span.rank == target:
                            break
                    elif decision is Decision.UNDETERMINED:
                        unsure_here.append(w)
                    if time.monotonic() - started > time_budget:
                        stopped_by = f"the time budget of {time_budget:g} s"
                        break
                if span.rank < target and unsure_here:
                    unsure[s] = unsure_here
            growth.append(span.rank)
            if span.rank == final or stopped_by:
                break
            if s >= limit:
                if s >= ceiling or time.monotonic() - started > time_budget:
                    break
                limit += 1
    limit = s
    scanned = list(growth)  # n_s(p) for s <= limit (the last a lower bound if stopped_by)
    while len(growth) > 1 and growth[-1] == growth[-2] and not unsure:
        growth.pop()
    growth_t = tuple(growth)
    weights = _weights(growth_t)
    bracket_generating: bool | None
    undetermined: dict | None = None
    if span.rank == n:
        bracket_generating = True
    elif final < n:
        bracket_generating = False
    else:
        bracket_generating = None
    certain = not unsure and span.rank == final
    invariant = None
    certificate = None
    if bracket_generating is None and final == n:
        # the orbit first: cheap, and where it succeeds no hypersurface can be invariant
        left = max(time_budget - (time.monotonic() - started), 0.0)
        certificate = certify_by_orbit(sys, p, time_budget=min(max(left, 5.0), ORBIT_TIME_BUDGET))
    if bracket_generating is None and not unsure and certificate is None:
        from nilpotent.core.analysis.singular import invariant_hypersurface

        invariant = invariant_hypersurface(sys, p, generic)
        if invariant is not None:
            bracket_generating = False
    if (bracket_generating is None or not certain) and invariant is None:
        reasons = []
        if unsure:
            reasons.append(
                "some rank decisions at the point could not be certified: "
                + "; ".join(
                    f"length {k}: {', '.join(format_word(w) for w in ws)}"
                    for k, ws in sorted(unsure.items())
                )
            )
        if span.rank < final:
            why = stopped_by or (
                "the Hall-word budget (HALL_WORD_BUDGET)" if automatic else "max_length"
            )
            reasons.append(
                f"brackets up to length {limit} span {span.rank} of {final} dimensions at the "
                f"point (as many as nearby: {final}); the search stopped at {why}"
            )
        undetermined = {
            "max_length": limit,
            "precision_bits": span.precision_reached or START_PRECISION_BITS,
            "undetermined_words": {
                str(k): [format_word(w) for w in ws] for k, ws in sorted(unsure.items())
            },
            "reason": "; ".join(reasons),
            "raise_with": "max_length (CLI --max-length)",
        }
    regular: bool | None = growth_t == generic if certain else None
    if invariant is not None:
        regular = False  # the brackets span R^n nearby, never at p
    # the lengths s whose n_s(p) is proved (the last scanned one only if its scan ended)
    proved = min(min(unsure, default=limit + 1) - 1, limit - 1 if stopped_by else limit)
    if regular is None and any(
        scanned[k] < generic[min(k, len(generic) - 1)] for k in range(min(proved, len(scanned)))
    ):
        regular = False  # a proved n_s(p) below the generic n_s
    known_up_to = None
    if certificate is not None:
        bracket_generating = True
        known_up_to = proved
        growth_t = tuple(scanned[:known_up_to])
        weights = _weights(growth_t)
        frame = [w for w in frame if word_length(w) <= known_up_to]
        undetermined = dict(undetermined or {})
        undetermined["reason"] = (
            f"the growth vector at the point is known up to bracket length {known_up_to} only "
            f"({growth_t[-1] if growth_t else 0} of {n} dimensions); bracket generation was "
            f"proved through the orbit instead ({undetermined.get('reason', '')})"
        )
    frame_values = _frame_values(sys, at, frame, p)
    return Filtration(
        system=sys,
        point=p,
        bracket_generating=bracket_generating,
        growth_vector=growth_t,
        weights=weights,
        step=len(growth_t),
        frame=tuple(frame),
        frame_values=tuple(frame_values),
        regular=regular,
        generic_growth_vector=generic,
        exact=span.exact,
        max_length=limit,
        undetermined=undetermined,
        invariant_hypersurface=invariant,
        certified_by=certificate,
        growth_vector_known_up_to=known_up_to,
    )


def _frame_values(
    sys: ControlSystem, at: WordValues, frame: Sequence[Word], p: tuple[sp.Expr, ...]
) -> tuple[tuple[sp.Expr, ...], ...]:
    """Exact values of the frame words at ``p``: the rationals already computed, else symengine."""
    exact = [at.exact_sympy(w) for w in frame]
    if all(v is not None for v in exact):
        return tuple(exact)  # type: ignore[arg-type]
    return word_values_at(sys, frame, p)


def _weights(growth: tuple[int, ...]) -> tuple[int, ...]:
    """$w_j = s$ for $n_{s-1} < j \\le n_s$."""
    return tuple(
        k
        for k, (before, after) in enumerate(zip((0, *growth), growth, strict=False), start=1)
        for _ in range(after - before)
    )


def singular_locus(sys: ControlSystem, filtration: Filtration | None = None) -> sp.Expr:
    """One expression whose zero set is the singular locus near ``filtration``'s point.

    The locus is computed from the generic frames
    (:func:`nilpotent.core.analysis.singular.singular_set`: the common zeros of the
    determinants of every adapted frame of Hall words with the generic
    weights); this returns its single equation (``1`` when the system is
    regular everywhere).  ``filtration`` (default ``analyze(sys)``) only
    supplies the generic growth vector.

    Parameters
    ----------
    sys : ControlSystem
        The system (parameters are substituted).
    filtration : Filtration or None
        Whose frame words to use (default: ``analyze(sys)`` at the origin).

    Raises
    ------
    ComputationLimitError
        If a frame field is too large to expand.
    NotBracketGeneratingError
        If the system is not bracket-generating at random points.

    Examples
    --------
    >>> x1, x2, x3 = sp.symbols("x1 x2 x3")
    >>> martinet = ControlSystem("martinet", (x1, x2, x3), ((1, 0, x2**2 / 2), (0, 1, 0)))
    >>> singular_locus(martinet, analyze(martinet, (0, 1, 0)))
    x2
    """
    from nilpotent.core.analysis.singular import singular_set

    f = filtration if filtration is not None else analyze(sys)
    return singular_set(sys, f.generic_growth_vector).equation


__all__ = [
    "ANALYSIS_TIME_BUDGET",
    "HALL_WORD_BUDGET",
    "Filtration",
    "analyze",
    "check_hall_budget",
    "default_max_length",
    "default_max_length_for_budget",
    "generic_growth_vector",
    "singular_locus",
]
