"""Sections 1 and 4 of the paper: the model, its growth, eq. vf, brackets, Figs 2–4."""

from __future__ import annotations

import random
from collections.abc import Iterable, Sequence

import sympy as sp

from nilpotent.core.decide import rank
from nilpotent.core.lie.brackets import bracket
from nilpotent.core.model.expressions import as_expr
from nilpotent.report.audit.compare import (
    fmt,
    fmt_rate,
    fmt_vec,
    format_field,
    printed_field,
    proportional,
    same_exprs,
    vanishes_identically,
)
from nilpotent.report.audit.computed import Computed
from nilpotent.report.audit.entries import AuditEntry, make_entry
from nilpotent.report.paper import PaperContent, PrintedField, X


def check_growth(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    claim = paper.growth_claim
    body, vf = c.body_filtration, c.vf_filtration
    same = body.growth_vector == claim and vf.growth_vector == claim
    ok = same and body.bracket_generating is True
    yield make_entry(
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
    ok = all(g == claim for g in generic) and body.regular is True and vf.regular is True
    yield make_entry(
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


def check_section4_fields(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
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
        constraints_ok = all(vanishes_identically(r) for r in residuals)
        planar = rot * sp.Matrix([1 if k == 0 else 0, 1 if k == 1 else 0])
        inputs_ok = same_exprs((g[0], g[1], g[2]), (planar[0], planar[1], 1 if k == 2 else 0))
        model = c.body.specialized_fields[k]
        model_ok = same_exprs(g, model)
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
        yield make_entry(
            f"sec4-field-g{k + 1}",
            printed.section,
            f"Solving the no-slip (Pfaff) constraints for q̇ with body-velocity inputs gives "
            f"g{k + 1} as printed (coordinates x, y, θ, φ1, φ2, φ3 = x1..x6).",
            printed_field(printed),
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
            if vanishes_identically(
                fields[0].components[3 + leg] - sp.sin(phi + a)
            ) and vanishes_identically(fields[1].components[3 + leg] + sp.cos(phi + a)):
                out.append(sp.Mod(a + sp.pi, 2 * sp.pi) - sp.pi)
                break
        else:
            return None
    return tuple(out)


def check_vf(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    """eq. vf: the Section 4 fields with R_θ removed?  And is it the same system?"""
    for k, printed in enumerate(paper.vf_fields):
        body = c.body.specialized_fields[k]
        removed = tuple(1 if j == k else 0 for j in range(3)) + tuple(body[3:])
        ok = same_exprs(printed.components, removed)
        if ok:
            why = "(ẋ1, ẋ2, ẋ3) = v and the φ-components are Section 4's"
        else:
            vf_angles = _leg_angles_of(paper.vf_fields)
            sec4_angles = _leg_angles_of(paper.section4_fields)
            why = "the planar part is ẇ = v, but the φ-components differ from Section 4's"
            if vf_angles is not None and sec4_angles is not None:
                why += (
                    f": they place the legs at angles {fmt_vec(vf_angles)} instead of "
                    f"{fmt_vec(sec4_angles)}"
                )
                shifts = {
                    sp.simplify(sp.Mod(a - b + sp.pi, 2 * sp.pi) - sp.pi)
                    for a, b in zip(vf_angles, sec4_angles, strict=True)
                }
                if len(shifts) == 1:
                    (shift,) = shifts
                    why += (
                        f" (every leg turned by {fmt(shift)}, i.e. the legs relabelled "
                        "cyclically, while x1, x2 stay in the old body frame; the paper's "
                        "note that parametrisations can vary does not make these the "
                        "same fields)"
                    )
        yield make_entry(
            f"sec4-vf-g{k + 1}",
            printed.section,
            f"eq. vf: g{k + 1} is the Section 4 field with the rotation R_θ removed "
            "(ẇ = v, φ̇ = A(φ)v with the same A(φ)).",
            printed_field(printed),
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
        vals = [[as_expr(v).subs(list(point.items())) for v in b] for b in brs]
        extra = []
        for a, b in ((0, 1), (1, 2), (0, 2)):
            bb = bracket(brs[a], brs[b], sys.coordinates)
            extra.append([as_expr(v).subs(list(point.items())) for v in bb])
        ranks[name] = (
            rank(vals, probabilistic=True)[0], rank(vals + extra, probabilistic=True)[0]
        )
    involutive = {name: r[0] == r[1] for name, r in ranks.items()}
    same = involutive["vf"] == involutive["Section 4"]
    yield make_entry(
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


def check_liebrackets(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
    labels = paper.bracket_labels_sec4
    for printed in paper.bracket_values:
        k = int(printed.name[1:])
        i, j = labels[k]
        ours = c.bracket_at_origin(c.vf, i, j)
        body = c.bracket_at_origin(c.body, i, j)
        ok = same_exprs(printed.components, ours)
        if ok:
            why = (
                f"[g{i},g{j}](0) computed from eq. vf with [X,Y] = DY·X − DX·Y "
                "(the sign the paper's printed brackets follow)"
            )
        else:
            why = f"[g{i},g{j}](0) from eq. vf is {format_field(ours, X)}"
            if same_exprs(printed.components[3:], body[3:]):
                why += (
                    "; the printed value is the φ-part of Section 4's bracket "
                    f"{format_field(body, X)}"
                )
        yield make_entry(
            f"sec4-bracket-g{k}",
            printed.section,
            f"eq. liebrackets: g{k} = [g{i},g{j}] at 0, computed from eq. vf.",
            printed_field(printed),
            format_field(ours, X),
            ok,
            why,
        )


def check_motion_claims(paper: PaperContent, c: Computed) -> Iterable[AuditEntry]:
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
            root_ok = vanishes_identically(bx) and vanishes_identically(by)
        elif claim.root == "x":
            root_ok = not vanishes_identically(bx) and vanishes_identically(by)
        elif claim.root == "y":
            root_ok = vanishes_identically(bx) and not vanishes_identically(by)
        else:
            root_ok = True
        del root
        ratio_ok = claim.ratios is None or proportional(b[3:], claim.ratios)
        ok = root_ok and ratio_ok and sim_ok

        def where(v: Sequence[sp.Expr]) -> str:
            if vanishes_identically(v[0]) and vanishes_identically(v[1]):
                return "root stays"
            return f"root moves by {fmt_vec(v[:2])}"

        parts = []
        if not root_ok:
            parts.append(f"the root does not move as stated ({where(b)})")
        if not ratio_ok:
            parts.append(
                f"the angles change as {':'.join(fmt(v) for v in b[3:])}, "
                f"not {':'.join(map(str, claim.ratios or ()))}"
            )
        if not sim_ok:
            parts.append("the simulated displacement does not match the bracket")
        why = (
            "; ".join(parts)
            if parts
            else (f"Section 4 robot: {where(b)}, angles {':'.join(fmt(v) for v in b[3:])}")
        )
        why += (
            f" (simulated Δq/(πA²) → {fmt_rate(rate)}); "
            f"with eq. vf: {where(bv)}, angles {':'.join(fmt(v) for v in bv[3:])}"
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
        yield make_entry(
            f"fig-{claim.figure}-motion",
            "4",
            statement + ".",
            claim.text,
            f"[g{i},g{j}](0) = {format_field(b, X)} (Section 4 robot)",
            ok,
            why,
        )
