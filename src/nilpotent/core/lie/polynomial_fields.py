r"""Vector fields as polynomials over $\mathbb{Q}$ in the coordinates and in elementary *atoms*.

The fields of most models are built from the coordinates with $+$, $\times$,
integer and rational powers and the elementary functions of the expression
grammar.  Each non-polynomial piece is an *atom* ($\sin u$, $\cos u$,
$e^{u}$, $1/b$, $b^{1/2}$, ...) and the atoms are closed under
differentiation: $\partial_k \sin u = \cos u\,\partial_k u$,
$\partial_k (1/b) = -(1/b)^2\,\partial_k b$,
$\partial_k b^{\alpha} = \alpha\, b^{\alpha}\,(1/b)\,\partial_k b$,
$\partial_k \log u = (1/u)\,\partial_k u$, ... (a differential algebra generated
by finitely many atoms).  A field is then a vector of polynomials over
$\mathbb{Q}$ in the coordinates and the atoms, and the bracket
$[X,Y]_j = \sum_k X_k\,\partial_k Y_j - Y_k\,\partial_k X_j$ (convention
$[X,Y] = DY\cdot X - DX\cdot Y$) is polynomial arithmetic in FLINT
(python-flint ``fmpq_mpoly``): for ``car-trailers:9`` every bracket up to length
11 takes a fraction of a second, where expanding the symengine expressions to
length 10 takes about half a minute.  No identity between atoms
($\sin^2 + \cos^2 = 1$) is used: the polynomials are not reduced, and their
values are exactly the values of the fields.

Values at a point (exact rationals, or certified arb balls):
:mod:`nilpotent.core.lie.polynomial_values`.  A dependence found at a random
*free* point (the coordinates and atoms treated as independent variables,
:meth:`PolynomialFields.free_field`) is a polynomial identity.

Polynomials are kept homogeneous in an extra variable $h$ (evaluated at 1),
so that a polynomial is evaluated at $m = M/2^e$ as $P(M, 2^e)/2^{e\deg P}$:
an evaluation at integers, about ten times faster in FLINT than at
rationals.  A system whose fields use something outside these functions
(``Abs``, a symbolic exponent) has no polynomial form
(:func:`polynomial_fields` returns None) and the caller keeps the expression path.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

import symengine as se
from flint import fmpq, fmpq_mpoly, fmpq_mpoly_ctx

from nilpotent.core.lie.brackets import (
    EXPANSION_TERMS_BUDGET,
    Word,
    format_word,
    se_coordinates,
    word_field_symengine,
)
from nilpotent.core.model.memo import IdentityMemo
from nilpotent.core.model.system import ControlSystem
from nilpotent.errors import ComputationLimitError

__all__ = ["AtomUndefined", "HPoly", "PolynomialFields", "Unsupported", "polynomial_fields"]

_FREE_SEED = 20261130


class Unsupported(Exception):
    """An expression has no polynomial form in atoms (the expression path is used instead)."""


class AtomUndefined(ValueError):
    """An atom cannot be evaluated at a point (pole, complex value)."""


@dataclass(frozen=True)
class HPoly:
    """A polynomial homogeneous of degree ``deg`` in the variables and $h$ (None: the zero)."""

    poly: fmpq_mpoly | None
    deg: int = 0

    @property
    def terms(self) -> int:
        return 0 if self.poly is None else len(self.poly)


ZERO = HPoly(None, 0)

# one-argument functions: kind -> derivative rule (see PolynomialFields._derivative_of_atom)
_FUNCTIONS = {
    se.sin: "sin", se.cos: "cos", se.tan: "tan", se.exp: "exp", se.log: "log",
    se.atan: "atan", se.sinh: "sinh", se.cosh: "cosh", se.tanh: "tanh",
    se.asin: "asin", se.acos: "acos",
}
_PAIRS = {"sin": "cos", "cos": "sin", "sinh": "cosh", "cosh": "sinh"}
_BUILD = {
    "sin": se.sin, "cos": se.cos, "tan": se.tan, "exp": se.exp, "log": se.log,
    "atan": se.atan, "sinh": se.sinh, "cosh": se.cosh, "tanh": se.tanh,
    "asin": se.asin, "acos": se.acos,
}


@dataclass(frozen=True)
class _Atom:
    kind: str  # a function name, "pow" (base**exponent, non-integer or -1) or "const"
    args: tuple  # symengine arguments: (u,), (y, x) for atan2, (base, exponent) for pow
    expr: se.Basic  # the atom as a symengine expression (for its value at a point)


class PolynomialFields:
    """The fields of a system as polynomials in coordinates and atoms; brackets by FLINT.

    Build with :func:`polynomial_fields` (cached on the system).  Variables:
    the $n$ coordinates, the atoms, then $h$.
    """

    def __init__(self, sys: ControlSystem) -> None:
        self.sys = sys
        self.coords = se_coordinates(sys)
        self._coord_index = {c: i for i, c in enumerate(self.coords)}
        generators = [word_field_symengine(sys, i) for i in range(1, sys.m + 1)]
        self.atoms: list[_Atom] = []
        self._atom_index: dict[tuple, int] = {}
        for field in generators:
            for e in field:
                self._register(e)
        n = sys.n
        names = [f"x{i}" for i in range(n)] + [f"a{i}" for i in range(len(self.atoms))] + ["h"]
        self.ctx = fmpq_mpoly_ctx.get(names, "lex")
        self.nvars = len(names)
        gens = self.ctx.gens()
        self._vars = [HPoly(g, 1) for g in gens[:-1]]
        self._h = gens[-1]
        self._one = HPoly(self.ctx.constant(1), 0)
        self._poly_memo: dict[se.Basic, HPoly] = {}
        # d(variable)/d(coordinate k), for every variable that is not constant
        self._dvar: list[dict[int, HPoly]] = [{k: self._one} for k in range(n)]
        for atom in self.atoms:
            self._dvar.append(self._derivative_of_atom(atom))
        self._fields: dict[Word, tuple[HPoly, ...]] = {}
        self._partials: dict[tuple[Word, int], dict[int, HPoly]] = {}
        self._norms: dict[int, tuple[tuple[HPoly, ...], list[fmpq]]] = {}
        for i, field in enumerate(generators, start=1):
            self._fields[i] = tuple(self.poly(e) for e in field)

    # --- registration of atoms ------------------------------------------------
    def _add_atom(self, kind: str, args: tuple, expr: se.Basic) -> None:
        key = (kind, args)
        if key not in self._atom_index:
            self._atom_index[key] = len(self.atoms)
            self.atoms.append(_Atom(kind, args, expr))

    def _register(self, e: se.Basic) -> None:
        if e.is_Symbol:
            if e not in self._coord_index:
                raise Unsupported(f"symbol {e}")
            return
        if isinstance(e, (se.Integer, se.Rational, se.RealDouble)):
            return
        if not e.free_symbols:
            self._add_atom("const", (e,), e)
            return
        if isinstance(e, (se.Add, se.Mul)):
            for a in e.args:
                self._register(a)
            return
        if isinstance(e, se.Pow):
            base, ex = e.args
            if base == se.E:  # symengine writes exp(u) as E**u
                self._register(ex)
                self._add_atom("exp", (ex,), e)
                return
            self._register(base)
            if isinstance(ex, se.Integer):
                if int(ex) < 0:
                    self._add_atom("pow", (base, se.Integer(-1)), base ** -1)
                return
            if isinstance(ex, se.Rational):
                self._add_atom("pow", (base, se.Integer(-1)), base ** -1)
                self._add_atom("pow", (base, ex), e)
                return
            raise Unsupported(f"power {e}")
        if isinstance(e, se.atan2):
            y, x = e.args
            self._register(y)
            self._register(x)
            r = se.expand(x**2 + y**2)
            self._register(r)
            self._add_atom("pow", (r, se.Integer(-1)), r**-1)
            self._add_atom("atan2", (y, x), e)
            return
        kind = _FUNCTIONS.get(type(e))
        if kind is None or len(e.args) != 1:
            raise Unsupported(f"function {type(e).__name__}")
        (u,) = e.args
        self._register(u)
        if kind in ("log",):
            self._add_atom("pow", (u, se.Integer(-1)), u**-1)
        elif kind == "atan":
            r = se.expand(1 + u**2)
            self._register(r)
            self._add_atom("pow", (r, se.Integer(-1)), r**-1)
        elif kind in ("asin", "acos"):
            r = se.expand(1 - u**2)
            self._register(r)
            self._add_atom("pow", (r, se.Integer(-1)), r**-1)
            self._add_atom("pow", (r, se.Rational(-1, 2)), r ** se.Rational(-1, 2))
        self._add_atom(kind, (u,), e)
        if kind in _PAIRS:
            other = _PAIRS[kind]
            self._add_atom(other, (u,), _BUILD[other](u))

    def _atom_var(self, kind: str, *args: se.Basic) -> HPoly:
        return self._vars[self.sys.n + self._atom_index[(kind, args)]]

    # --- conversion -----------------------------------------------------------------
    def constant(self, q: fmpq) -> HPoly:
        return HPoly(self.ctx.constant(q), 0) if q != 0 else ZERO

    def poly(self, e: se.Basic) -> HPoly:
        """The polynomial of a (registered) symengine expression."""
        hit = self._poly_memo.get(e)
        if hit is None:
            hit = self._poly(e)
            self._poly_memo[e] = hit
        return hit

    def _poly(self, e: se.Basic) -> HPoly:
        if e.is_Symbol:
            return self._vars[self._coord_index[e]]
        if isinstance(e, se.Integer):
            return self.constant(fmpq(int(e)))
        if isinstance(e, se.Rational):
            p, q = e.get_num_den()
            return self.constant(fmpq(int(p), int(q)))
        if isinstance(e, se.RealDouble):
            fr = Fraction(repr(float(e)))
            return self.constant(fmpq(fr.numerator, fr.denominator))
        if not e.free_symbols:
            return self._atom_var("const", e)
        if isinstance(e, se.Add):
            out = ZERO
            for a in e.args:
                out = self.add(out, self.poly(a))
            return out
        if isinstance(e, se.Mul):
            out = self._one
            for a in e.args:
                out = self.mul(out, self.poly(a))
            return out
        if isinstance(e, se.Pow):
            base, ex = e.args
            if base == se.E:
                return self._atom_var("exp", ex)
            if isinstance(ex, se.Integer):
                k = int(ex)
                if k >= 0:
                    return self.power(self.poly(base), k)
                return self.power(self._atom_var("pow", base, se.Integer(-1)), -k)
            return self._atom_var("pow", base, ex)
        if isinstance(e, se.atan2):
            return self._atom_var("atan2", *e.args)
        return self._atom_var(_FUNCTIONS[type(e)], e.args[0])

    # --- arithmetic -------------------------------------------------------------------
    def _pad(self, a: HPoly, deg: int) -> fmpq_mpoly:
        assert a.poly is not None
        return a.poly if a.deg == deg else a.poly * self._h ** (deg - a.deg)

    def add(self, a: HPoly, b: HPoly, sign: int = 1) -> HPoly:
        if b.poly is None:
            return a
        if a.poly is None:
            return b if sign == 1 else HPoly(-b.poly, b.deg)
        deg = max(a.deg, b.deg)
        pa, pb = self._pad(a, deg), self._pad(b, deg)
        s = pa + pb if sign == 1 else pa - pb
        return HPoly(s, deg) if not s.is_zero() else ZERO

    def mul(self, a: HPoly, b: HPoly, word: Word | None = None) -> HPoly:
        if a.poly is None or b.poly is None:
            return ZERO
        if word is not None and a.terms * b.terms > EXPANSION_TERMS_BUDGET:
            raise ComputationLimitError(
                f"the field of {format_word(word)} of {self.sys.name!r} would expand to up to "
                f"{a.terms * b.terms:,} terms in one product (budget EXPANSION_TERMS_BUDGET = "
                f"{EXPANSION_TERMS_BUDGET:,} in nilpotent.core.lie.brackets): refused instead of "
                "exhausting memory; a smaller model is needed"
            )
        return HPoly(a.poly * b.poly, a.deg + b.deg)

    def power(self, a: HPoly, k: int) -> HPoly:
        if k == 0:
            return self._one
        if a.poly is None:
            return ZERO
        return HPoly(a.poly**k, a.deg * k)

    def scale(self, a: HPoly, q: fmpq) -> HPoly:
        return HPoly(a.poly * q, a.deg) if a.poly is not None and q != 0 else ZERO

    def var_partial(self, a: HPoly, var: int) -> HPoly:
        """$\\partial a / \\partial v$ for the variable of index ``var``."""
        if a.poly is None:
            return ZERO
        d = a.poly.derivative(var)
        return HPoly(d, a.deg - 1) if not d.is_zero() else ZERO

    def partial(self, a: HPoly, k: int, word: Word | None = None) -> HPoly:
        """$\\partial a / \\partial x_k$ (chain rule through the atoms)."""
        if a.poly is None:
            return ZERO
        out = ZERO
        degrees = a.poly.degrees()
        for v, dv in enumerate(self._dvar):
            if degrees[v] == 0:
                continue
            step = dv.get(k)
            if step is None:
                continue
            out = self.add(out, self.mul(self.var_partial(a, v), step, word))
        return out

    def _derivative_of_atom(self, atom: _Atom) -> dict[int, HPoly]:
        """$\\partial(\\text{atom})/\\partial x_k$ for every coordinate $k$ it depends on."""
        kind, args = atom.kind, atom.args
        if kind == "const":
            return {}
        me = self._atom_var(kind, *args)
        out: dict[int, HPoly] = {}
        if kind == "atan2":
            y, x = (self.poly(a) for a in args)
            r = self._atom_var("pow", se.expand(args[1] ** 2 + args[0] ** 2), se.Integer(-1))
            for k in range(self.sys.n):
                num = self.add(
                    self.mul(x, self.partial(y, k)), self.mul(y, self.partial(x, k)), sign=-1
                )
                if num.poly is not None:
                    out[k] = self.mul(num, r)
            return out
        u = self.poly(args[0])
        if kind == "pow":
            ex = args[1]
            inv = self._atom_var("pow", args[0], se.Integer(-1))
            if isinstance(ex, se.Integer):  # 1/b: -(1/b)^2 b'
                factor = self.scale(self.mul(inv, inv), fmpq(-1))
            else:  # b^a: a b^a (1/b) b'
                p, q = ex.get_num_den()
                factor = self.scale(self.mul(me, inv), fmpq(int(p), int(q)))
        elif kind in ("sin", "sinh"):
            factor = self._atom_var(_PAIRS[kind], *args)
        elif kind == "cos":
            factor = self.scale(self._atom_var("sin", *args), fmpq(-1))
        elif kind == "cosh":
            factor = self._atom_var("sinh", *args)
        elif kind == "tan":
            factor = self.add(self._one, self.mul(me, me))
        elif kind == "tanh":
            factor = self.add(self._one, self.mul(me, me), sign=-1)
        elif kind == "exp":
            factor = me
        elif kind == "log":
            factor = self._atom_var("pow", args[0], se.Integer(-1))
        elif kind == "atan":
            factor = self._atom_var("pow", se.expand(1 + args[0] ** 2), se.Integer(-1))
        else:  # asin, acos: +-(1 - u^2)^(-1/2)
            root = self._atom_var("pow", se.expand(1 - args[0] ** 2), se.Rational(-1, 2))
            factor = root if kind == "asin" else self.scale(root, fmpq(-1))
        for k in range(self.sys.n):
            du = self.partial(u, k)
            if du.poly is not None:
                out[k] = self.mul(factor, du)
        return out

    # --- word fields ------------------------------------------------------------------
    def field(self, word: Word) -> tuple[HPoly, ...]:
        """The field of ``word`` (components, in the order of the coordinates), cached.

        Words equal up to sign by antisymmetry ($[v, u] = -[u, v]$, at any depth)
        share one computation.

        Raises
        ------
        ComputationLimitError
            If one product would exceed ``EXPANSION_TERMS_BUDGET`` terms.
        """
        hit = self._fields.get(word)
        if hit is not None:
            return hit
        canon, sign = _canonical(word)
        if sign == 0:
            value: tuple[HPoly, ...] = (ZERO,) * self.sys.n
        elif canon != word:
            value = self.field(canon)
            if sign < 0:
                value = tuple(self.scale(c, fmpq(-1)) for c in value)
        else:
            u, v = word  # type: ignore[misc]
            X, Y = self.field(u), self.field(v)
            out = []
            for j in range(self.sys.n):
                acc = ZERO
                for k in range(self.sys.n):
                    if X[k].poly is not None and Y[j].poly is not None:
                        acc = self.add(acc, self.mul(X[k], self._partial_of(v, j, k), word))
                    if Y[k].poly is not None and X[j].poly is not None:
                        acc = self.add(
                            acc, self.mul(Y[k], self._partial_of(u, j, k), word), sign=-1
                        )
                out.append(acc)
            value = tuple(out)
        self._fields[word] = value
        return value

    def _partial_of(self, word: Word, j: int, k: int) -> HPoly:
        cache = self._partials.setdefault((word, j), {})
        hit = cache.get(k)
        if hit is None:
            hit = self.partial(self.field(word)[j], k, word)
            cache[k] = hit
        return hit

    def free_point(self) -> list[fmpq]:
        r"""A pseudo-random point of $\mathbb{Z}^N$ for the variables (fixed seed), $h = 1$.

        Coordinates and atoms get independent values in $[2^{61}, 2^{62})$, as if
        no relation tied them: see :meth:`PointValues.free_field`.
        """
        hit = getattr(self, "_free", None)
        if hit is None:
            rng = random.Random(_FREE_SEED)
            hit = [fmpq(rng.randrange(2**61, 2**62)) for _ in range(self.nvars - 1)]
            hit.append(fmpq(1))
            self._free = hit
        return hit

    def free_field(self, field: Sequence[HPoly]) -> list[fmpq]:
        r"""The components' exact values at :meth:`free_point`.

        If these vectors, for some words, are linearly dependent, then so are
        the words' polynomial vectors over $\mathbb{Q}(x, a)$ (with probability
        at least $1 - D/2^{61}$, $D$ the degree of a nonzero minor: the
        Schwartz-Zippel lemma), hence the words' values at *every* point.
        """
        args = self.free_point()
        return [c.poly(*args) if c.poly is not None else fmpq(0) for c in field]

    def norms(self, field: tuple[HPoly, ...]) -> list[fmpq]:
        """The 1-norms of the components' coefficients (cached with the field)."""
        hit = self._norms.get(id(field))
        if hit is None or hit[0] is not field:
            values = [
                sum((abs(q) for q in c.poly.coeffs()), fmpq(0)) if c.poly is not None
                else fmpq(0)
                for c in field
            ]
            hit = (field, values)
            self._norms[id(field)] = hit
        return hit[1]


def _canonical(word: Word) -> tuple[Word, int]:
    """``(w, s)`` with ``word = s * w``, ``w`` having each pair's halves in a fixed order.

    ``s = 0`` when the word is 0 by antisymmetry ($[u, u] = 0$ at some depth).
    """
    if isinstance(word, int):
        return word, 1
    cu, su = _canonical(word[0])
    cv, sv = _canonical(word[1])
    if su == 0 or sv == 0 or cu == cv:
        return word, 0
    if _order(cu) > _order(cv):
        return (cv, cu), -su * sv
    return (cu, cv), su * sv


def _order(word: Word) -> tuple[int, str]:
    from nilpotent.core.lie.brackets import word_length

    return word_length(word), repr(word)


def polynomial_fields(sys: ControlSystem) -> PolynomialFields | None:
    """The polynomial form of the fields of ``sys`` (cached on it), or None when it has none.

    Raises
    ------
    ComputationLimitError
        If a generator field is too large to expand (as for the expression path).
    """
    return _MEMO.get(sys, lambda: _build(sys))


def _build(sys: ControlSystem) -> PolynomialFields | None:
    try:
        return PolynomialFields(sys)
    except Unsupported:
        return None


# the polynomial fields per system, owned here (the system is immutable); a value
# refers to its system, so the table is bounded
_MEMO: IdentityMemo[PolynomialFields | None] = IdentityMemo(maxsize=64)
