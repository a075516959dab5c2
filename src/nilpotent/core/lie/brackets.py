"""Bracket words, Hall basis, Lie derivative and Lie bracket of vector fields.

Convention (everywhere in `nilpotent`): $[X, Y] = DY\\cdot X - DX\\cdot Y$, so that
$[X,Y]f = X(Yf) - Y(Xf)$.

A *bracket word* is a generator index (``1`` for ``X1``, 1-based as users write
it) or a pair ``(u, v)`` of words standing for $[u, v]$; ``(1, (1, 2))`` is
``[X1,[X1,X2]]``.  Its *length* is the number of generators in it.

The symbolic field of a word (:func:`word_field`) is computed with symengine,
expanding every component after each bracket (unexpanded towers grow
exponentially), and cached per system; values at a point
(:func:`word_values_at`) are exact sympy numbers.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from functools import lru_cache
from typing import TypeAlias

import symengine as se
import sympy as sp

from nilpotent.core.model.memo import IdentityMemo
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ComputationLimitError, OptionError, PointError

Word: TypeAlias = "int | tuple[Word, Word]"
"""A bracket word: a 1-based generator index or a pair ``(u, v)`` meaning $[u, v]$."""

SeField: TypeAlias = tuple[se.Basic, ...]
"""A vector field as a tuple of symengine expressions (one per coordinate)."""

_CACHE_KEY = "brackets.word_field_symengine"
_SYMPY_CACHE_KEY = "brackets.word_field"


# --- words ------------------------------------------------------------------


def word_length(w: Word) -> int:
    """Number of generators in the word ``w`` (``word_length((1, (1, 2))) == 3``)."""
    if isinstance(w, int):
        return 1
    return word_length(w[0]) + word_length(w[1])


def format_word(w: Word) -> str:
    """The word as users write it.

    Parameters
    ----------
    w : Word
        A generator ``i`` (1-based) or a pair of words.

    Examples
    --------
    >>> format_word((1, (1, 2)))
    '[X1,[X1,X2]]'
    >>> format_word(2)
    'X2'
    """
    if isinstance(w, int):
        return f"X{w}"
    return f"[{format_word(w[0])},{format_word(w[1])}]"


_TOKEN = re.compile(r"\s*(?:(\[)|(\])|(,)|[Xx](\d+))")


def parse_word(text: str, m: int | None = None) -> Word:
    """Parse a word written as ``"X2"`` or ``"[X1,[X1,X2]]"`` (spaces allowed).

    Parameters
    ----------
    text:
        The word, e.g. ``"[X1, X2]"``.
    m:
        If given, the number of fields: indices outside ``1..m`` are refused.

    Raises
    ------
    OptionError
        If the text is not a well-formed word (or names a field beyond ``m``).

    Examples
    --------
    >>> parse_word("[X1,[X1,X2]]")
    (1, (1, 2))
    """
    tokens: list[tuple[str, int | None]] = []
    pos = 0
    src = text.strip()
    while pos < len(src):
        mt = _TOKEN.match(src, pos)
        if mt is None or mt.end() == pos:
            raise OptionError(f"bad bracket word {text!r}: unexpected text at {src[pos:]!r}")
        if mt.group(1):
            tokens.append(("[", None))
        elif mt.group(2):
            tokens.append(("]", None))
        elif mt.group(3):
            tokens.append((",", None))
        else:
            tokens.append(("X", int(mt.group(4))))
        pos = mt.end()
        while pos < len(src) and src[pos].isspace():
            pos += 1

    def parse(i: int) -> tuple[Word, int]:
        if i >= len(tokens):
            raise OptionError(f"bad bracket word {text!r}: it ends too early")
        kind, val = tokens[i]
        if kind == "X":
            assert val is not None
            if val < 1 or (m is not None and val > m):
                limit = f"X1..X{m}" if m is not None else "X1, X2, ..."
                raise OptionError(f"bad bracket word {text!r}: X{val} is not a field ({limit})")
            return val, i + 1
        if kind != "[":
            raise OptionError(f"bad bracket word {text!r}: expected X<i> or '['")
        left, i = parse(i + 1)
        if i >= len(tokens) or tokens[i][0] != ",":
            raise OptionError(f"bad bracket word {text!r}: expected ',' inside [ ]")
        right, i = parse(i + 1)
        if i >= len(tokens) or tokens[i][0] != "]":
            raise OptionError(f"bad bracket word {text!r}: expected ']'")
        return (left, right), i + 1

    if not tokens:
        raise OptionError("bad bracket word: empty text")
    word, end = parse(0)
    if end != len(tokens):
        raise OptionError(f"bad bracket word {text!r}: unexpected text after the word")
    return word


@lru_cache(maxsize=64)
def hall_basis(m: int, max_length: int) -> tuple[Word, ...]:
    """The Hall basis (Marshall Hall, 1950) of the free Lie algebra on ``X1..Xm``, up to a length.

    The Hall set $H$ and its total order are built together, length by length:

    * the generators ``1 < 2 < ... < m`` come first;
    * a word of length $\\ge 2$ is $[u, v]$ with $u, v \\in H$, $u < v$, and, when
      $v = [v', v'']$, also $v' \\le u$;
    * words are ordered by length, and words of the same length by the order in
      which they are generated: $u$ running through $H$ in order, then $v$.

    The words are returned in this order, so every word comes after its
    sub-words.  There are exactly $\\frac1k\\sum_{d\\mid k}\\mu(d)\\,m^{k/d}$ words of
    length $k$ (Witt's formula).  Example for ``m = 2`` up to length 3:
    ``X1, X2, [X1,X2], [X1,[X1,X2]], [X2,[X1,X2]]``.

    Parameters
    ----------
    m : int
        Number of generators (fields).
    max_length : int
        Longest word returned.

    Examples
    --------
    >>> [format_word(w) for w in hall_basis(2, 4)][3:]
    ['[X1,[X1,X2]]', '[X2,[X1,X2]]', '[X1,[X1,[X1,X2]]]', '[X2,[X1,[X1,X2]]]', '[X2,[X2,[X1,X2]]]']
    """
    if m < 1 or max_length < 1:
        return ()
    rank: dict[Word, int] = {}
    by_length: list[list[Word]] = [[], list(range(1, m + 1))]
    ordered: list[Word] = list(range(1, m + 1))
    for i, g in enumerate(ordered):
        rank[g] = i
    for length in range(2, max_length + 1):
        new: list[Word] = []
        for lu in range(1, length):
            lv = length - lu
            if lu > lv:
                break
            for u in by_length[lu]:
                for v in by_length[lv]:
                    if rank[u] >= rank[v]:
                        continue
                    if not isinstance(v, int) and rank[v[0]] > rank[u]:
                        continue
                    new.append((u, v))
        for w in new:
            rank[w] = len(ordered)
            ordered.append(w)
        by_length.append(new)
    return tuple(ordered)


# --- sympy: Lie derivative and bracket ---------------------------------------


def lie_derivative(field: Sequence[sp.Expr], f: sp.Expr, coords: Sequence[sp.Symbol]) -> sp.Expr:
    """The Lie derivative $Xf = \\sum_j X_j\\,\\partial f/\\partial x_j$ (sympy, not simplified).

    Examples
    --------
    >>> x, y = sp.symbols("x y")
    >>> lie_derivative((y, 0), x**2, (x, y))
    2*x*y
    """
    return sp.Add(*[c * sp.diff(f, x) for c, x in zip(field, coords, strict=True) if c != 0])


def bracket(
    X: Sequence[sp.Expr], Y: Sequence[sp.Expr], coords: Sequence[sp.Symbol]
) -> tuple[sp.Expr, ...]:
    """The Lie bracket $[X, Y] = DY\\cdot X - DX\\cdot Y$ of two sympy fields (expanded).

    Component $j$ is $X(Y_j) - Y(X_j)$, so $[X,Y]f = X(Yf) - Y(Xf)$.

    Parameters
    ----------
    X, Y : sequence of sympy expressions
        The two fields' components, shape ``(n,)``, in the order of ``coords``.
    coords : sequence of sympy symbols
        The coordinates, shape ``(n,)``.

    Examples
    --------
    >>> x, y, th = sp.symbols("x y theta")
    >>> bracket((sp.cos(th), sp.sin(th), 0), (0, 0, 1), (x, y, th))
    (sin(theta), -cos(theta), 0)
    """
    return tuple(
        sp.expand(lie_derivative(X, yj, coords) - lie_derivative(Y, xj, coords))
        for xj, yj in zip(X, Y, strict=True)
    )


# --- symengine word fields, cached per system --------------------------------


# what this module memoises per system (word fields, symbols), owned here: the
# system itself is immutable; an entry goes with its system
_MEMO: IdentityMemo[dict] = IdentityMemo()


def _memo(sys: ControlSystem) -> dict:
    return _MEMO.get(sys, dict)


def se_coordinates(sys: ControlSystem) -> tuple[se.Symbol, ...]:
    """The coordinates of ``sys`` as symengine symbols (cached)."""
    cache = _memo(sys)
    key = "brackets.se_coords"
    if key not in cache:
        cache[key] = tuple(se.Symbol(str(c)) for c in sys.coordinates)
    return cache[key]


def to_symengine(expr: sp.Basic | int) -> se.Basic:
    """Convert an (internal) sympy expression or number to symengine."""
    return se.S(expr)


def to_sympy(sys: ControlSystem, expr: se.Basic) -> sp.Expr:
    """Convert a symengine expression in the coordinates of ``sys`` back to sympy.

    Symbols come back as the system's own coordinate symbols (with their
    assumptions, which symengine does not keep).
    """
    value = sp.S(expr)
    back = _memo(sys).get("brackets.back")
    if back is None:
        back = {sp.Symbol(str(c)): c for c in sys.coordinates if c != sp.Symbol(str(c))}
        _memo(sys)["brackets.back"] = back
    return value.xreplace(back) if back else value


def se_lie_derivative(field: SeField, f: se.Basic, coords: Sequence[se.Symbol]) -> se.Basic:
    """$Xf$ for a symengine field and function, expanded."""
    free = f.free_symbols
    terms = [c * f.diff(x) for c, x in zip(field, coords, strict=True) if c != 0 and x in free]
    if not terms:
        return se.Integer(0)
    return se.expand(se.Add(*terms))


def se_bracket(X: SeField, Y: SeField, coords: Sequence[se.Symbol]) -> SeField:
    """$[X, Y] = DY\\cdot X - DX\\cdot Y$ for symengine fields, each component expanded."""
    out = []
    for xj, yj in zip(X, Y, strict=True):
        terms = []
        fy = yj.free_symbols
        fx = xj.free_symbols
        for ck, dk, x in zip(X, Y, coords, strict=True):
            if ck != 0 and x in fy:
                terms.append(ck * yj.diff(x))
            if dk != 0 and x in fx:
                terms.append(-dk * xj.diff(x))
        out.append(se.expand(se.Add(*terms)) if terms else se.Integer(0))
    return tuple(out)


EXPANSION_TERMS_BUDGET = 2_000_000
"""Most terms an expanded field component may have (a bound checked before expanding)."""


def _terms(e: se.Basic) -> int:
    """Number of terms of an expanded expression."""
    return len(e.args) if isinstance(e, se.Add) else 1


def _expanded_terms_bound(e: se.Basic) -> int:
    """An upper bound on the number of terms of ``se.expand(e)`` (without expanding)."""
    if isinstance(e, se.Add):
        return sum(_expanded_terms_bound(a) for a in e.args)
    if isinstance(e, se.Mul):
        out = 1
        for a in e.args:
            out *= _expanded_terms_bound(a)
        return out
    if isinstance(e, se.Pow):
        base, ex = e.args
        if isinstance(ex, se.Integer) and int(ex) > 1:
            t = _expanded_terms_bound(base)
            return math.comb(int(ex) + t - 1, t - 1) if t > 1 else 1
        return 1
    return 1


def _check_expansion(sys: ControlSystem, word: Word, bound: int) -> None:
    if bound > EXPANSION_TERMS_BUDGET:
        raise ComputationLimitError(
            f"the field of {format_word(word)} of {sys.name!r} would expand to up to "
            f"{bound:,} terms per component (budget EXPANSION_TERMS_BUDGET = "
            f"{EXPANSION_TERMS_BUDGET:,} in nilpotent.core.lie.brackets): refused instead of "
            "exhausting memory; a smaller model (or expanded fields) is needed"
        )


def word_field_symengine(sys: ControlSystem, word: Word) -> SeField:
    """The field of ``word`` as symengine expressions, expanded, cached on ``sys``.

    Parameters are substituted (the fields are ``sys.specialized_fields``);
    $[v, u]$ is reused as $-[u, v]$.
    """
    cache: dict[Word, SeField] = _memo(sys).setdefault(_CACHE_KEY, {})
    hit = cache.get(word)
    if hit is not None:
        return hit
    if isinstance(word, int):
        if not 1 <= word <= sys.m:
            raise OptionError(f"{format_word(word)} is not a field of {sys.name!r} (m = {sys.m})")
        raw = [to_symengine(e) for e in sys.specialized_fields[word - 1]]
        _check_expansion(sys, word, max(_expanded_terms_bound(e) for e in raw))
        value = tuple(se.expand(e) for e in raw)
    elif word[0] == word[1]:
        value = tuple(se.Integer(0) for _ in range(sys.n))
    elif (word[1], word[0]) in cache:
        value = tuple(se.expand(-e) for e in cache[(word[1], word[0])])
    else:
        left = word_field_symengine(sys, word[0])
        right = word_field_symengine(sys, word[1])
        # [X, Y]_j = sum_k X_k d_k Y_j - Y_k d_k X_j: at most this many terms
        bound = max(
            sum(_terms(a) * _terms(b) for a in left) + sum(_terms(a) * _terms(b) for a in right)
            for b in (*left, *right)
        )
        _check_expansion(sys, word, bound)
        value = se_bracket(left, right, se_coordinates(sys))
    cache[word] = value
    return value


def is_built(sys: ControlSystem, word: Word) -> bool:
    """Whether the symbolic field of ``word`` is already cached on ``sys``."""
    return isinstance(word, int) or word in _memo(sys).get(_CACHE_KEY, {})


def word_field(sys: ControlSystem, word: Word) -> tuple[sp.Expr, ...]:
    """The vector field of a bracket word, as expanded sympy expressions.

    Computed with symengine (each bracket expanded), converted to sympy and
    cached on ``sys``.  Parameters are substituted.  Convention
    $[X,Y] = DY\\cdot X - DX\\cdot Y$.

    Parameters
    ----------
    sys : ControlSystem
        The system whose fields ``X1..Xm`` the word names.
    word : Word
        A generator ``i`` (1-based) or a pair of words.

    Examples
    --------
    >>> x, y, th = sp.symbols("x y theta")
    >>> s = ControlSystem("unicycle", (x, y, th), ((sp.cos(th), sp.sin(th), 0), (0, 0, 1)))
    >>> word_field(s, (1, 2))
    (sin(theta), -cos(theta), 0)
    """
    cache: dict[Word, tuple[sp.Expr, ...]] = _memo(sys).setdefault(_SYMPY_CACHE_KEY, {})
    hit = cache.get(word)
    if hit is None:
        hit = tuple(to_sympy(sys, e) for e in word_field_symengine(sys, word))
        cache[word] = hit
    return hit


def _point_substitution(sys: ControlSystem, point: Sequence[sp.Expr]) -> dict[se.Symbol, se.Basic]:
    if len(point) != sys.n:
        raise PointError(f"a point of {sys.name!r} has {sys.n} coordinates, got {len(point)}")
    return {x: to_symengine(v) for x, v in zip(se_coordinates(sys), point, strict=True)}


def _check_finite(value: sp.Expr, sys: ControlSystem, point: Sequence[sp.Expr]) -> None:
    if value.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
        raise PointError(
            f"the fields of {sys.name!r} are not defined at the point "
            f"({', '.join(str(v) for v in point)})"
        )


def _exact_directional(e: se.Basic, subs: dict, direction: dict, t: se.Symbol) -> se.Basic:
    """$\\frac{d}{dt} e(p + t\\,w)|_{t=0}$ exactly (``subs`` is $p$, ``direction`` is $w$)."""
    free = e.free_symbols
    moving = {x: subs[x] + t * direction[x] for x in free if direction.get(x, 0) != 0}
    if not moving:
        return se.Integer(0)
    fixed = {x: subs[x] for x in free if x not in moving}
    return se.expand(e.subs(fixed).subs(moving).diff(t).subs({t: 0}))


def word_values_symengine(
    sys: ControlSystem, word: Word, subs: dict[se.Symbol, se.Basic]
) -> tuple[se.Basic, ...]:
    """Exact value of a word's field at the point ``subs`` (symengine numbers, expanded).

    If the word's field is not cached yet and the word is $[u, v]$, the value is
    $Dv(p)\\,u(p) - Du(p)\\,v(p)$ from directional derivatives of the (built)
    fields of ``u`` and ``v``: the field of the longest words is never expanded.
    """
    cache: dict[Word, SeField] = _memo(sys).setdefault(_CACHE_KEY, {})
    if word in cache or isinstance(word, int):
        return tuple(se.expand(e.subs(subs)) if e.free_symbols else e
                     for e in word_field_symengine(sys, word))
    u, v = word
    fu, fv = word_field_symengine(sys, u), word_field_symengine(sys, v)
    uval = word_values_symengine(sys, u, subs)
    vval = word_values_symengine(sys, v, subs)
    coords = se_coordinates(sys)
    t = se.Dummy("t")
    du = dict(zip(coords, uval, strict=True))
    dv = dict(zip(coords, vval, strict=True))
    return tuple(
        se.expand(_exact_directional(b, subs, du, t) - _exact_directional(a, subs, dv, t))
        for a, b in zip(fu, fv, strict=True)
    )


def word_values_at(
    sys: ControlSystem, words: Iterable[Word], point: Sequence[sp.Expr]
) -> tuple[tuple[sp.Expr, ...], ...]:
    """Exact values at ``point`` of the fields of ``words``.

    Returns ``values[k][j]``, the $x_{j+1}$-component of word ``k`` at the point, as
    sympy numbers (exact where the point is exact; e.g. ``sqrt(3)/2``).  A word
    $[u, v]$ whose field is not cached is evaluated as $Dv(p)u(p) - Du(p)v(p)$
    (see :func:`word_values_symengine`).

    Raises
    ------
    PointError
        If the point has the wrong length or a field is undefined there.

    Examples
    --------
    >>> x, y, th = sp.symbols("x y theta")
    >>> s = ControlSystem("unicycle", (x, y, th), ((sp.cos(th), sp.sin(th), 0), (0, 0, 1)))
    >>> word_values_at(s, [(1, 2), (2, (1, 2))], (0, 0, sp.pi / 2))
    ((1, 0, 0), (0, 1, 0))
    """
    subs = _point_substitution(sys, point)
    out = []
    for w in words:
        vals = tuple(sp.S(v) for v in word_values_symengine(sys, w, subs))
        for v in vals:
            _check_finite(v, sys, point)
        out.append(vals)
    return tuple(out)
