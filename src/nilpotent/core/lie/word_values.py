"""Values of bracket words at a point, for the rank engine (:mod:`nilpotent.core.decide.spans`).

:class:`WordValues` evaluates words at one point as
:class:`~nilpotent.core.decide.spans.Vector` objects: exact rationals, certified arb
balls at any precision, or exact symengine numbers, all by forward-mode
directional derivatives of the fields of the word's halves (so the field of the
longest words is never expanded).  Bracket convention $[X,Y] = DY\\cdot X - DX\\cdot Y$.
"""

from __future__ import annotations

from collections.abc import Sequence

import flint
import symengine as se
import sympy as sp

from nilpotent.core.decide.spans import (
    Evaluator,
    Inaccurate,
    NotEvaluable,
    NotRational,
    SymbolicEvaluator,
    Vector,
    ball,
    exact_value,
)
from nilpotent.core.lie.brackets import (
    Word,
    is_built,
    se_coordinates,
    to_symengine,
    to_sympy,
    word_field_symengine,
)
from nilpotent.core.lie.polynomial_fields import AtomUndefined, PolynomialFields, polynomial_fields
from nilpotent.core.lie.polynomial_values import PointValues
from nilpotent.core.model.system import ControlSystem

__all__ = ["Undefined", "WordValues"]


class Undefined(Exception):
    """A field cannot be evaluated (pole, complex value) at a point."""


class WordValues:
    """Values of bracket words at one point, as :class:`~nilpotent.core.decide.spans.Vector` values.

    When the fields have a polynomial form in the coordinates and elementary
    atoms (:mod:`nilpotent.core.lie.polynomial_fields`: every model built from the
    grammar's polynomial, rational and elementary functions), exact rationals
    and balls come from the word's polynomial field, built by FLINT; its value
    is exact when the coordinates and the atoms are rational at the point
    (``cos(0) = 1``), else a certified ball.  Otherwise (and always with
    ``box``) a word whose field is built (cached on the system) is evaluated
    from its field; a word $[u, v]$ whose field is not built is
    $Dv(q)u(q) - Du(q)v(q)$, from directional derivatives of the fields of
    ``u`` and ``v`` (exact rationals or arb balls, forward-mode), so the longest
    fields are never expanded.  Exact values in symengine's numbers
    (``cos(pi/2)`` is ``0``, ``sqrt(3)/2``) are computed from the symengine
    fields, only when a decision needs them (``symbolic``), and abandoned when
    a value grows beyond a size budget.  With ``box`` (one arb ball per
    coordinate), the balls enclose the values over the whole box (interval
    arithmetic) and no exact value is computed.
    """

    def __init__(
        self,
        sys: ControlSystem,
        point: Sequence[sp.Expr],
        symbolic: bool,
        box: Sequence[flint.arb] | None = None,
    ) -> None:
        self.sys = sys
        self.point = tuple(point)
        self.coords = se_coordinates(sys)
        self.allow_symbolic = symbolic and box is None
        self.box = tuple(box) if box is not None else None
        q = [exact_value(v) for v in point]
        self.rational_point = None if any(v is None for v in q) or box is not None else q
        self._exact: dict[Word, list | None] = {}
        self._balls: dict[tuple[Word, int], list] = {}
        self._sym: dict[Word, tuple | None] = {}
        self._sym_se: dict[Word, list | None] = {}
        self._free: dict[Word, list] = {}
        self._poly: PolynomialFields | None = polynomial_fields(sys) if box is None else None
        self._poly_at = PointValues(self._poly, self.point) if self._poly is not None else None

    def vector(self, word: Word) -> WordVector:
        return WordVector(self, word)

    # exact rationals ------------------------------------------------------------
    def exact(self, word: Word) -> list | None:
        if word in self._exact:
            return self._exact[word]
        out = None
        if self._poly is not None and self._poly_at is not None:
            try:
                out = self._poly_at.exact_field(self._poly.field(word))
            except AtomUndefined as exc:
                raise Undefined(str(exc)) from exc
        elif self.rational_point is not None:
            env = dict(zip(self.coords, self.rational_point, strict=True))
            try:
                out = self._eval(word, env, exact=True, sub=self.exact)
            except NotRational:
                out = None
        self._exact[word] = out
        return out

    def balls(self, word: Word, prec: int) -> list:
        key = (word, prec)
        hit = self._balls.get(key)
        if hit is not None:
            return hit
        if self._poly is not None and self._poly_at is not None:
            try:
                out = self._poly_at.ball_field(self._poly.field(word), prec)
            except AtomUndefined as exc:
                raise Undefined(str(exc)) from exc
            self._balls[key] = out
            return out
        old = flint.ctx.prec
        flint.ctx.prec = prec
        try:
            values = self.box if self.box is not None else [ball(v, prec) for v in self.point]
            env = dict(zip(self.coords, values, strict=True))
            try:
                out = self._eval(word, env, exact=False, sub=lambda w: self.balls(w, prec))
            except Inaccurate:
                out = [flint.arb("nan")] * self.sys.n
        finally:
            flint.ctx.prec = old
        self._balls[key] = out
        return out

    def free(self, word: Word) -> list | None:
        """Exact values of the word's polynomial form at a pseudo-random free point, or None.

        See :meth:`nilpotent.core.lie.polynomial_fields.PolynomialFields.free_field`.
        """
        if self._poly is None:
            return None
        hit = self._free.get(word)
        if hit is None:
            hit = self._poly.free_field(self._poly.field(word))
            self._free[word] = hit
        return hit

    def exact_sympy(self, word: Word) -> tuple[sp.Expr, ...] | None:
        """The exact value as sympy rationals, or None when it is not known to be rational."""
        vals = self.exact(word)
        if vals is None:
            return None
        return tuple(sp.Rational(int(q.p), int(q.q)) for q in vals)

    def _eval(self, word: Word, env: dict, exact: bool, sub) -> list:
        try:
            if isinstance(word, int) or is_built(self.sys, word):
                ev = Evaluator(env, exact)
                return [ev.value(e) for e in word_field_symengine(self.sys, word)]
            u, v = word
            uval, vval = sub(u), sub(v)
            if uval is None or vval is None:
                raise NotRational
            fu, fv = word_field_symengine(self.sys, u), word_field_symengine(self.sys, v)
            along_u = Evaluator(env, exact, dict(zip(self.coords, uval, strict=True)))
            along_v = Evaluator(env, exact, dict(zip(self.coords, vval, strict=True)))
            return [along_u.dual(b)[1] - along_v.dual(a)[1] for a, b in zip(fu, fv, strict=True)]
        except NotEvaluable as exc:
            raise Undefined(str(exc)) from exc
        except ZeroDivisionError as exc:
            raise Undefined("division by zero") from exc

    def symbolic(self, word: Word) -> tuple | None:
        """Exact values (sympy) from symengine's exact numbers, or None beyond the budget."""
        if not self.allow_symbolic:
            return None
        if word not in self._sym:
            try:
                vals = self._symbolic(word)
                out = tuple(to_sympy(self.sys, v) for v in vals) if vals is not None else None
            except NotRational:
                out = None
            self._sym[word] = out
        return self._sym[word]

    def _symbolic(self, word: Word) -> list | None:
        if word in self._sym_se:
            return self._sym_se[word]
        env = {x: to_symengine(v) for x, v in zip(self.coords, self.point, strict=True)}
        try:
            if isinstance(word, int) or is_built(self.sys, word):
                ev = SymbolicEvaluator(env)
                out = [ev.value(e) for e in word_field_symengine(self.sys, word)]
            else:
                u, v = word
                uval, vval = self._symbolic(u), self._symbolic(v)
                if uval is None or vval is None:
                    return None
                fu, fv = word_field_symengine(self.sys, u), word_field_symengine(self.sys, v)
                along_u = SymbolicEvaluator(env, dict(zip(self.coords, uval, strict=True)))
                along_v = SymbolicEvaluator(env, dict(zip(self.coords, vval, strict=True)))
                out = [
                    se.expand(along_u.dual(b)[1] - along_v.dual(a)[1])
                    for a, b in zip(fu, fv, strict=True)
                ]
        except NotRational:
            out = None
        except NotEvaluable as exc:
            raise Undefined(str(exc)) from exc
        self._sym_se[word] = out
        return out


class WordVector(Vector):
    def __init__(self, at: WordValues, word: Word) -> None:
        self.at, self.word = at, word

    def rational(self):
        vals = self.at.exact(self.word)
        if vals is None:
            return None
        return {k: v for k, v in enumerate(vals) if v != 0}

    def balls(self, prec: int):
        return {k: v for k, v in enumerate(self.at.balls(self.word, prec)) if not v.is_zero()}

    def free(self):
        vals = self.at.free(self.word)
        if vals is None:
            return None
        return {k: v for k, v in enumerate(vals) if v != 0}

    def symbolic(self):
        vals = self.at.symbolic(self.word)
        if vals is None:
            return None
        return {k: v for k, v in enumerate(vals) if v != 0}
