r"""Values at a point of fields given as polynomials in coordinates and atoms.

The fields of :mod:`nilpotent.core.lie.polynomial_fields` are polynomials over
$\mathbb{Q}$ in the coordinates and elementary atoms; :class:`PointValues`
gives their values at one point:

* *exact*: when the variables a polynomial uses (coordinates, atoms) have
  rational values at the point (``cos(0) = 1``, ``sin(pi/2) = 1``: symengine's
  exact evaluation), its value is an exact rational (FLINT evaluation at
  integers, with a common denominator as the homogenising variable $h$);
* *balls*: otherwise each variable is enclosed in an ``arb`` ball
  $m_i \pm r_i$ (the atoms by :class:`nilpotent.core.decide.evaluation.Evaluator`),
  the polynomial is evaluated exactly at the dyadic midpoints $m = M/2^e$ (as
  $P(M, 2^e)/2^{e \deg P}$) and the result widened by a rigorous bound of
  $|P(v) - P(m)|$ over the box:
  $\|P\|_1\, d\, \max_i r_i\, \prod_i B_i^{d_i}$ with
  $B_i \ge \max(1, |m_i| + r_i)$, $d$ the total degree and $d_i$ the degree in
  variable $i$ (mean-value theorem, term by term).  The variables are enclosed
  with as many more bits than asked as $\|P\|_1 d$ has, so that the bound stays
  near $2^{-P}$ of the largest terms.  The enclosures are certified like every
  other ball of :mod:`nilpotent.core.decide.spans`.

An atom without a value at the point (``1/a`` at ``a = 0``, needed only for
derivatives of ``sqrt(a)``) is an error only for the polynomials that use it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import flint
import symengine as se
from flint import arb, fmpq

from nilpotent.core.decide.evaluation import Evaluator, Inaccurate, NotEvaluable, exact_value
from nilpotent.core.lie.polynomial_fields import AtomUndefined, HPoly, PolynomialFields

__all__ = ["PointValues"]


class PointValues:
    """Values of the variables (coordinates, atoms) of :class:`PolynomialFields` at a point.

    Raises
    ------
    AtomUndefined
        (from :meth:`exact_field` / :meth:`ball_field`) when an atom is not
        defined at the point (division by zero, complex value).
    """

    def __init__(self, pf: PolynomialFields, point: Sequence[object]) -> None:
        self.pf = pf
        self.point = tuple(point)
        self._exact: list[fmpq | None] | bool = False
        self._balls: dict[int, list[arb]] = {}
        self.undefined: dict[int, str] = {}  # variable index -> why it has no value
        self._reduced: dict[int, tuple[tuple[HPoly, ...], tuple[HPoly, ...]]] = {}

    # exact -------------------------------------------------------------------------
    def exact_vars(self) -> list[fmpq | None]:
        """Exact rational values of the variables (None where irrational), cached.

        Raises
        ------
        AtomUndefined
            If an atom has a pole or a complex value at the point.
        """
        if self._exact is False:
            self._exact = self._exact_vars()
        return self._exact  # type: ignore[return-value]

    def _exact_vars(self) -> list[fmpq | None]:
        out: list[fmpq | None] = [exact_value(v) for v in self.point]
        env = {x: se.S(v) for x, v in zip(self.pf.coords, self.point, strict=True)}
        for atom in self.pf.atoms:
            try:
                value = atom.expr.subs(env) if atom.expr.free_symbols else atom.expr
            except ZeroDivisionError:
                value = se.zoo
            if value.has(se.zoo) or value.has(se.nan):
                # an error only for the polynomials that use it (1/a for the derivative
                # of sqrt(a) is not needed for the value of sqrt(a) at a = 0)
                self.undefined[len(out)] = "division by zero"
                out.append(None)
                continue
            out.append(exact_value(value))
        return out

    def _check_defined(self, field: Sequence[HPoly]) -> None:
        for c in field:
            if c.poly is not None and self.undefined:
                degrees = c.poly.degrees()
                for i, why in self.undefined.items():
                    if degrees[i]:
                        raise AtomUndefined(why)

    def exact_field(self, field: Sequence[HPoly]) -> list[fmpq] | None:
        """Exact rational values of the components, or None when a variable they use is not."""
        values = self.exact_vars()
        self._check_defined(field)
        missing = [i for i, q in enumerate(values) if q is None]
        for c in field:
            if c.poly is not None and missing:
                degrees = c.poly.degrees()
                if any(degrees[i] for i in missing):
                    return None
        den = 1
        for q in values:
            if q is not None:
                den = math.lcm(den, int(q.q))
        args = [fmpq(int(q.p) * (den // int(q.q))) if q is not None else fmpq(0) for q in values]
        args.append(fmpq(den))
        return [
            c.poly(*args) / fmpq(den) ** c.deg if c.poly is not None else fmpq(0) for c in field
        ]

    # balls ---------------------------------------------------------------------------
    def ball_vars(self, prec: int) -> list[arb]:
        """Enclosures of the variables at ``prec`` bits (exact where rational), cached."""
        hit = self._balls.get(prec)
        if hit is not None:
            return hit
        from nilpotent.core.decide.evaluation import ball

        exact = self.exact_vars()
        old = flint.ctx.prec
        flint.ctx.prec = prec
        try:
            n = len(self.point)
            coords = [
                arb(q) if q is not None else ball(v, prec)
                for q, v in zip(exact[:n], self.point, strict=True)
            ]
            env = dict(zip(self.pf.coords, coords, strict=True))
            ev = Evaluator(env, exact=False)
            out = list(coords)
            for atom, q in zip(self.pf.atoms, exact[n:], strict=True):
                if q is not None:
                    out.append(arb(q))
                    continue
                if len(out) in self.undefined:
                    out.append(arb("nan"))
                    continue
                try:
                    out.append(ev.value(atom.expr))
                except Inaccurate:
                    out.append(arb("nan"))
                except (NotEvaluable, ZeroDivisionError) as exc:
                    self.undefined[len(out)] = str(exc) or "division by zero"
                    out.append(arb("nan"))
        finally:
            flint.ctx.prec = old
        self._balls[prec] = out
        return out

    def ball_field(self, field: tuple[HPoly, ...], prec: int) -> list[arb]:
        """Certified enclosures of the components at ``prec`` bits (see the module docstring).

        All components are ``nan`` balls when a variable they use could not be
        enclosed (as when a ball evaluation loses all accuracy).
        """
        field = self._without_zeros(field)
        norms = self.pf.norms(field)
        # work with enough more bits that the error bound (proportional to the 1-norm
        # of the coefficients) stays near 2^-prec of the largest terms
        extra = max((int(q * c.deg).bit_length() for q, c in zip(norms, field, strict=True)),
                    default=0)
        work = prec + 32 * ((extra + 31) // 32)
        out = self._ball_field(field, norms, work)
        # a value much smaller than the 1-norm (cancellation, tiny atoms) loses relative
        # accuracy: when more than half of the bits are lost, evaluate once more with them
        lost = max((_magnitude(v.rad()) - _magnitude(v.mid()) + prec for v in out
                    if v.is_finite() and not v.mid().is_zero() and not v.rad().is_zero()),
                   default=0)
        if lost > prec // 2:
            out = self._ball_field(field, norms, work + 32 * ((min(lost, 4096) + 31) // 32))
        return out

    def _without_zeros(self, field: tuple[HPoly, ...]) -> tuple[HPoly, ...]:
        r"""The field with the variables exactly 0 at the point substituted (cached).

        A term with a factor exactly 0 is exactly 0 whatever the other factors'
        enclosures (as in ball arithmetic, where $0 \cdot [m \pm r] = 0$), so
        an exact zero stays exact.
        """
        zeros = [i for i, q in enumerate(self.exact_vars()) if q is not None and q == 0]
        if not zeros:
            return field
        hit = self._reduced.get(id(field))
        if hit is not None and hit[0] is field:
            return hit[1]
        out = []
        for c in field:
            if c.poly is not None:
                degrees = c.poly.degrees()
                if any(degrees[i] for i in zeros):
                    p = c.poly.subs({i: fmpq(0) for i in zeros if degrees[i]})
                    c = HPoly(p, c.deg) if not p.is_zero() else HPoly(None, 0)
            out.append(c)
        reduced = tuple(out)
        self._reduced[id(field)] = (field, reduced)
        return reduced

    def _ball_field(self, field: tuple[HPoly, ...], norms: list[fmpq], work: int) -> list[arb]:
        n = len(field)
        values = self.ball_vars(work)
        self._check_defined(field)
        used = [False] * len(values)
        degrees = [c.poly.degrees() if c.poly is not None else None for c in field]
        for deg in degrees:
            if deg is not None:
                for i, d in enumerate(deg[: len(values)]):
                    if d:
                        used[i] = True
        if any(u and not b.is_finite() for u, b in zip(used, values, strict=True)):
            return [arb("nan")] * n
        old = flint.ctx.prec
        flint.ctx.prec = work
        try:
            mids, exps, radius, bounds = [], [], arb(0), []
            for u, b in zip(used, values, strict=True):
                if not u:
                    mids.append(0)
                    exps.append(0)
                    bounds.append(arb(1))
                    continue
                man, ex = b.mid().man_exp()
                mids.append(int(man))
                exps.append(int(ex))
                r = b.rad()
                if r > radius:
                    radius = r
                bounds.append(max(arb(1), arb(b.abs_upper())))
            e = max(0, *(-x for x in exps))
            args = [fmpq(m * 2 ** (x + e)) for m, x in zip(mids, exps, strict=True)]
            args.append(fmpq(2**e))
            out = []
            for c, deg, norm1 in zip(field, degrees, norms, strict=True):
                if c.poly is None or deg is None:
                    out.append(arb(0))
                    continue
                value = arb(c.poly(*args) / fmpq(2 ** (e * c.deg)))
                if radius != 0:
                    growth = arb(1)
                    for bnd, d in zip(bounds, deg, strict=False):
                        if d:
                            growth *= bnd**d
                    err = arb(norm1) * c.deg * radius * growth
                    value += arb(0, err.abs_upper())
                out.append(value)
            return out
        finally:
            flint.ctx.prec = old


def _magnitude(x: arb) -> int:
    r"""$\lfloor \log_2 |x| \rfloor + 1$ of a nonzero ball's midpoint (exact exponent, no float)."""
    man, ex = x.mid().man_exp()
    return int(ex) + abs(int(man)).bit_length()
