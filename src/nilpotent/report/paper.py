r"""The paper's printed statements, read from its LaTeX source at run time.

The paper (Hrdina, Návrat, Vašík, *Nilpotent approximation of a trident snake
robot controlling distribution*) ships with the package as
``nilpotent/report/assets/paper.tex``.  :func:`read_paper` locates each
checkable formula in that source (by its ``\label``, or by the unique text
around it), translates it with :mod:`nilpotent.report.latexmath` into the
expression grammar and parses it with
:func:`nilpotent.core.model.expressions.parse_expression`.  The audit
(:mod:`nilpotent.report.audit`) compares these printed values with computed
ones; nothing here decides whether the paper is right.

Coordinates: the paper's Section 3 fixes ``q = (x, y, θ, φ1, φ2, φ3) =:
(x1, ..., x6)``; every field read here is returned as a tuple of components
along ``x1..x6`` (or ``y1..y6`` for the privileged coordinates of Sections 5–6),
in that order.  ``[g^i_k]_x`` is, as in the paper, the ``i``-th component of
``g_k``.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from functools import cache
from importlib import resources

import sympy as sp

from nilpotent.core.model.expressions import parse_expression
from nilpotent.errors import ExpressionError
from nilpotent.report.latexmath import (
    PARTIAL_PREFIX,
    latex_to_grammar,
    split_top_level,
    strip_layout,
    vector_field_to_grammar,
)

__all__ = [
    "ComponentClaim",
    "MotionClaim",
    "PaperContent",
    "PeriodicInput",
    "PrintedField",
    "TextClaim",
    "paper_source",
    "read_paper",
]

#: The model coordinates x1..x6 (= x, y, θ, φ1, φ2, φ3) and privileged y1..y6.
X = sp.symbols("x1:7")
Y = sp.symbols("y1:7")
A, OMEGA, T = sp.symbols("A omega t")

_X_LATEX = {f"x_{i}": f"x{i}" for i in range(1, 7)}
_Y_LATEX = {f"y_{i}": f"y{i}" for i in range(1, 7)}
# Section 4 writes the coordinates as (x, y, θ, φ1, φ2, φ3) = (x1, ..., x6).
_Q_LATEX = {
    "x": "x1",
    "y": "x2",
    r"\theta": "x3",
    r"\phi_1": "x4",
    r"\phi_2": "x5",
    r"\phi_3": "x6",
}
_INPUT_LATEX = {"A": "A", r"\omega": "omega", "t": "t"}


@dataclass(frozen=True)
class PrintedField:
    """A vector field as printed: its name, LaTeX, section and components.

    ``components[j]`` is the component along the ``j``-th coordinate of
    ``coordinates`` (``x1..x6`` or ``y1..y6``).
    """

    name: str
    latex: str
    section: str
    coordinates: tuple[sp.Symbol, ...]
    components: tuple[sp.Expr, ...]


@dataclass(frozen=True)
class ComponentClaim:
    """A printed single component ``[g^i_k]_x = value`` (Section 5's examples)."""

    field: int  # k
    coordinate: int  # i (1-based)
    latex: str
    value: sp.Expr


@dataclass(frozen=True)
class PeriodicInput:
    """A periodic input ``v_k(t)`` of Section 7 with its LaTeX label."""

    name: str
    label: str
    latex: str
    components: tuple[sp.Expr, ...]  # functions of A, omega, t


@dataclass(frozen=True)
class MotionClaim:
    """What the text says a bracket motion of Figs 2–4 does.

    ``root`` is ``"stays"`` (the body centre does not move), ``"x"`` or ``"y"``
    (it moves along that axis); ``ratios`` are the printed ``a:b:c`` of the
    joint-angle changes, or ``None`` where the text gives none.
    """

    figure: str  # LaTeX label of the figure
    bracket: int  # k of the g_k whose realization the figure shows
    text: str
    root: str | None
    ratios: tuple[int, ...] | None


@dataclass(frozen=True)
class TextClaim:
    """A statement in words, with the sentence it is made in."""

    section: str
    text: str


@dataclass(frozen=True)
class PaperContent:
    """Every checkable printed statement of the paper, parsed.

    Attributes are named after where they are printed; fields are tuples of
    :class:`PrintedField` in the printed order.
    """

    source_sha256: str
    section4_fields: tuple[PrintedField, ...]  # g1..g3 of Section 4, in x1..x6
    vf_fields: tuple[PrintedField, ...]  # eq. (vf)
    bracket_labels_sec4: dict[int, tuple[int, int]]  # 4 -> (1, 2): g4 = [g1, g2]
    bracket_values: tuple[PrintedField, ...]  # eq. (liebrackets), values at 0
    component_examples: tuple[ComponentClaim, ...]  # Section 5: [g^i_k]_x = ...
    privileged_matrix: sp.ImmutableMatrix  # Section 5: y = M x
    privileged_matrix_latex: str
    weights: tuple[int, ...]  # Section 6: "the coordinate weights are (...)"
    weights_text: str
    approximation_y: tuple[PrintedField, ...]  # Section 6: ĝ1..ĝ3 in y
    approximation_brackets_y: tuple[PrintedField, ...]  # Section 6: ĝ4..ĝ6 in y
    approximation_x: tuple[PrintedField, ...]  # Section 7: ĝ1..ĝ6 in x
    bracket_labels_sec7: dict[int, tuple[int, int]]  # 5 -> (1, 3): ĝ5 = [ĝ1, ĝ3]
    periodic_inputs: tuple[PeriodicInput, ...]
    periodic_targets: tuple[int, ...]  # "for ĝ4, ĝ5, ĝ6, respectively"
    growth_claim: tuple[int, ...]
    growth_text: TextClaim
    step_claim: int
    step_text: TextClaim
    motion_claims: tuple[MotionClaim, ...]
    brackets_coincide_text: TextClaim
    privileged_text: TextClaim
    vf_text: TextClaim
    homogeneous_text: TextClaim


@cache
def paper_source() -> str:
    """The LaTeX source of the paper shipped in ``nilpotent/report/assets/paper.tex``."""
    return resources.files("nilpotent.report").joinpath("assets/paper.tex").read_text("utf-8")


# --- locating things in the source --------------------------------------------
def _section_at(source: str, position: int) -> str:
    """The number of the ``\\section`` that contains ``position`` (as printed)."""
    return str(len(re.findall(r"\\section\{", source[:position])))


def _find(source: str, pattern: str, what: str, flags: int = re.S) -> re.Match[str]:
    match = re.search(pattern, source, flags)
    if match is None:
        raise ExpressionError(f"the paper's source has no {what} (pattern {pattern!r})")
    return match


def _environment_after(source: str, marker: str, env: str, what: str) -> tuple[str, int]:
    """Body of the first ``\\begin{env}`` at or after the text ``marker``."""
    start = source.find(marker)
    if start < 0:
        raise ExpressionError(f"the paper's source has no {what} (marker {marker!r})")
    m = _find(
        source[start:],
        rf"\\begin\{{{re.escape(env)}\}}(.*?)\\end\{{{re.escape(env)}\}}",
        what,
    )
    return m.group(1), start + m.start(1)


def _aligned_lines(body: str) -> list[tuple[str, str]]:
    """``(left, right)`` of each ``left &= right`` line; continuation lines are joined."""
    body = re.sub(r"\\(?:begin|end)\{aligned\}", "", body)
    body = re.sub(r"\\label\{[^}]*\}", "", body)
    lines: list[tuple[str, str]] = []
    for raw in body.split(r"\\"):
        text = strip_layout(raw).strip()
        if not text:
            continue
        text = text.rstrip(",.").strip()
        if "=" in text:
            left, right = text.split("=", 1)
            if left.strip():
                lines.append((left.strip(), right.strip()))
                continue
            text = right
        if not lines:
            raise ExpressionError(f"continuation line without a start: {raw!r}")
        left, right = lines[-1]
        lines[-1] = (left, f"{right} {text.strip()}")
    return lines


def _parse_field(
    name: str, latex: str, section: str, coords: tuple[sp.Symbol, ...], symbols: dict[str, str]
) -> PrintedField:
    grammar = vector_field_to_grammar(latex, symbols)
    placeholders = {PARTIAL_PREFIX + str(c): sp.Symbol(PARTIAL_PREFIX + str(c)) for c in coords}
    names: dict[str, sp.Basic] = {str(c): c for c in coords}
    names.update(placeholders)
    expr = sp.expand(parse_expression(grammar, names, where=f"paper: {name}"))
    comps = tuple(expr.coeff(placeholders[PARTIAL_PREFIX + str(c)]) for c in coords)
    rest = sp.expand(expr - sum(c * p for c, p in zip(comps, placeholders.values(), strict=True)))
    if rest != 0:
        raise ExpressionError(f"paper: {name} is not a vector field: leftover {rest}")
    return PrintedField(name, latex.strip(), section, coords, comps)


def _field_name(left: str) -> str:
    m = re.fullmatch(r"(\\hat\s*)?g_\{?(\d)\}?", left.replace(" ", ""))
    if m is None:
        m = re.fullmatch(r"(\\hat)g_\{?(\d)\}?", left.replace(" ", ""))
    if m is None:
        raise ExpressionError(f"paper: unexpected left-hand side {left!r}")
    return ("ĝ" if m.group(1) else "g") + m.group(2)


def _fields_in(
    source: str, body: str, offset: int, coords: tuple[sp.Symbol, ...], symbols: dict[str, str]
) -> tuple[PrintedField, ...]:
    section = _section_at(source, offset)
    return tuple(
        _parse_field(_field_name(left), right, section, coords, symbols)
        for left, right in _aligned_lines(body)
    )


def _bracket_labels(text: str, hat: bool) -> dict[int, tuple[int, int]]:
    h = r"\\hat\s*" if hat else ""
    pattern = rf"{h}g_\{{?(\d)\}}?\s*=\s*\[\s*{h}g_(\d)\s*,\s*{h}g_(\d)\s*\]"
    return {int(k): (int(i), int(j)) for k, i, j in re.findall(pattern, text)}


def _parse_matrix(body: str) -> sp.ImmutableMatrix:
    rows = []
    for raw in body.split(r"\\"):
        if not raw.strip():
            continue
        cells = split_top_level(raw, "&")
        rows.append(
            [
                parse_expression(latex_to_grammar(c, {}), {}, where="paper: Section 5 matrix")
                for c in cells
            ]
        )
    return sp.ImmutableMatrix(rows)


def _parse_tuple(latex: str, where: str) -> tuple[sp.Expr, ...]:
    inner = latex.strip()
    if not (inner.startswith("(") and inner.endswith(")")):
        raise ExpressionError(f"paper: {where} is not a tuple: {latex!r}")
    names: dict[str, sp.Basic] = {"A": A, "omega": OMEGA, "t": T}
    return tuple(
        parse_expression(latex_to_grammar(piece, _INPUT_LATEX), names, where=f"paper: {where}")
        for piece in split_top_level(inner[1:-1], ",")
    )


_SENTENCE_END = re.compile(r"(?<!i\.e)(?<!e\.g)\.(?=\s|$)|\n\s*\n|\$\$")


def _sentence(source: str, pattern: str, what: str) -> TextClaim:
    """The sentence around the first match of ``pattern``, LaTeX commands for layout removed."""
    m = _find(source, pattern, what)
    ends_before = [e.end() for e in _SENTENCE_END.finditer(source, 0, m.start())]
    start = ends_before[-1] if ends_before else 0
    after = _SENTENCE_END.search(source, m.end())
    end = after.end() if after else len(source)
    text = re.sub(r"\\(?:begin|end|label)\{[^}]*\}", " ", source[start:end])
    text = re.sub(r"\s+", " ", text).strip()
    return TextClaim(_section_at(source, m.start()), text)


def _motion_claims(source: str) -> tuple[MotionClaim, ...]:
    captions = {
        label: int(k)
        for k, label in re.findall(
            r"\\caption\{Realization of \$g_(\d)\$ motion\}\\label\{(\w+)\}", source
        )
    }
    start = _find(source, r"Note that the trajectories on Fig\.", "the Figs 2-4 discussion").start()
    end = source.find(r"\begin{figure}", start)
    text = source[start:end]
    refs = list(re.finditer(r"Fig\.\s*\\ref\{(\w+)\}", text))
    claims = []
    for n, ref in enumerate(refs):
        piece = text[ref.start() : refs[n + 1].start() if n + 1 < len(refs) else len(text)]
        label = ref.group(1)
        if label not in captions:
            continue
        root: str | None = None
        if "root stays put" in piece:
            root = "stays"
        else:
            axis = re.search(r"root moves along the \$(\w)\$", piece)
            root = axis.group(1) if axis else None
        ratio = re.search(r"proportionally to\s*(-?\d+(?::-?\d+)+)", piece)
        ratios = tuple(int(v) for v in ratio.group(1).split(":")) if ratio else None
        claims.append(
            MotionClaim(label, captions[label], re.sub(r"\s+", " ", piece).strip(), root, ratios)
        )
    return tuple(claims)


def _component_examples(source: str) -> tuple[ComponentClaim, ...]:
    m = _find(source, r"Then e\.g\.\s*\$(.*?)\$ etc", "Section 5's component examples")
    out = []
    names: dict[str, sp.Basic] = {str(s): s for s in X}
    for piece in re.split(r",\\\s*", m.group(1)):
        cm = re.fullmatch(r"\s*\[g(?:\^(\d)_(\d)|_(\d)\^(\d))\]_x\s*=\s*(.+?)\s*", piece, re.S)
        if cm is None:
            raise ExpressionError(f"paper: unreadable component example {piece!r}")
        if cm.group(1):
            coord, field = int(cm.group(1)), int(cm.group(2))
        else:
            field, coord = int(cm.group(3)), int(cm.group(4))
        value = parse_expression(
            latex_to_grammar(cm.group(5), _X_LATEX), names, where="paper: Section 5"
        )
        out.append(ComponentClaim(field, coord, piece.strip(), value))
    return tuple(out)


def read_paper(source: str | None = None) -> PaperContent:
    """Parse every checkable printed statement of the paper's LaTeX ``source``.

    Parameters
    ----------
    source:
        The LaTeX text; default: the copy shipped with the package
        (:func:`paper_source`).

    Raises
    ------
    nilpotent.errors.ExpressionError
        If a formula cannot be found or read (the source changed).
    """
    src = paper_source() if source is None else source
    sha = hashlib.sha256(src.encode()).hexdigest()

    body, off = _environment_after(
        src, r"spanned by vector fields $g_1, g_2, g_3$", "align*", "Section 4 fields"
    )
    sec4 = _fields_in(src, body, off, X, _Q_LATEX)

    m = _find(src, r"\\begin\{equation\}\\label\{vf\}(.*?)\\end\{equation\}", "eq. (vf)")
    vf = _fields_in(src, m.group(1), m.start(1), X, _X_LATEX)

    labels_text = _find(src, r"denote them by (.*?)\. Their", "the Section 4 bracket names")
    labels4 = _bracket_labels(labels_text.group(1), hat=False)

    m = _find(src, r"\\label\{liebrackets\}(.*?)\\end\{equation\}", "eq. (liebrackets)")
    brackets = _fields_in(src, m.group(1), m.start(1), X, _X_LATEX)

    examples = _component_examples(src)

    m = _find(src, r"\\begin\{pmatrix\}\s*\\phantom(.*?)\\end\{pmatrix\}", "the Section 5 matrix")
    matrix_body = r"\phantom" + m.group(1)
    matrix = _parse_matrix(matrix_body)

    wm = _find(src, r"coordinate weights are \$\(([\d,\s]+)\)\$", "the weights of Section 6")
    weights = tuple(int(v) for v in wm.group(1).split(","))

    body, off = _environment_after(
        src,
        "In our case, we obtain the following vector fields",
        "align*",
        "Section 6 approximation",
    )
    approx_y = _fields_in(src, body, off, Y, _Y_LATEX)
    body, off = _environment_after(
        src, "the coordinates of $(\\hat g_4", "align*", "Section 6 brackets"
    )
    approx_br_y = _fields_in(src, body, off, Y, _Y_LATEX)
    body, off = _environment_after(
        src,
        "in $(x_1,x_2,x_3,x_4,x_5,x_6)$ coordinates are of the form",
        "aligned",
        "Section 7 fields in x",
    )
    approx_x = _fields_in(src, body, off, X, _X_LATEX)

    m = _find(src, r"for the vector fields \$(.*?)\$,?\s*respectively", "the Section 7 pairing")
    labels7 = _bracket_labels(m.group(1), hat=True)
    targets = tuple(int(k) for k in re.findall(r"\\hat\s*g_(\d)\s*=", m.group(1)))

    body, _ = _environment_after(src, r"respectively, the input", "align", "the periodic inputs")
    inputs = []
    for raw in body.split(r"\\"):
        if not raw.strip():
            continue
        lm = _find(raw, r"\\label\{(\w+)\}", "a periodic input label")
        left, right = raw.split("&=", 1)
        right = re.sub(r"\\label\{\w+\}", "", right).strip()
        name = re.sub(r"[\s{}]", "", left.split("(")[0])
        inputs.append(PeriodicInput(name, lm.group(1), right, _parse_tuple(right, name)))

    gm = _find(src, r"the filtration is \$\((\d+),\s*(\d+)\)\$", "the growth claim")
    growth = (int(gm.group(1)), int(gm.group(2)))
    growth_text = _sentence(src, r"the filtration is \$\(", "the growth claim")
    sm = _find(src, r"nilpotent Lie algebra of step \$r=(\d+)\$", "the step claim")
    step_text = _sentence(src, r"nilpotent Lie algebra of step", "the step claim")
    coincide = _sentence(src, r"Lie bracket motions at 0 correspond exactly", "Section 7 claim")
    privileged = _sentence(src, r"are clearly the privileged ones", "Section 5 claim")
    vf_text = _sentence(src, r"We shall use this form", "the use of eq. (vf)")
    homogeneous = _sentence(
        src, r"coordinate functions of \$g_1\^\{\(-1\)\}", "Section 6 form of the g^(-1)"
    )

    return PaperContent(
        source_sha256=sha,
        section4_fields=sec4,
        vf_fields=vf,
        bracket_labels_sec4=labels4,
        bracket_values=brackets,
        component_examples=examples,
        privileged_matrix=matrix,
        privileged_matrix_latex=matrix_body.strip(),
        weights=weights,
        weights_text=wm.group(0),
        approximation_y=approx_y,
        approximation_brackets_y=approx_br_y,
        approximation_x=approx_x,
        bracket_labels_sec7=labels7,
        periodic_inputs=tuple(inputs),
        periodic_targets=targets,
        growth_claim=growth,
        growth_text=growth_text,
        step_claim=int(sm.group(1)),
        step_text=step_text,
        motion_claims=_motion_claims(src),
        brackets_coincide_text=coincide,
        privileged_text=privileged,
        vf_text=vf_text,
        homogeneous_text=homogeneous,
    )
