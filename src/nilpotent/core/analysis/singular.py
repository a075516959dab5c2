r"""The singular locus of a system: where the growth vector differs from the generic one.

A point $p$ is *regular* when its growth vector equals the generic one
$(N_1, \dots, N_r)$ (weights $w_1 \le \dots \le w_n$).  If some *adapted frame*
$F = (Y_1, \dots, Y_n)$ of Hall words with $|Y_j| = w_j$ has
$\det F(p) \ne 0$, then $n_s(p) \ge N_s$ for every $s$, and since
$n_s(p) \le N_s$ near a generic point, $p$ is regular; conversely at a regular
point some such frame of Hall words spans.  Hence

.. math:: \text{regular set} = \bigcup_F \{\det F \ne 0\},\qquad
          \text{singular locus} = \bigcap_F \{\det F = 0\},

over the adapted frames $F$ of Hall words with the generic weights.
:func:`singular_set` computes these determinants, simplifies them (rational
functions are cancelled and factored; trigonometric polynomials in the
coordinates are brought to a normal form modulo $\sin^2 + \cos^2 = 1$, so that
e.g. the trident body form's 15,000-character determinant becomes a constant),
and states the locus as the common zeros of their numerators.

This needs a system that is bracket-generating at random points (else there
is no square frame).  Bracket convention $[X,Y] = DY\cdot X - DX\cdot Y$.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import symengine as se
import sympy as sp

from nilpotent.core.lie.brackets import (
    Word,
    format_word,
    hall_basis,
    to_sympy,
    word_field_symengine,
    word_length,
)
from nilpotent.core.model.expressions import as_expr
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ComputationLimitError, NotBracketGeneratingError

__all__ = [
    "MAX_FRAMES",
    "SINGULAR_LOCUS_MAX_CHARS",
    "SingularLocus",
    "invariant_hypersurface",
    "singular_set",
]

SINGULAR_LOCUS_MAX_CHARS = 20_000
"""Largest frame column (characters of its components) whose determinant is expanded."""

SINGULAR_DETERMINANT_MAX_CHARS = 200_000
"""Budget on the expanded frame determinant before its trigonometric normal form
(sympy's ``together``/``cancel`` on larger ones runs for minutes: ``car-trailers:4``'s
is 5.2 million characters)."""

MAX_FRAMES = 24
"""Most adapted frames whose determinants are computed (beyond: the locus is a superset)."""


@dataclass(frozen=True)
class SingularLocus:
    """The singular locus as the common zeros of a set of equations.

    Attributes
    ----------
    determinants:
        ``(frame, determinant)`` for each adapted frame examined (simplified).
    equations:
        The distinct non-constant equations ``e = 0`` (numerators of the
        determinants, constant factors dropped); the locus is where all of
        them vanish.  Empty when some determinant is a nonzero constant: the
        system is regular everywhere (where its fields are defined).
    complete:
        Whether every adapted frame was examined (else the equations describe
        a set that *contains* the singular locus).
    """

    determinants: tuple[tuple[tuple[Word, ...], sp.Expr], ...]
    equations: tuple[sp.Expr, ...]
    complete: bool

    @property
    def empty(self) -> bool:
        """Whether the system is regular everywhere (a determinant is a nonzero constant)."""
        return not self.equations and any(d.is_number for _, d in self.determinants)

    @property
    def equation(self) -> sp.Expr:
        """One expression whose zero set is the locus (``1`` when it is empty).

        The single equation when there is one, else the sum of their squares
        (real coordinates).
        """
        if not self.equations:
            return sp.Integer(1) if self.empty else self.determinants[0][1]
        if len(self.equations) == 1:
            return self.equations[0]
        return sp.Add(*[e**2 for e in self.equations])

    def statement(self) -> str:
        """A sentence saying what the locus is."""
        frames = len(self.determinants)
        how = (
            f"the common zeros of the determinants of the {frames} adapted frame(s) of Hall "
            "words with the generic weights"
        )
        if not self.complete:
            how += " examined (a set that contains the singular locus: more frames exist)"
        if self.empty:
            const = next(d for _, d in self.determinants if d.is_number)
            return f"empty: regular everywhere (a frame determinant is the constant {const})"
        if not self.equations:
            nonzero = [d for _, d in self.determinants if d != 0]
            if nonzero:
                return (
                    "empty where the fields are defined: the frame determinant "
                    f"{nonzero[0]} has a constant numerator"
                )
            return f"everywhere: every determinant is 0 ({how})"
        eqs = " and ".join(f"{e} = 0" for e in self.equations)
        return f"{eqs} ({how})"


def _frames(generic: Sequence[int], m: int) -> tuple[list[tuple[Word, ...]], bool]:
    """Adapted frames of Hall words with the generic weights (at most :data:`MAX_FRAMES`)."""
    words = hall_basis(m, len(generic))
    choices = []
    prev = 0
    for s, ns in enumerate(generic, start=1):
        of_length = [w for w in words if word_length(w) == s]
        choices.append(list(itertools.combinations(of_length, ns - prev)))
        prev = ns
    total = 1
    for c in choices:
        total *= len(c)
    frames = []
    for combo in itertools.product(*choices):
        frames.append(tuple(w for part in combo for w in part))
        if len(frames) >= MAX_FRAMES:
            break
    return frames, total <= MAX_FRAMES


def trig_normal_form(expr: sp.Expr, coords: Sequence[sp.Symbol]) -> sp.Expr:
    r"""``expr`` simplified: trigonometric polynomials in the coordinates reduced, then factored.

    $\sin$ and $\cos$ of sums and multiples are expanded, $\sin x_k, \cos x_k$
    become variables $s_k, c_k$, and every $s_k^2$ is replaced by $1 - c_k^2$
    (a normal form of polynomials modulo $s_k^2 + c_k^2 - 1$); the result is
    converted back, cancelled and factored.  Expressions with other functions
    of the coordinates are only cancelled and factored.
    """
    e = expr.replace(sp.tan, lambda a: sp.sin(a) / sp.cos(a))
    e = e.replace(sp.cot, lambda a: sp.cos(a) / sp.sin(a))
    e = sp.expand_trig(e)
    sym: dict[sp.Expr, sp.Symbol] = {}
    pairs = []
    for x in coords:
        c, s = sp.Dummy(f"c_{x}"), sp.Dummy(f"s_{x}")
        sym[sp.cos(x)] = c
        sym[sp.sin(x)] = s
        pairs.append((c, s))
    e2 = e.xreplace(sym)
    if any(f.has(*coords) for f in e2.atoms(sp.Function)) or not sym:
        return as_expr(sp.factor(sp.cancel(expr)))
    num, den = sp.fraction(sp.cancel(sp.together(e2)))

    def reduce(p: sp.Expr) -> sp.Expr:
        p = sp.expand(p)
        for c, s in pairs:
            if p.has(s):
                poly = sp.Poly(p, s)
                p = sp.expand(
                    sum(
                        coef * s ** (k % 2) * (1 - c**2) ** (k // 2)
                        for (k,), coef in poly.terms()
                    )
                )
        return p

    back = {v: k for k, v in sym.items()}
    ratio = as_expr(reduce(num).xreplace(back)) / as_expr(reduce(den).xreplace(back))
    out = as_expr(sp.factor(sp.cancel(ratio)))
    return _compact(out)


def _compact(e: sp.Expr) -> sp.Expr:
    """``trigsimp`` of each factor of a small expression, where it is shorter."""
    if len(str(e)) > 2_000:
        return e
    factors = sp.Mul.make_args(e)
    out = []
    for f in factors:
        g = sp.trigsimp(f)
        out.append(g if len(str(g)) < len(str(f)) else f)
    return sp.Mul(*out)


def _equation(det: sp.Expr) -> sp.Expr | None:
    """The numerator of ``det`` without constant factors (None if ``det`` is a constant)."""
    if det.is_number:
        return None
    num = as_expr(sp.factor(sp.fraction(sp.factor(det))[0]))
    parts = [
        b
        for f in sp.Mul.make_args(num)
        for b in [f.base if isinstance(f, sp.Pow) and f.exp.is_positive else f]
        if not b.is_number
    ]
    if not parts:
        return None
    eq = sp.Mul(*parts)
    if eq.could_extract_minus_sign():
        eq = -eq
    return eq


def singular_set(sys: ControlSystem, generic: Sequence[int] | None = None) -> SingularLocus:
    """The singular locus of ``sys`` (module docstring), as a set of equations.

    Parameters
    ----------
    sys:
        The system (parameters substituted).
    generic:
        Its generic growth vector (default: computed near the origin).

    Raises
    ------
    NotBracketGeneratingError
        If the system is not bracket-generating at random points (no square frame).
    ComputationLimitError
        If a frame field is longer than :data:`SINGULAR_LOCUS_MAX_CHARS`
        characters, or its expanded determinant longer than
        :data:`SINGULAR_DETERMINANT_MAX_CHARS` (the simplification would be unmanageable).

    Examples
    --------
    >>> x, y = sp.symbols("x y")
    >>> grushin = ControlSystem("grushin", (x, y), ((1, 0), (0, x)))
    >>> singular_set(grushin).equations
    (x,)
    """
    if generic is None:
        from nilpotent.core.analysis.growth import generic_growth_vector

        generic = generic_growth_vector(sys)
    if not generic or generic[-1] != sys.n:
        raise NotBracketGeneratingError(
            f"{sys.name!r} is not bracket-generating near the point (generic growth vector "
            f"{tuple(generic)}): no square frame, no determinant"
        )
    frames, complete = _frames(generic, sys.m)
    coords = sys.coordinates
    dets = []
    equations: list[sp.Expr] = []
    for frame in frames:
        cols = [word_field_symengine(sys, w) for w in frame]
        sizes = [sum(len(str(e)) for e in col) for col in cols]
        if max(sizes) > SINGULAR_LOCUS_MAX_CHARS:
            worst = max(range(len(sizes)), key=sizes.__getitem__)
            raise ComputationLimitError(
                f"the singular locus of {sys.name!r} is not expanded: the frame field "
                f"{format_word(frame[worst])} alone has {sizes[worst]:,} characters (limit "
                f"SINGULAR_LOCUS_MAX_CHARS = {SINGULAR_LOCUS_MAX_CHARS:,}), so the "
                f"{sys.n}x{sys.n} determinant would be far larger; analyze points instead "
                "(the regular/singular verdict at a point needs no determinant)"
            )
        n = sys.n
        mat = se.DenseMatrix(n, n, [cols[k][j] for j in range(n) for k in range(n)])
        expanded = se.expand(mat.det())
        size = len(str(expanded))
        if size > SINGULAR_DETERMINANT_MAX_CHARS:
            raise ComputationLimitError(
                f"the singular locus of {sys.name!r} is not simplified: the determinant of the "
                f"frame {', '.join(format_word(w) for w in frame)} expands to {size:,} "
                f"characters (limit SINGULAR_DETERMINANT_MAX_CHARS = "
                f"{SINGULAR_DETERMINANT_MAX_CHARS:,} in nilpotent.core.analysis.singular); analyze "
                "points instead (the regular/singular verdict at a point needs no determinant)"
            )
        det = trig_normal_form(to_sympy(sys, expanded), coords)
        dets.append((frame, det))
        if det.is_number and det != 0:
            return SingularLocus(tuple(dets), (), True)
        eq = _equation(det)
        if eq is not None and all(sp.simplify(eq - e) != 0 for e in equations):
            equations.append(eq)
    return SingularLocus(tuple(dets), tuple(equations), complete)


def invariant_hypersurface(
    sys: ControlSystem, point: Sequence[sp.Expr], generic: Sequence[int]
) -> sp.Expr | None:
    r"""An equation $g$ proving that ``sys`` is not bracket-generating at ``point``, or None.

    $g$ is one of the equations of the singular locus with $g(p) = 0$ and
    $\nabla g(p) \ne 0$ whose zero set near $p$ is invariant under every field:
    then every bracket is tangent to it and the brackets never span
    $\mathbb{R}^n$ at $p$.  Invariance is proved exactly: for polynomial $g$ and
    rational fields, $g$ divides the numerator of every $X_i g$; otherwise $g = 0$
    is solved for a coordinate $x_k$ with $\partial_k g(p) \ne 0$ (the branch
    through $p$) and every $X_i g$ must simplify to 0 on it.  None when no such
    $g$ is found (nothing is then concluded).
    """
    coords = sys.coordinates
    fields = sys.specialized_fields
    rational = all(as_expr(e).is_rational_function(*coords) for f in fields for e in f)
    try:
        locus = singular_set(sys, generic)
    except (ComputationLimitError, NotBracketGeneratingError):
        return None
    at = dict(zip(coords, point, strict=True))
    at_pairs = list(at.items())
    for g in locus.equations:
        if len(str(g)) > 2_000 or sp.simplify(g.subs(at_pairs)) != 0:
            continue
        grad = [sp.diff(g, x) for x in coords]
        moving = [k for k, d in enumerate(grad) if sp.simplify(d.subs(at_pairs)) != 0]
        if not moving:
            continue
        derivs = [sp.Add(*[c * d for c, d in zip(f, grad, strict=True)]) for f in fields]
        if rational and g.is_polynomial(*coords):
            ok = all(
                sp.div(sp.expand(sp.fraction(sp.cancel(d))[0]), g, *coords)[1] == 0
                for d in derivs
            )
        else:
            ok = _vanishes_on_branch(g, derivs, coords[moving[0]], at, coords)
        if ok:
            return g
    return None


def _vanishes_on_branch(
    g: sp.Expr, derivs: Sequence[sp.Expr], x: sp.Symbol, at: dict, coords: Sequence[sp.Symbol]
) -> bool:
    """Whether every ``derivs`` vanishes on the branch of ``g = 0`` through ``at`` (as x = s)."""
    try:
        solutions = sp.solve(g, x)
    except (NotImplementedError, ValueError):
        return False
    for sol in solutions:
        if sp.simplify(sol.subs(list(at.items())) - at[x]) != 0:
            continue
        for d in derivs:
            value = d.subs(x, sol)
            if sp.simplify(value) != 0 and trig_normal_form(as_expr(value), coords) != 0:
                return False
        return True
    return False
