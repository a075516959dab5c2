r"""The audit of the paper: every checkable printed statement against a computation.

:func:`run_audit` reads the paper's formulas from its LaTeX source
(:func:`nilpotent.report.paper.read_paper`), computes the same objects with the
library — the built-in models ``trident-snake`` (body-velocity inputs, the
paper's Section 4, ``r = l = 1``) and ``trident-snake-paper`` (its eq. ``vf``),
:func:`~nilpotent.core.filtration.analyze`,
:func:`~nilpotent.core.approximation.approximate`, brackets with
:func:`~nilpotent.core.brackets.bracket`, and one-period simulations of the
periodic inputs (:mod:`nilpotent.simulate`) — and compares them **when it
runs**.  Nothing in this module states a verdict in advance.

Comparisons are exact where the objects are exact: two expressions are equal
when their difference vanishes at several random rational points evaluated with
30 significant digits (a nonzero value there proves a difference) *and* sympy
cannot show it is nonzero; bracket values at the origin are exact algebraic
numbers compared structurally.  Simulations decide only what is numerical by
nature (which bracket a periodic input realises), with stated tolerances.

Conventions: $[X, Y] = DY\cdot X - DX\cdot Y$; the input
$u_i = -A\omega\sin\omega t$, $u_j = A\omega\cos\omega t$ moves the state by
$\pi A^2 [X_i, X_j](p) + O(A^3)$ per period.

Each :class:`AuditEntry` has the fields of the ``nilpotent/audit@1`` schema
(``INTERFACE.md``): ``id, section, statement, paper, computed, verdict
(agrees|differs), explanation``.
"""

from __future__ import annotations

import math
import random
import re
from collections.abc import Callable, Collection, Iterable, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import sympy as sp

from nilpotent.core.brackets import bracket
from nilpotent.core.expressions import format_expression
from nilpotent.core.system import ControlSystem
from nilpotent.errors import OptionError
from nilpotent.report.latexmath import strip_layout
from nilpotent.report.paper import OMEGA, A, PaperContent, PrintedField, T, X, Y, read_paper

__all__ = ["AUDIT_SCHEMA", "CHECKS", "Audit", "AuditEntry", "format_field", "run_audit"]

#: The schema name written into ``audit.json``.
AUDIT_SCHEMA = "nilpotent/audit@1"
AGREES = "agrees"
DIFFERS = "differs"

_SAMPLES = 6
_DIGITS = 30
_NUMERIC_ZERO = sp.Float("1e-20")


@dataclass(frozen=True)
class AuditEntry:
    """One checked statement of the paper (the ``nilpotent/audit@1`` entry)."""

    id: str
    section: str
    statement: str
    paper: str
    computed: str
    verdict: str
    explanation: str

    def __post_init__(self) -> None:
        if self.verdict not in (AGREES, DIFFERS):
            raise ValueError(f"verdict must be {AGREES!r} or {DIFFERS!r}, got {self.verdict!r}")

    def as_dict(self) -> dict[str, str]:
        return {
            "id": self.id,
            "section": self.section,
            "statement": self.statement,
            "paper": self.paper,
            "computed": self.computed,
            "verdict": self.verdict,
            "explanation": self.explanation,
        }


@dataclass(frozen=True)
class Audit:
    """The audit of the paper: its entries and the source they were read from."""

    entries: tuple[AuditEntry, ...]
    paper_sha256: str

    @property
    def agreeing(self) -> tuple[AuditEntry, ...]:
        return tuple(e for e in self.entries if e.verdict == AGREES)

    @property
    def differing(self) -> tuple[AuditEntry, ...]:
        return tuple(e for e in self.entries if e.verdict == DIFFERS)

    def entry(self, entry_id: str) -> AuditEntry:
        """The entry with this id (``KeyError`` if none)."""
        for e in self.entries:
            if e.id == entry_id:
                return e
        raise KeyError(entry_id)

    def as_json(self) -> dict[str, Any]:
        """The ``nilpotent/audit@1`` object of ``INTERFACE.md`` (plus a summary)."""
        return {
            "schema": AUDIT_SCHEMA,
            "paper_sha256": self.paper_sha256,
            "summary": {
                "entries": len(self.entries),
                "agrees": len(self.agreeing),
                "differs": len(self.differing),
            },
            "entries": [e.as_dict() for e in self.entries],
        }


# --- exact comparison and printing ---------------------------------------------
def _vanishes(expr: sp.Expr, seed: int = 0) -> bool:
    """Whether ``expr`` is identically zero (random 30-digit points, then sympy)."""
    e = sp.expand(sp.S(expr))
    if e == 0:
        return True
    free = sorted(e.free_symbols, key=str)
    if not free:
        return abs(sp.N(e, _DIGITS)) < _NUMERIC_ZERO and sp.simplify(e) == 0
    rng = random.Random(seed)
    for _ in range(_SAMPLES):
        point = {s: sp.Rational(rng.randint(-97, 97), 31) for s in free}
        if abs(sp.N(e.subs(point), _DIGITS)) > _NUMERIC_ZERO:
            return False
    return True


def _same(a: Sequence[sp.Expr], b: Sequence[sp.Expr]) -> bool:
    return len(a) == len(b) and all(_vanishes(sp.S(x) - sp.S(y)) for x, y in zip(a, b, strict=True))


def _exact(value: sp.Expr) -> sp.Expr:
    return sp.nsimplify(sp.simplify(value)) if sp.S(value).free_symbols == set() else value


def _at_origin(field: Sequence[sp.Expr], coords: Sequence[sp.Symbol]) -> tuple[sp.Expr, ...]:
    zero = {c: 0 for c in coords}
    return tuple(sp.radsimp(sp.simplify(sp.S(c).subs(zero))) for c in field)


def _fmt(value: sp.Expr) -> str:
    return format_expression(sp.S(value))


def format_field(comps: Sequence[sp.Expr], coords: Sequence[sp.Symbol]) -> str:
    """``sqrt(3)*∂x5 - sqrt(3)*∂x6``: a field in the expression grammar with ∂ names."""
    terms = []
    for c, x in zip(comps, coords, strict=True):
        c = sp.S(c)
        if c == 0:
            continue
        name = f"∂{x}"
        if c == 1:
            terms.append(name)
        elif c == -1:
            terms.append(f"-{name}")
        else:
            sign = ""
            if c.could_extract_minus_sign():
                sign, c = "-", -c
            text = _fmt(c)
            if not (c.is_Atom or c.is_Function or c.is_Pow or c.is_Mul):
                text = f"({text})"
            terms.append(f"{sign}{text}*{name}")
    text = " + ".join(terms) or "0"
    return text.replace("+ -", "- ")


def _printed(field: PrintedField) -> str:
    """A field as printed in the paper: ``g_1 = <its LaTeX>``, whitespace normalised."""
    name = ("\\hat g_" if field.name.startswith("ĝ") else "g_") + field.name[-1]
    return f"{name} = " + re.sub(r"\s+", " ", field.latex).strip()


def _printed_matrix(latex: str) -> str:
    """The printed matrix's LaTeX cells without layout commands: ``[a, b, ...; ...]``."""
    rows = []
    for row in latex.split("\\\\"):
        cells = [re.sub(r"\s+", " ", strip_layout(c)).strip() for c in row.split("&")]
        rows.append(", ".join(cells))
    return "[" + "; ".join(rows) + "]"


def _fmt_vec(values: Sequence[sp.Expr]) -> str:
    return "(" + ", ".join(_fmt(v) for v in values) + ")"


def _fmt_rate(values: Sequence[float]) -> str:
    """Simulated rates to 4 decimals (values below 5e-5 print as 0)."""
    return "(" + ", ".join(f"{v:.4f}" if abs(v) >= 5e-5 else "0" for v in values) + ")"


def _proportional(u: Sequence[sp.Expr], v: Sequence[sp.Expr]) -> bool:
    """Both nonzero and parallel (``u = c v`` for some real ``c ≠ 0``)."""
    if all(_vanishes(a) for a in u) or all(_vanishes(b) for b in v):
        return False
    return all(
        _vanishes(u[i] * v[j] - u[j] * v[i]) for i in range(len(u)) for j in range(i + 1, len(u))
    )


def _weighted_part(
    expr: sp.Expr, ys: Sequence[sp.Symbol], weights: Sequence[int], d: int
) -> sp.Expr:
    """The terms of weighted degree ``d`` of ``expr`` at 0 (Taylor; weights ``w_k`` of ``y_k``)."""
    t = sp.Dummy("t")
    scaled = sp.S(expr).subs(
        {y: t**w * y for y, w in zip(ys, weights, strict=True)}, simultaneous=True
    )
    coeff = sp.diff(scaled, t, d).subs(t, 0) / sp.factorial(d)
    return sp.expand(sp.simplify(coeff))


def _push(
    fields: Sequence[Sequence[sp.Expr]], jac: sp.Matrix, old: Sequence[sp.Symbol], inverse: dict
) -> tuple[tuple[sp.Expr, ...], ...]:
    """Push fields forward by a change of coordinates with Jacobian ``jac`` (new/old)."""
    out = []
    for f in fields:
        col = jac * sp.Matrix([sp.S(c) for c in f])
        out.append(tuple(sp.expand(sp.S(c).subs(inverse, simultaneous=True)) for c in col))
    return tuple(out)


def _rank(vectors: Sequence[Sequence[sp.Expr]]) -> int:
    from nilpotent.core.spans import rank  # the one rank engine (certified; random point)

    return rank(vectors, probabilistic=True)[0]


# --- what the audit computes ---------------------------------------------------
class _Computed:
    """The computed side, built lazily (each object once)."""

    def __init__(self, paper: PaperContent) -> None:
        self.paper = paper

    @cached_property
    def body(self) -> ControlSystem:
        from nilpotent.models import get_model

        model = get_model("trident-snake", {"r": sp.Integer(1), "l": sp.Integer(1)}).specialized()
        # the paper's names: (x, y, θ, φ1, φ2, φ3) =: (x1, ..., x6)
        rename = dict(zip(model.coordinates, X, strict=True))
        fields = tuple(tuple(sp.S(v).xreplace(rename) for v in f) for f in model.fields)
        return ControlSystem(model.name, X, fields, (), model.description)

    @cached_property
    def vf(self) -> ControlSystem:
        from nilpotent.models import get_model

        return get_model("trident-snake-paper").specialized()

    def bracket_at_origin(self, sys: ControlSystem, i: int, j: int) -> tuple[sp.Expr, ...]:
        key = (sys.name, i, j)
        cache = self.__dict__.setdefault("_brackets", {})
        if key not in cache:
            f = sys.specialized_fields
            cache[key] = _at_origin(bracket(f[i - 1], f[j - 1], sys.coordinates), sys.coordinates)
        return cache[key]

    @cached_property
    def body_filtration(self):
        from nilpotent.core.filtration import analyze

        return analyze(self.body)

    @cached_property
    def vf_filtration(self):
        from nilpotent.core.filtration import analyze

        return analyze(self.vf)

    @cached_property
    def approximation(self):
        from nilpotent.core.approximation import approximate

        return approximate(self.vf)

    def frame_matrix(self, labels: dict[int, tuple[int, int]], sys: ControlSystem) -> sp.Matrix:
        """Columns ``g1(0) .. g6(0)``, ``g_k = [g_i, g_j]`` as ``labels`` names them."""
        cols = [_at_origin(f, sys.coordinates) for f in sys.specialized_fields]
        cols += [self.bracket_at_origin(sys, *labels[k]) for k in (4, 5, 6)]
        return sp.Matrix(cols).T

    @cached_property
    def paper_y_fields(self) -> tuple[tuple[sp.Expr, ...], ...]:
        """eq. (vf) written in the paper's coordinates ``y = M x`` (exact pushforward)."""
        m = self.paper.privileged_matrix
        inverse = dict(zip(X, list(m.inv() * sp.Matrix(Y)), strict=True))
        return _push(self.vf.specialized_fields, sp.Matrix(m), X, inverse)

    @cached_property
    def paper_y_truncation(self) -> tuple[tuple[sp.Expr, ...], ...]:
        """Terms of weighted degree ``w_j − 1`` of eq. (vf) in the paper's ``y``."""
        w = self.paper.weights
        return tuple(
            tuple(_weighted_part(c, Y, w, w[j] - 1) for j, c in enumerate(f))
            for f in self.paper_y_fields
        )

    @cached_property
    def paper_y_low_terms(self) -> tuple[tuple[sp.Expr, ...], ...]:
        """Terms of weighted degree ``< w_j − 1`` (nonzero only for non-privileged ``y``)."""
        w = self.paper.weights
        return tuple(
            tuple(
                sp.Add(*[_weighted_part(c, Y, w, d) for d in range(w[j] - 1)])
                for j, c in enumerate(f)
            )
            for f in self.paper_y_fields
        )

    def displacement_rate(self, sys: ControlSystem, i: int, j: int) -> tuple[float, ...]:
        """``Δx / (πA²)`` over one period of the ``(i, j)`` periodic input, extrapolated to A → 0.

        One-period simulations (:func:`nilpotent.simulate.simulate`) at
        ``A = 0.02`` and ``0.01`` from the origin (adaptive DOP853, rtol 1e-12);
        since ``Δx/(πA²) = [X_i,X_j](0) + c A + O(A²)``, the Richardson
        combination ``2 r(A/2) − r(A)`` removes the ``O(A)`` term.
        """
        from nilpotent.numeric import compile_system
        from nilpotent.simulate import bracket_signal, simulate

        key = (sys.name, i, j)
        cache = self.__dict__.setdefault("_rates", {})
        if key not in cache:
            compiled = compile_system(sys, backend="numpy")
            rates = []
            for amp in (0.02, 0.01):
                run = simulate(
                    compiled, bracket_signal(sys.m, i, j, amp), samples=2, rtol=1e-12, atol=1e-14
                )
                rates.append(run.final / (math.pi * amp**2))
            cache[key] = tuple(float(v) for v in 2 * rates[1] - rates[0])
        return cache[key]


Check = Callable[[PaperContent, _Computed], Iterable[AuditEntry]]


def _entry(
    id_: str, section: str, statement: str, paper: str, computed: str, ok: bool, why: str
) -> AuditEntry:
    return AuditEntry(id_, section, statement, paper, computed, AGREES if ok else DIFFERS, why)


# --- Sections 1 and 4: the model and its growth ---------------------------------
def _check_growth(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    claim = paper.growth_claim
    body, vf = c.body_filtration, c.vf_filtration
    ok = body.growth_vector == claim and vf.growth_vector == claim and body.bracket_generating
    yield _entry(
        "sec1-growth-vector",
        paper.growth_text.section,
        f"The system is locally controllable and its filtration (growth vector) is {claim} at 0.",
        str(claim),
        f"Section 4 fields: {body.growth_vector}; eq. vf: {vf.growth_vector}",
        ok,
        f"analyze() at the origin: bracket generating, weights {body.weights}"
        if ok
        else "analyze() finds another growth vector",
    )
    generic = (body.generic_growth_vector, vf.generic_growth_vector)
    ok = all(g == claim for g in generic) and body.regular and vf.regular
    yield _entry(
        "sec4-growth-regular",
        "4",
        f"In regular points g1, g2, g3 define a bracket-generating distribution with growth "
        f"vector {claim} (Chow–Rashevsky: controllable).",
        str(claim),
        f"generic growth near 0: Section 4 {generic[0]}, eq. vf {generic[1]}; 0 regular: "
        f"{body.regular and vf.regular}",
        ok,
        "growth vector at random points near the origin (analyze().generic_growth_vector)",
    )


_LEG_ANGLES = (sp.Integer(0), 2 * sp.pi / 3, 4 * sp.pi / 3)


def _check_section4_fields(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    """The paper's g1, g2, g3 against the no-slip constraints and the body-velocity model."""
    x, y, th = X[0], X[1], X[2]
    phis = X[3:]
    rot = sp.Matrix([[sp.cos(th), -sp.sin(th)], [sp.sin(th), sp.cos(th)]])
    for k, printed in enumerate(paper.section4_fields):
        g = printed.components
        residuals = []
        for alpha, phi, idx in zip(_LEG_ANGLES, phis, range(3), strict=True):
            psi = th + alpha + phi
            row = [-sp.sin(psi), sp.cos(psi), sp.cos(phi) + 1, 0, 0, 0]
            row[3 + idx] = 1
            residuals.append(sum(r * gi for r, gi in zip(row, g, strict=True)))
        constraints_ok = all(_vanishes(r) for r in residuals)
        planar = rot * sp.Matrix([1 if k == 0 else 0, 1 if k == 1 else 0])
        inputs_ok = _same((g[0], g[1], g[2]), (planar[0], planar[1], 1 if k == 2 else 0))
        model = c.body.specialized_fields[k]
        model_ok = _same(g, model)
        ok = constraints_ok and inputs_ok and model_ok
        why = (
            "satisfies the 3 no-side-slip constraints (legs at 0, 2π/3, 4π/3; r = l = 1), "
            f"moves the body with body-frame velocity e_{k + 1}, and equals the trident-snake "
            "model"
        )
        if not ok:
            failed = [
                n
                for n, f in (
                    ("constraints", constraints_ok),
                    ("body velocity", inputs_ok),
                    ("model", model_ok),
                )
                if not f
            ]
            why = "fails: " + ", ".join(failed)
        yield _entry(
            f"sec4-field-g{k + 1}",
            printed.section,
            f"Solving the no-slip (Pfaff) constraints for q̇ with body-velocity inputs gives "
            f"g{k + 1} as printed (coordinates x, y, θ, φ1, φ2, φ3 = x1..x6).",
            _printed(printed),
            format_field(model, X),
            ok,
            why,
        )
    del x, y


def _leg_angles_of(fields: Sequence[PrintedField]) -> tuple[sp.Expr, ...] | None:
    """Angles ``a_i`` with ``g1 ∋ sin(x_{3+i} + a_i)``, ``g2 ∋ −cos(x_{3+i} + a_i)``, if any."""
    out = []
    for leg in range(3):
        phi = X[3 + leg]
        for k in range(-6, 7):
            a = k * sp.pi / 3
            if _vanishes(fields[0].components[3 + leg] - sp.sin(phi + a)) and _vanishes(
                fields[1].components[3 + leg] + sp.cos(phi + a)
            ):
                out.append(sp.Mod(a + sp.pi, 2 * sp.pi) - sp.pi)
                break
        else:
            return None
    return tuple(out)


def _check_vf(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    """eq. vf: the Section 4 fields with R_θ removed?  And is it the same system?"""
    for k, printed in enumerate(paper.vf_fields):
        body = c.body.specialized_fields[k]
        removed = tuple(1 if j == k else 0 for j in range(3)) + tuple(body[3:])
        ok = _same(printed.components, removed)
        if ok:
            why = "(ẋ1, ẋ2, ẋ3) = v and the φ-components are Section 4's"
        else:
            vf_angles = _leg_angles_of(paper.vf_fields)
            sec4_angles = _leg_angles_of(paper.section4_fields)
            why = "the planar part is ẇ = v, but the φ-components differ from Section 4's"
            if vf_angles is not None and sec4_angles is not None:
                why += (
                    f": they place the legs at angles {_fmt_vec(vf_angles)} instead of "
                    f"{_fmt_vec(sec4_angles)}"
                )
                shifts = {
                    sp.simplify(sp.Mod(a - b + sp.pi, 2 * sp.pi) - sp.pi)
                    for a, b in zip(vf_angles, sec4_angles, strict=True)
                }
                if len(shifts) == 1:
                    (shift,) = shifts
                    why += (
                        f" (every leg turned by {_fmt(shift)}, i.e. the legs relabelled "
                        "cyclically, while x1, x2 stay in the old body frame; the paper's "
                        "note that parametrisations can vary does not make these the "
                        "same fields)"
                    )
        yield _entry(
            f"sec4-vf-g{k + 1}",
            printed.section,
            f"eq. vf: g{k + 1} is the Section 4 field with the rotation R_θ removed "
            "(ẇ = v, φ̇ = A(φ)v with the same A(φ)).",
            _printed(printed),
            format_field(removed, X),
            ok,
            why,
        )
    # Same system?  Span of the three brackets: involutive for vf, not for Section 4.
    ranks = {}
    for name, sys in (("vf", c.vf), ("Section 4", c.body)):
        f = sys.specialized_fields
        pairs = [(0, 1), (1, 2), (0, 2)]
        brs = [bracket(f[i], f[j], sys.coordinates) for i, j in pairs]
        rng = random.Random(7)
        point = {s: sp.Rational(rng.randint(-60, 60), 37) for s in sys.coordinates}
        vals = [[sp.S(v).subs(point) for v in b] for b in brs]
        extra = []
        for a, b in ((0, 1), (1, 2), (0, 2)):
            bb = bracket(brs[a], brs[b], sys.coordinates)
            extra.append([sp.S(v).subs(point) for v in bb])
        ranks[name] = (_rank(vals), _rank(vals + extra))
    involutive = {name: r[0] == r[1] for name, r in ranks.items()}
    same = involutive["vf"] == involutive["Section 4"]
    yield _entry(
        "sec4-vf-same-system",
        paper.vf_fields[0].section,
        "eq. vf describes the same robot as Section 4's g1, g2, g3 (the simplified form is "
        "used 'for the sake of simplicity').",
        paper.vf_text.text,
        "span{[gi,gj]}: "
        + "; ".join(f"{n}: rank {r[0]}, with its own brackets {r[1]}" for n, r in ranks.items()),
        same,
        "the span of the brackets [gi,gj] is involutive for vf but not for Section 4's fields, "
        "so no change of coordinates maps one system to the other"
        if not same
        else "the bracket spans are both involutive or both not (no obstruction found)",
    )


def _check_liebrackets(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    labels = paper.bracket_labels_sec4
    for printed in paper.bracket_values:
        k = int(printed.name[1:])
        i, j = labels[k]
        ours = c.bracket_at_origin(c.vf, i, j)
        body = c.bracket_at_origin(c.body, i, j)
        ok = _same(printed.components, ours)
        if ok:
            why = (
                f"[g{i},g{j}](0) computed from eq. vf with [X,Y] = DY·X − DX·Y "
                "(the sign the paper's printed brackets follow)"
            )
        else:
            why = f"[g{i},g{j}](0) from eq. vf is {format_field(ours, X)}"
            if _same(printed.components[3:], body[3:]):
                why += (
                    "; the printed value is the φ-part of Section 4's bracket "
                    f"{format_field(body, X)}"
                )
        yield _entry(
            f"sec4-bracket-g{k}",
            printed.section,
            f"eq. liebrackets: g{k} = [g{i},g{j}] at 0, computed from eq. vf.",
            _printed(printed),
            format_field(ours, X),
            ok,
            why,
        )


def _check_motion_claims(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    """Figs 2–4: direction of the root and ratios of the joint angles, Section 4 robot."""
    labels = paper.bracket_labels_sec4
    for claim in paper.motion_claims:
        i, j = labels[claim.bracket]
        b = c.bracket_at_origin(c.body, i, j)
        bv = c.bracket_at_origin(c.vf, i, j)
        rate = c.displacement_rate(c.body, i, j)
        sim_ok = max(abs(r - float(v)) for r, v in zip(rate, b, strict=True)) < 1e-3
        root = {"stays": (0, 0), "x": None, "y": None}
        bx, by = b[0], b[1]
        if claim.root == "stays":
            root_ok = _vanishes(bx) and _vanishes(by)
        elif claim.root == "x":
            root_ok = not _vanishes(bx) and _vanishes(by)
        elif claim.root == "y":
            root_ok = _vanishes(bx) and not _vanishes(by)
        else:
            root_ok = True
        del root
        ratio_ok = claim.ratios is None or _proportional(b[3:], claim.ratios)
        ok = root_ok and ratio_ok and sim_ok

        def where(v: Sequence[sp.Expr]) -> str:
            if _vanishes(v[0]) and _vanishes(v[1]):
                return "root stays"
            return f"root moves by {_fmt_vec(v[:2])}"

        parts = []
        if not root_ok:
            parts.append(f"the root does not move as stated ({where(b)})")
        if not ratio_ok:
            parts.append(
                f"the angles change as {':'.join(_fmt(v) for v in b[3:])}, "
                f"not {':'.join(map(str, claim.ratios or ()))}"
            )
        if not sim_ok:
            parts.append("the simulated displacement does not match the bracket")
        why = (
            "; ".join(parts)
            if parts
            else (f"Section 4 robot: {where(b)}, angles {':'.join(_fmt(v) for v in b[3:])}")
        )
        why += (
            f" (simulated Δq/(πA²) → {_fmt_rate(rate)}); "
            f"with eq. vf: {where(bv)}, angles {':'.join(_fmt(v) for v in bv[3:])}"
        )
        statement = f"Fig. ({claim.figure}), motion of g{claim.bracket} = [g{i},g{j}]: "
        statement += {
            "stays": "the root stays put",
            "x": "the root moves along the x-axis",
            "y": "the root moves along the y-axis",
            None: "",
        }[claim.root]
        if claim.ratios:
            statement += f", the angles change proportionally to {':'.join(map(str, claim.ratios))}"
        yield _entry(
            f"fig-{claim.figure}-motion",
            "4",
            statement + ".",
            claim.text,
            f"[g{i},g{j}](0) = {format_field(b, X)} (Section 4 robot)",
            ok,
            why,
        )


# --- Section 5: privileged coordinates ----------------------------------------
def _check_components(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    for ex in paper.component_examples:
        ours = c.vf.specialized_fields[ex.field - 1][ex.coordinate - 1]
        ok = _vanishes(ex.value - ours)
        yield _entry(
            f"sec5-component-g{ex.field}-x{ex.coordinate}",
            "5",
            f"Example: the x{ex.coordinate}-component of g{ex.field} (eq. vf) is {_fmt(ex.value)}.",
            ex.latex,
            _fmt(ours),
            ok,
            "read off eq. vf"
            if ok
            else f"eq. vf gives [g^{ex.coordinate}_{ex.field}]_x = {_fmt(ours)}",
        )


def _check_privileged(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    m = sp.Matrix(paper.privileged_matrix)
    labels_tried = {
        "Section 4 names": paper.bracket_labels_sec4,
        "Section 7 names": paper.bracket_labels_sec7,
    }
    products = {
        name: sp.simplify(m * c.frame_matrix(lab, c.vf)) for name, lab in labels_tried.items()
    }
    printed = sp.Matrix(
        [
            [_at_origin(f, X)[r] for f in c.vf.specialized_fields]
            + [b.components[r] for b in paper.bracket_values]
            for r in range(6)
        ]
    )
    products["printed eq. liebrackets"] = sp.simplify(m * printed)
    ok_any = [n for n, p in products.items() if p == sp.eye(6)]
    correct = c.frame_matrix(paper.bracket_labels_sec4, c.vf).inv()
    yield _entry(
        "sec5-matrix-condition",
        "5",
        "The linear map y = M x of Section 5 satisfies ∂/∂y_i|_0 = g_i|_0 for i = 1..6 "
        "(g4, g5, g6 the brackets of eq. liebrackets).",
        "M = " + _printed_matrix(paper.privileged_matrix_latex),
        "M must be [g1(0) … g6(0)]⁻¹ = " + _matrix_text(sp.simplify(correct)),
        bool(ok_any),
        ("holds with " + ok_any[0])
        if ok_any
        else "M·[g1(0) … g6(0)] ≠ I with either naming of g5, g6 and with the printed bracket "
        "values; row 4 of M·G(0) is " + _fmt_vec(list(products["Section 4 names"].row(3))),
    )
    g0 = [_at_origin(f, X) for f in c.vf.specialized_fields]
    rows_ok = all(_vanishes(sum(m[r, j] * g[j] for j in range(6))) for r in (3, 4, 5) for g in g0)
    values = [[sp.simplify(sum(m[r, j] * g[j] for j in range(6))) for g in g0] for r in (3, 4, 5)]
    yield _entry(
        "sec5-matrix-weight2-rows",
        "5",
        "Rows 4–6 of M define the weight-2 coordinates: dy4, dy5, dy6 vanish on "
        "g1(0), g2(0), g3(0) (so that y4..y6 have order 2).",
        "rows 4–6 of M: " + "; ".join(_fmt_vec(list(m.row(r))) for r in (3, 4, 5)),
        "dy_r(g_i(0)) for r = 4..6: " + "; ".join(_fmt_vec(v) for v in values),
        rows_ok,
        "the rows annihilate span{g1, g2, g3}(0)"
        if rows_ok
        else "the rows do not vanish on span{g1, g2, g3}(0): y4, y5, y6 have order 1",
    )
    orders = [_linear_order(m.row(r), c) for r in range(6)]
    ok = tuple(orders) == tuple(paper.weights)
    yield _entry(
        "sec5-privileged",
        paper.privileged_text.section,
        f"The coordinates y = M x are privileged at 0: ord_0(y_j) = w_j = {tuple(paper.weights)}.",
        paper.privileged_text.text,
        f"ord_0(y_j) = {tuple(orders)} (eq. vf)",
        ok,
        "non-holonomic orders of the linear functions y_j computed from the fields and their "
        "brackets at 0" + ("" if ok else ": y4, y5, y6 are not of order 2, so y is not privileged"),
    )


def _linear_order(row: sp.Matrix, c: _Computed) -> float:
    """Non-holonomic order at 0 of the linear function ``row · x`` for eq. vf."""
    from nilpotent.core.orders import function_order

    return function_order(c.vf, sum(row[j] * X[j] for j in range(6)), None, 4)


def _field_order(c: _Computed, field: Sequence[sp.Expr]) -> float:
    """Non-holonomic order at 0 of a vector field on eq. vf's space (``MATH.md`` §3).

    In privileged coordinates ``z`` (approximate()'s), ``ord(Z) = min_j ord(Z z_j) − w_j``.
    """
    from nilpotent.core.orders import function_order

    z = c.approximation.coordinates.forward
    weights = c.vf_filtration.weights
    out = math.inf
    for zj, wj in zip(z, weights, strict=True):
        f = sp.expand(sum(sp.S(field[k]) * sp.diff(zj, X[k]) for k in range(6)))
        out = min(out, function_order(c.vf, f, None, wj + 2) - wj)
    return out


def _matrix_text(m: sp.Matrix) -> str:
    return "[" + "; ".join(", ".join(_fmt(v) for v in m.row(r)) for r in range(m.rows)) + "]"


# --- Section 6: the nilpotent approximation -------------------------------------
def _bracket_y(a: Sequence[sp.Expr], b: Sequence[sp.Expr]) -> tuple[sp.Expr, ...]:
    return bracket(a, b, Y)


def _check_weights(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    ours = c.vf_filtration.weights
    yield _entry(
        "sec6-weights",
        "6",
        f"The coordinate weights are {tuple(paper.weights)}.",
        paper.weights_text,
        str(ours),
        tuple(ours) == tuple(paper.weights),
        "weights of the filtration at 0 (analyze)",
    )


def _check_approximation(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    approx = c.approximation
    ours_y = approx.fields
    names = approx.coordinates.names
    for k, printed in enumerate(paper.approximation_y):
        trunc = c.paper_y_truncation[k]
        low = c.paper_y_low_terms[k]
        ok = _same(printed.components, trunc)
        ours_k = [
            sp.S(v).subs(dict(zip(approx.coordinates.names, Y, strict=True))) for v in ours_y[k]
        ]
        if ok:
            why = f"equals the terms of weighted degree w_j − 1 of g{k + 1} in y = M x"
            if _same(printed.components, ours_k):
                why += f" and approximate()'s X̂{k + 1}"
        else:
            why = (
                f"the weighted truncation of g{k + 1} in the paper's y = M x is "
                f"{format_field(trunc, Y)}"
            )
        if any(not _vanishes(v) for v in low):
            why += (
                f"; g{k + 1} also has terms of lower weighted degree in y "
                f"({format_field(low, Y)}), so y is not privileged"
            )
        yield _entry(
            f"sec6-approx-g{k + 1}",
            printed.section,
            f"ĝ{k + 1} (Section 6) is g{k + 1}^(−1), the part of weighted degree −1 of g{k + 1} "
            "written in the coordinates y = M x of Section 5.",
            _printed(printed),
            format_field(trunc, Y),
            ok,
            why,
        )
    # Is the printed family a nilpotent approximation in *some* privileged coordinates?
    # Both families have weight-1 components e_i, weight-2 components linear in y1..y3.
    # Nilpotent approximations in two privileged coordinate systems differ by a graded change
    # y'_{4..6} = L y_{4..6} + q(y1, y2, y3) (q quadratic), under which the weight-2 parts
    # become L·(ours) + grad q and the (constant) brackets L·(ours).  So L is fixed by the
    # brackets, and the printed family is such an approximation iff printed − L·ours is, in
    # each weight-2 component, the gradient of a quadratic (symmetric Jacobian).
    sub = dict(zip(names, Y, strict=True))
    ours_in_y = [[sp.S(v).subs(sub) for v in f] for f in ours_y]
    printed_y = [f.components for f in paper.approximation_y]
    pairs = ((1, 2), (1, 3), (2, 3))

    def bracket_matrix(fields: Sequence[Sequence[sp.Expr]]) -> sp.Matrix:
        cols = [_bracket_y(fields[i - 1], fields[j - 1]) for i, j in pairs]
        return sp.Matrix([[sp.expand(col[r]) for col in cols] for r in range(3, 6)])

    b_printed, b_ours = bracket_matrix(printed_y), bracket_matrix(ours_in_y)
    ok = (
        all(_same(printed_y[k][:3], ours_in_y[k][:3]) for k in range(3))
        and not (b_printed.free_symbols | b_ours.free_symbols)
        and b_ours.det() != 0
        and b_printed.det() != 0
    )
    change = sp.zeros(3, 3)
    if ok:
        change = sp.simplify(b_printed * b_ours.inv())
        rest = [
            sp.Matrix(printed_y[k][3:]) - change * sp.Matrix(ours_in_y[k][3:]) for k in range(3)
        ]
        ok = all(
            _vanishes(sp.diff(rest[a][r], Y[b]) - sp.diff(rest[b][r], Y[a]))
            for r in range(3)
            for a in range(3)
            for b in range(3)
        )
    yield _entry(
        "sec6-approx-family",
        "6",
        "(ĝ1, ĝ2, ĝ3) is a nilpotent approximation of (g1, g2, g3) at 0 in some privileged "
        "coordinates (whatever y is).",
        "; ".join(_printed(f) for f in paper.approximation_y),
        "approximate(): "
        + "; ".join(f"X̂{k + 1} = {format_field(f, names)}" for k, f in enumerate(ours_y)),
        ok,
        (
            "the printed fields equal approximate()'s after the graded change of coordinates "
            f"(y4, y5, y6) → {_matrix_text(change)}·(y4, y5, y6) + quadratics in y1, y2, y3: "
            "a nilpotent approximation, in other privileged coordinates"
        )
        if ok
        else "no homogeneous change of coordinates maps approximate()'s fields to the printed ones",
    )


def _is_form(expr: sp.Expr, degree: int) -> bool:
    """Whether ``expr`` is a homogeneous polynomial of ``degree`` in y1, y2, y3 only."""
    e = sp.expand(sp.S(expr))
    if e == 0:
        return True
    if e.free_symbols - set(Y[:3]):
        return False
    poly = sp.Poly(e, *Y[:3])
    return all(sum(m) == degree for m in poly.monoms())


def _check_homogeneous_form(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    w = paper.weights
    bad = [
        f"{f.name}: {_fmt(v)} along ∂y{j + 1}"
        for f in paper.approximation_y
        for j, v in enumerate(f.components)
        if not _is_form(v, w[j] - 1)
    ]
    yield _entry(
        "sec6-homogeneous-form",
        paper.homogeneous_text.section,
        "In (ĝ1, ĝ2, ĝ3) the ∂y1..∂y3 components are constants and the ∂y4..∂y6 components "
        "are linear forms in y1, y2, y3 (homogeneous of degree −1).",
        paper.homogeneous_text.text,
        "components of the printed ĝ: " + ("all of that form" if not bad else "; ".join(bad)),
        not bad,
        "checked on the printed Section 6 fields (weights (1,1,1,2,2,2))"
        if not bad
        else "some components are not of weighted degree w_j − 1",
    )


def _check_first_order(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    """Read in the paper's y = M x, is the printed ĝ a first-order approximation of vf?"""
    m = sp.Matrix(paper.privileged_matrix)
    forward = dict(zip(Y, list(m * sp.Matrix(X)), strict=True))
    hat_x = _push([f.components for f in paper.approximation_y], m.inv(), Y, forward)
    fields = c.vf.specialized_fields
    printed = [
        _field_order(c, [g - h for g, h in zip(fields[i], hat_x[i], strict=True)]) for i in range(3)
    ]
    ours = [
        _field_order(
            c, [g - h for g, h in zip(fields[i], c.approximation.fields_x[i], strict=True)]
        )
        for i in range(3)
    ]
    ok = all(o >= 0 for o in printed)
    yield _entry(
        "sec6-first-order",
        paper.step_text.section,
        "Read in the coordinates y = M x of Section 5, the printed (ĝ1, ĝ2, ĝ3) is a first-order "
        "approximation of (g1, g2, g3) at 0: every gi − ĝi has order ≥ 0.",
        paper.step_text.text,
        "ord_0(gi − ĝi) = "
        + ", ".join(str(o) for o in printed)
        + "; for approximate()'s X̂i: "
        + ", ".join(str(o) for o in ours),
        ok,
        "orders computed in approximate()'s privileged coordinates (MATH.md §3)"
        + (
            ""
            if ok
            else ": the printed fields, read in the paper's y, are not a first-order "
            "approximation (the remainders are of negative order)"
        ),
    )


def _check_step(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    fields = [f.components for f in paper.approximation_y]
    length2 = [_bracket_y(fields[i], fields[j]) for i, j in ((0, 1), (0, 2), (1, 2))]
    nonzero2 = any(not all(_vanishes(v) for v in b) for b in length2)
    length3 = [_bracket_y(fields[a], b) for a in range(3) for b in length2]
    zero3 = all(all(_vanishes(v) for v in b) for b in length3)
    step = 1 if not nonzero2 else (2 if zero3 else 3)
    cert = c.approximation.certificate.nilpotent_step
    yield _entry(
        "sec6-step",
        paper.step_text.section,
        f"(ĝ1, ĝ2, ĝ3) generates a nilpotent Lie algebra of step r = {paper.step_claim}: all "
        f"brackets of length greater than {paper.step_claim} vanish.",
        paper.step_text.text,
        f"printed ĝ: brackets of length 2 {'nonzero' if nonzero2 else 'zero'}, of length 3 "
        f"{'zero' if zero3 else 'nonzero'} → step {step}; approximate(): step {cert}",
        step == paper.step_claim and cert == paper.step_claim,
        f"e.g. [ĝ1,ĝ2] = {format_field(length2[0], Y)} ≠ 0; the step is the filtration's "
        f"r = {len(paper.growth_claim)}"
        if step != paper.step_claim
        else "computed",
    )


def _check_hat_brackets(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    """Section 6's ĝ4..ĝ6, read with Section 7's naming, where the hatted names are defined.

    The clash with Section 4's naming of g5, g6 is its own entry
    (``sec4-sec7-bracket-names``), so it is not counted twice here.
    """
    fields = [f.components for f in paper.approximation_y]
    labels = paper.bracket_labels_sec7
    for printed in paper.approximation_brackets_y:
        k = int(printed.name[1:])
        i, j = labels[k]
        ours = _bracket_y(fields[i - 1], fields[j - 1])
        ok = _same(printed.components, ours)
        other = [
            kk
            for kk, (a, b) in paper.bracket_labels_sec4.items()
            if _same(printed.components, _bracket_y(fields[a - 1], fields[b - 1]))
        ]
        why = f"[ĝ{i},ĝ{j}] of the printed ĝ (Section 7 defines ĝ{k} = [ĝ{i},ĝ{j}])"
        if not ok and other:
            a, b = paper.bracket_labels_sec4[other[0]]
            why = (
                f"[ĝ{i},ĝ{j}] = {format_field(ours, Y)}; the printed value is [ĝ{a},ĝ{b}], "
                "Section 4's naming"
            )
        yield _entry(
            f"sec6-bracket-g{k}",
            printed.section,
            f"ĝ{k} = [ĝ{i},ĝ{j}] (Section 7's naming) equals "
            f"{format_field(printed.components, Y)}.",
            _printed(printed),
            format_field(ours, Y),
            ok,
            why,
        )


def _check_labels(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    s4, s7 = paper.bracket_labels_sec4, paper.bracket_labels_sec7

    def show(lab: dict[int, tuple[int, int]], hat: str) -> str:
        return ", ".join(f"{hat}{k} = [{hat}{i},{hat}{j}]" for k, (i, j) in sorted(lab.items()))

    ok = s4 == s7
    swapped = [k for k in s4 if s4.get(k) != s7.get(k)]
    yield _entry(
        "sec4-sec7-bracket-names",
        "7",
        "The brackets are named consistently: Section 4's g4, g5, g6 and Section 7's "
        "ĝ4, ĝ5, ĝ6 are the same brackets.",
        f"Section 4: {show(s4, 'g')}; Section 7: {show(s7, 'ĝ')}",
        "the same name for the same bracket in both sections"
        if ok
        else f"names {', '.join(f'g{k}' for k in swapped)} denote different brackets",
        ok,
        "consistent" if ok else "g5 and g6 are swapped between Section 4 and Section 7",
    )


# --- Section 7: the approximation in x and the bracket motions ---------------------
def _check_approximation_x(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    m = sp.Matrix(paper.privileged_matrix)
    minv = m.inv()
    forward = dict(zip(Y, list(m * sp.Matrix(X)), strict=True))
    printed_y = [f.components for f in paper.approximation_y] + [
        f.components for f in paper.approximation_brackets_y
    ]
    own = _push(printed_y, minv, Y, forward)
    approx = c.approximation
    ours_x = list(approx.fields_x)
    labels = paper.bracket_labels_sec7
    for k in (4, 5, 6):
        i, j = labels[k]
        ours_x.append(c.bracket_at_origin(c.vf, i, j))
    for k, printed in enumerate(paper.approximation_x):
        own_ok = _same(printed.components, own[k])
        ours_ok = _same(printed.components, ours_x[k])
        ok = own_ok or ours_ok
        name = f"ĝ{k + 1}"
        what = (
            "the correct approximation's field"
            if k < 3
            else f"the bracket [g{labels[k + 1][0]},g{labels[k + 1][1]}](0)"
        )
        if own_ok and ours_ok:
            why = "equals both the pushforward of Section 6 by M⁻¹ and " + what
        elif own_ok:
            why = "equals the pushforward of the Section 6 field by the paper's M⁻¹"
        elif ours_ok:
            why = (
                f"equals {what} (approximate()), but not the pushforward of Section 6's "
                f"{name} by the paper's M⁻¹ ({format_field(own[k], X)})"
            )
        else:
            why = (
                f"neither the pushforward of Section 6's {name} by M⁻¹ "
                f"({format_field(own[k], X)}) nor {what} ({format_field(ours_x[k], X)})"
            )
        yield _entry(
            f"sec7-approx-x-g{k + 1}",
            printed.section,
            f"{name} written in the coordinates x1..x6 (Section 7).",
            _printed(printed),
            format_field(ours_x[k], X),
            ok,
            why,
        )


def _check_motions_coincide(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    labels = paper.bracket_labels_sec7
    printed_hat = {
        int(f.name[1:]): f.components for f in paper.approximation_x if int(f.name[1:]) >= 4
    }
    printed_orig = {int(f.name[1:]): f.components for f in paper.bracket_values}
    # With the paper's own printed values (Section 7's ĝk vs the bracket it names).
    mismatched = []
    for k, (i, j) in sorted(labels.items()):
        s4_name = next(kk for kk, p in paper.bracket_labels_sec4.items() if p == (i, j))
        if not _same(printed_hat[k], printed_orig[s4_name]):
            mismatched.append(
                f"ĝ{k} = [ĝ{i},ĝ{j}] is printed {format_field(printed_hat[k], X)} "
                f"but g{s4_name} = [g{i},g{j}] is {format_field(printed_orig[s4_name], X)}"
            )
    yield _entry(
        "sec7-motions-coincide-printed",
        paper.brackets_coincide_text.section,
        "With the printed values, the bracket fields ĝ4, ĝ5, ĝ6 (Section 7) equal the original "
        "brackets g4, g5, g6 at 0 (eq. liebrackets).",
        paper.brackets_coincide_text.text,
        "; ".join(mismatched) if mismatched else "all three printed pairs equal",
        not mismatched,
        "the paper's own Section 7 values contradict its claim"
        if mismatched
        else "the printed values agree",
    )
    # The claim as mathematics: brackets of the approximation at 0 = brackets of g at 0.
    approx = c.approximation
    names = approx.coordinates.names
    jac = sp.Matrix([[sp.diff(xf, yv) for yv in names] for xf in approx.coordinates.inverse])
    at0 = {yv: 0 for yv in names}
    rows = []
    ok = True
    for i, j in ((1, 2), (1, 3), (2, 3)):
        hat = bracket(approx.fields[i - 1], approx.fields[j - 1], names)
        hat_x = jac.subs(at0) * sp.Matrix([sp.S(v).subs(at0) for v in hat])
        orig = c.bracket_at_origin(c.vf, i, j)
        same = _same(list(hat_x), orig)
        ok = ok and same
        rows.append(f"[X̂{i},X̂{j}](0) = {format_field([sp.simplify(v) for v in hat_x], X)}")
    yield _entry(
        "sec7-motions-coincide",
        paper.brackets_coincide_text.section,
        "The Lie bracket motions of the nilpotent approximation at 0 coincide with the original "
        "ones: [ĝi,ĝj](0) = [gi,gj](0).",
        paper.brackets_coincide_text.text,
        "; ".join(rows),
        ok,
        "holds for the approximation approximate() builds (brackets pushed to x at 0)"
        if ok
        else "the brackets of approximate()'s fields differ from the original ones at 0",
    )


def _input_pair(components: Sequence[sp.Expr]) -> tuple[int, int] | None:
    sin_part = -A * OMEGA * sp.sin(OMEGA * T)
    cos_part = A * OMEGA * sp.cos(OMEGA * T)
    i = [k for k, v in enumerate(components) if _vanishes(v - sin_part)]
    j = [k for k, v in enumerate(components) if _vanishes(v - cos_part)]
    zero = [k for k, v in enumerate(components) if _vanishes(v)]
    if len(i) == 1 and len(j) == 1 and len(zero) == len(components) - 2:
        return i[0] + 1, j[0] + 1
    return None


def _check_inputs(paper: PaperContent, c: _Computed) -> Iterable[AuditEntry]:
    labels7 = paper.bracket_labels_sec7
    for inp, target in zip(paper.periodic_inputs, paper.periodic_targets, strict=True):
        pair = _input_pair(inp.components)
        if pair is None:
            yield _entry(
                f"sec7-input-{inp.name.replace('_', '')}",
                "7",
                f"{inp.name} is a periodic bracket input.",
                f"{inp.name}(t) = {inp.latex}",
                "not of the form (−Aω sin ωt, Aω cos ωt) on two inputs",
                False,
                "unrecognised input",
            )
            continue
        i, j = pair
        realised = next((k for k, p in labels7.items() if p == (i, j)), None)
        rate = c.displacement_rate(c.vf, i, j)
        expected = c.bracket_at_origin(c.vf, i, j)
        sim_ok = max(abs(r - float(v)) for r, v in zip(rate, expected, strict=True)) < 1e-3
        target_pair = labels7[target]
        ok = (i, j) == target_pair and sim_ok
        label_k = inp.label.rsplit("input", 1)[-1]
        why = (
            f"u{i} = −Aω sin ωt, u{j} = Aω cos ωt moves the state by πA²[g{i},g{j}](0) "
            f"(simulated Δx/(πA²) → {_fmt_rate(rate)})"
        )
        if (i, j) != target_pair:
            why += (
                f": it realises ĝ{realised} = [ĝ{i},ĝ{j}], not ĝ{target} = "
                f"[ĝ{target_pair[0]},ĝ{target_pair[1]}]"
            )
            if label_k == str(realised):
                why += f" (its equation label {inp.label} names the right bracket)"
        yield _entry(
            f"sec7-input-{inp.name.replace('_', '')}",
            "7",
            f"The periodic input {inp.name} (listed for ĝ{target} = "
            f"[ĝ{target_pair[0]},ĝ{target_pair[1]}], 'respectively'; label {inp.label}) "
            f"realises ĝ{target}.",
            f"{inp.name}(t) = {inp.latex}",
            f"realises [g{i},g{j}] = ĝ{realised} (Section 7's naming)",
            ok,
            why,
        )


#: The checks, in the order of the paper.
CHECKS: tuple[tuple[str, Check], ...] = (
    ("growth vector", _check_growth),
    ("Section 4 fields", _check_section4_fields),
    ("eq. vf", _check_vf),
    ("eq. liebrackets", _check_liebrackets),
    ("Figs 2-4 motions", _check_motion_claims),
    ("Section 5 components", _check_components),
    ("privileged coordinates", _check_privileged),
    ("weights", _check_weights),
    ("nilpotent approximation", _check_approximation),
    ("homogeneous form", _check_homogeneous_form),
    ("first order", _check_first_order),
    ("nilpotency step", _check_step),
    ("brackets of the approximation", _check_hat_brackets),
    ("bracket names", _check_labels),
    ("approximation in x", _check_approximation_x),
    ("bracket motions coincide", _check_motions_coincide),
    ("periodic inputs", _check_inputs),
)


def run_audit(
    paper: PaperContent | None = None,
    *,
    only: Collection[str] | None = None,
    progress: Callable[[str], None] | None = None,
) -> Audit:
    """Check every statement of the paper by computation.

    Parameters
    ----------
    paper:
        The parsed paper (default: :func:`read_paper` of the shipped source).
    only:
        Run only these groups of checks (names of :data:`CHECKS`); default all.
    progress:
        Called with the name of each group of checks before it runs.

    Returns
    -------
    Audit
        One :class:`AuditEntry` per checked statement, in the paper's order.
    """
    content = read_paper() if paper is None else paper
    known = [name for name, _ in CHECKS]
    unknown = sorted(set(only or ()) - set(known))
    if unknown:
        raise OptionError(f"unknown audit checks {unknown}; known: {', '.join(known)}")
    computed = _Computed(content)
    entries: list[AuditEntry] = []
    for name, check in CHECKS:
        if only is not None and name not in only:
            continue
        if progress is not None:
            progress(name)
        entries.extend(check(content, computed))
    ids = [e.id for e in entries]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise RuntimeError(f"duplicate audit ids: {dup}")
    return Audit(tuple(entries), content.source_sha256)
