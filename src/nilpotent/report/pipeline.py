r"""``reproduce``: the paper's pipeline end to end, written as an offline web page.

:func:`reproduce` runs, in order,

1. the audit (:func:`nilpotent.report.audit.run_audit`): every checkable
   statement of the paper against a computation;
2. the two models — ``trident-snake`` (body-velocity inputs, the paper's
   Section 4, ``r = l = 1``) and ``trident-snake-paper`` (its eq. ``vf``) — with
   their growth vector, weights and adapted frame (:func:`~nilpotent.core.filtration.analyze`);
3. privileged coordinates and the nilpotent approximation of each
   (:func:`~nilpotent.core.approximation.approximate`), in ``y`` and in ``x``;
4. the bracket motions of Figs 2–4 (Section 4 robot) and the comparisons of
   Figs 5–7 (eq. vf against its approximation, as in the paper; the Section 4
   robot against its approximation as well), with animations of the robot;
5. the amplitude study (error against amplitude, log–log, fitted slopes);
6. the singular set of eq. vf;

and writes ``DIR/index.html`` (self-contained: inline CSS and script, images
as relative files under ``DIR/figures/``, nothing fetched), ``DIR/figures/``
(PNG + SVG of every figure, GIF + HTML player (+ MP4 with ffmpeg) of every
animation), ``DIR/data/`` (CSV/JSON of every number shown) and
``DIR/audit.json`` (schema ``nilpotent/audit@1``).

Everything is written into a temporary folder beside ``DIR`` and moved into
place at the end, so ``DIR`` is never left half-written.  An existing ``DIR``
is replaced only if it is empty or a previous reproduction (it holds an
``audit.json`` of this schema); anything else is refused.

Bracket names: the paper names ``[g2,g3]`` "g5" in Section 4 and "ĝ6" in
Section 7 (the audit flags this); figures here are titled with the brackets
themselves, and Figs 2–7 follow Section 4's names (``g4 = [g1,g2]``,
``g5 = [g2,g3]``, ``g6 = [g1,g3]``) like the paper's figure captions.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp

from nilpotent.errors import OptionError
from nilpotent.outputs import remove_stale_temporaries, temporary_prefix

__all__ = [
    "DEFAULT_OUT",
    "FULL",
    "QUICK",
    "Reproduction",
    "Settings",
    "reproduce",
]

#: Where ``nilpotent reproduce`` writes when no ``--out`` is given.
DEFAULT_OUT = "nilpotent-paper"

Progress = Callable[[str, int, int], None]


@dataclass(frozen=True)
class Settings:
    """How much to compute: amplitudes, samples per trajectory, animation frames."""

    figure_amplitude: float
    samples: int
    frames: int
    amplitudes: tuple[float, ...]
    dpi: int
    animation_dpi: int


#: The full reproduction.
FULL = Settings(0.3, 181, 48, tuple(float(a) for a in np.geomspace(0.02, 0.5, 10)), 150, 80)
#: ``--quick``: fewer amplitudes, samples and frames (tests, CI).
QUICK = Settings(0.3, 61, 8, (0.05, 0.1, 0.2, 0.4), 90, 60)


@dataclass(frozen=True)
class Reproduction:
    """What :func:`reproduce` wrote (paths are inside ``out_dir``) and its key numbers."""

    out_dir: Path
    index: Path
    audit_path: Path
    audit: Any  # nilpotent.report.audit.Audit
    figures: tuple[Path, ...]
    data: tuple[Path, ...]
    animations: tuple[Path, ...]
    slopes: dict[str, dict[str, float | None]]
    quick: bool
    seconds: float
    timings: dict[str, float] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        """A JSON-ready summary (``nilpotent/reproduce@1``) for ``--json``."""
        return {
            "schema": "nilpotent/reproduce@1",
            "out": str(self.out_dir),
            "index": str(self.index),
            "audit": str(self.audit_path),
            "quick": self.quick,
            "audit_summary": self.audit.as_json()["summary"],
            "differs": [e.id for e in self.audit.differing],
            "figures": [str(p) for p in self.figures],
            "animations": [str(p) for p in self.animations],
            "data": [str(p) for p in self.data],
            "slopes": self.slopes,
            "seconds": round(self.seconds, 3),
            "timings": {k: round(v, 3) for k, v in self.timings.items()},
        }


# --- output folder handling ---------------------------------------------------------
def _check_target(target: Path) -> None:
    from nilpotent.report.audit import AUDIT_SCHEMA

    if not target.exists():
        if not target.parent.exists():
            raise OptionError(f"cannot write {target}: folder {target.parent} does not exist")
        return
    if not target.is_dir():
        raise OptionError(f"--out {target} exists and is not a folder")
    if not any(target.iterdir()):
        return
    audit = target / "audit.json"
    try:
        ours = json.loads(audit.read_text(encoding="utf-8")).get("schema") == AUDIT_SCHEMA
    except (OSError, ValueError, AttributeError):
        ours = False
    if not ours:
        raise OptionError(
            f"--out {target} exists and is not a previous reproduction (no {AUDIT_SCHEMA} "
            "audit.json in it); choose another folder or remove it"
        )


def _move_into_place(tmp: Path, target: Path, existed: bool = True) -> None:
    if target.exists() and not existed:
        raise OptionError(
            f"--out {target} was created by something else while the reproduction ran; it is "
            "left untouched (run again, or choose another folder)"
        )
    _check_target(target)  # again: what is there now must still be a previous reproduction
    if target.exists():
        old = Path(tempfile.mkdtemp(prefix=temporary_prefix(target, "old"), dir=target.parent))
        os.replace(target, old / target.name)
        os.replace(tmp, target)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(tmp, target)


# --- formatting ----------------------------------------------------------------------
def _fmt(value: Any) -> str:
    from nilpotent.core.expressions import format_expression

    return format_expression(sp.S(value))


def _write_json(path: Path, obj: Any) -> Path:
    from nilpotent.strict_json import json_text

    path.write_text(json_text(obj), encoding="utf-8")
    return path


def _write_csv(path: Path, header: Sequence[str], rows: Sequence[Sequence[Any]]) -> Path:
    with path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows(rows)
    return path


def _model_payload(system, filtration, approx) -> dict[str, Any]:
    from nilpotent.core.brackets import format_word

    coords = system.coordinate_names
    cert = approx.certificate
    return {
        "model": system.name,
        "description": system.description,
        "coordinates": list(coords),
        "fields": [[_fmt(v) for v in f] for f in system.specialized_fields],
        "point": [_fmt(v) for v in filtration.point],
        "growth_vector": list(filtration.growth_vector),
        "weights": list(filtration.weights),
        "step": filtration.step,
        "regular": filtration.regular,
        "frame": [format_word(w) for w in filtration.frame],
        "frame_values": [[_fmt(v) for v in col] for col in filtration.frame_values],
        "privileged": {
            "method": approx.coordinates.method,
            "names": [str(y) for y in approx.coordinates.names],
            "expressions": [_fmt(e) for e in approx.coordinates.forward],
            "inverse": [_fmt(e) for e in approx.coordinates.inverse],
            "orders": list(approx.coordinates.orders),
        },
        "approximation_y": [[_fmt(v) for v in f] for f in approx.fields],
        "approximation_x": [[_fmt(v) for v in f] for f in approx.fields_x],
        "certificate": {
            "orders": list(cert.orders),
            "weights": list(cert.weights),
            "homogeneous": cert.homogeneous,
            "nilpotent_step": cert.nilpotent_step,
            "growth_vector_at_0": list(cert.growth_vector_at_0),
            "remainder_order_ok": cert.remainder_order_ok,
        },
    }


# --- the pipeline -------------------------------------------------------------------
_PAIRS = ((1, 2), (2, 3), (1, 3))


def reproduce(
    out_dir: str | os.PathLike[str] = DEFAULT_OUT,
    quick: bool = False,
    *,
    progress: Progress | None = None,
) -> Reproduction:
    """Reproduce the paper end to end and write the page, figures, data and audit.

    Parameters
    ----------
    out_dir:
        The folder to write (default ``./nilpotent-paper``); replaced whole at
        the end (see the module docstring for when it is refused).
    quick:
        Fewer amplitudes, samples and frames (:data:`QUICK` instead of :data:`FULL`).
    progress:
        Called as ``progress(step, done, total)`` before each step.

    Returns
    -------
    Reproduction
    """
    target = Path(out_dir).resolve()
    _check_target(target)
    existed = target.exists()
    remove_stale_temporaries(target)  # left by runs killed outright
    settings = QUICK if quick else FULL
    tmp = Path(tempfile.mkdtemp(prefix=temporary_prefix(target), dir=target.parent))
    mask = os.umask(0)
    os.umask(mask)
    os.chmod(tmp, 0o777 & ~mask)  # mkdtemp makes it private; the result is an ordinary folder
    try:
        result = _run(tmp, settings, quick, progress)
        _move_into_place(tmp, target, existed)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return _relocate(result, tmp, target)


def _relocate(r: Reproduction, old: Path, new: Path) -> Reproduction:
    def move(p: Path) -> Path:
        return new / p.relative_to(old)

    return Reproduction(
        new,
        move(r.index),
        move(r.audit_path),
        r.audit,
        tuple(map(move, r.figures)),
        tuple(map(move, r.data)),
        tuple(map(move, r.animations)),
        r.slopes,
        r.quick,
        r.seconds,
        r.timings,
    )


_STEPS = (
    "auditing the paper",
    "analysing the models",
    "nilpotent approximations",
    "bracket motions (Figs 2-4)",
    "comparisons (Figs 5-7)",
    "animations",
    "amplitude study",
    "singular set",
    "writing the page",
)


def _run(out: Path, settings: Settings, quick: bool, progress: Progress | None) -> Reproduction:
    from nilpotent.core.approximation import approximate
    from nilpotent.core.brackets import word_values_at
    from nilpotent.core.filtration import analyze
    from nilpotent.models import get_model
    from nilpotent.models.trident import TridentGeometry
    from nilpotent.report.audit import run_audit
    from nilpotent.report.paper import read_paper
    from nilpotent.simulate import compare_bracket_motion, scaling_study
    from nilpotent.viz import (
        animate_motion_comparison,
        plot_bracket_motion,
        plot_error_scaling,
        plot_motion_comparison,
        plot_paper_singular_set,
        save_animation,
        save_figure,
    )

    start = time.perf_counter()
    timings: dict[str, float] = {}
    figures_dir = out / "figures"
    data_dir = out / "data"
    figures_dir.mkdir()
    data_dir.mkdir()
    figures: list[Path] = []
    data: list[Path] = []
    animations: list[Path] = []
    step_no = 0

    def step(name: str) -> None:
        nonlocal step_no, last
        now = time.perf_counter()
        if step_no > 0:
            timings[_STEPS[step_no - 1]] = now - last
        last = now
        if progress is not None:
            progress(name, step_no, len(_STEPS))
        step_no += 1

    last = start

    # 1. audit
    step(_STEPS[0])
    paper = read_paper()
    audit = run_audit(paper)
    audit_path = _write_json(out / "audit.json", audit.as_json())
    data.append(
        _write_csv(
            data_dir / "audit.csv",
            ["id", "section", "verdict", "statement", "paper", "computed", "explanation"],
            [
                [e.id, e.section, e.verdict, e.statement, e.paper, e.computed, e.explanation]
                for e in audit.entries
            ],
        )
    )

    # 2. models and filtrations
    step(_STEPS[1])
    body = get_model("trident-snake", {"r": sp.Integer(1), "l": sp.Integer(1)})
    vf = get_model("trident-snake-paper")
    filt = {"body": analyze(body), "vf": analyze(vf)}

    # 3. approximations
    step(_STEPS[2])
    approx = {"body": approximate(body), "vf": approximate(vf)}
    systems = {"body": body, "vf": vf}
    payload = {k: _model_payload(systems[k], filt[k], approx[k]) for k in systems}
    data.append(_write_json(data_dir / "models.json", payload))
    geometry = {
        "body": TridentGeometry.for_form("trident-snake"),
        "vf": TridentGeometry.for_form("trident-snake-paper"),
    }
    s4_names = {pair: k for k, pair in paper.bracket_labels_sec4.items()}

    # 4-5. motions and comparisons
    step(_STEPS[3])
    motions: dict[tuple[str, tuple[int, int]], Any] = {}
    exact_brackets: dict[tuple[str, tuple[int, int]], tuple[sp.Expr, ...]] = {}
    for key in ("body", "vf"):
        spec = systems[key].specialized()
        for pair in _PAIRS:
            motions[key, pair] = compare_bracket_motion(
                systems[key],
                pair,
                settings.figure_amplitude,
                approximation=approx[key],
                samples=settings.samples,
            )
            (exact_brackets[key, pair],) = word_values_at(spec, [pair], spec.origin())
    motion_rows = []
    for (key, pair), m in motions.items():
        stem = f"motion_{key}_{pair[0]}{pair[1]}"
        header = (
            ["t"]
            + [f"{c}_original" for c in systems[key].coordinate_names]
            + [f"{c}_approximation" for c in systems[key].coordinate_names]
        )
        rows = np.column_stack([m.times, m.original, m.approximate]).tolist()
        data.append(_write_csv(data_dir / f"{stem}.csv", header, rows))
        motion_rows.append(
            {
                "model": systems[key].name,
                "bracket": list(pair),
                "amplitude": m.amplitude,
                "bracket_at_0": [_fmt(v) for v in exact_brackets[key, pair]],
                "final_original": m.original[-1].tolist(),
                "final_approximation": m.approximate[-1].tolist(),
                "prediction": m.prediction.tolist(),
                "endpoint_error": m.endpoint_error,
            }
        )
    data.append(_write_json(data_dir / "motions.json", motion_rows))
    fig_motion: dict[tuple[int, int], str] = {}
    for n, pair in enumerate(_PAIRS):
        m = motions["body", pair]
        k = s4_names[pair]
        fig, _ = plot_bracket_motion(
            m.original,
            geometry["body"],
            times=m.times,
            title=f"Fig. {n + 2}: g{k} = [g{pair[0]},g{pair[1]}] motion of the robot "
            f"(Section 4 fields, A = {m.amplitude:g})",
        )
        stem = f"fig{n + 2}_g{k}_motion"
        figures.extend(save_figure(fig, figures_dir, stem, dpi=settings.dpi))
        fig_motion[pair] = stem

    step(_STEPS[4])
    fig_compare: dict[tuple[str, tuple[int, int]], str] = {}
    for key, label in (("vf", "eq. vf (the paper's form)"), ("body", "Section 4 robot")):
        for n, pair in enumerate(_PAIRS):
            m = motions[key, pair]
            k = s4_names[pair]
            fig, _ = plot_motion_comparison(
                m.original,
                m.approximate,
                geometry[key],
                times=m.times,
                title=f"[g{pair[0]},g{pair[1]}] (g{k}): {label}, original (dotted) vs "
                f"nilpotent approximation (solid), A = {m.amplitude:g}",
            )
            stem = (
                f"fig{n + 5}_g{k}_comparison"
                if key == "vf"
                else f"fig{n + 5}b_g{k}_comparison_robot"
            )
            figures.extend(save_figure(fig, figures_dir, stem, dpi=settings.dpi))
            fig_compare[key, pair] = stem

    # animations of the robot (Section 4 fields) and its approximation
    step(_STEPS[5])
    anim_files: dict[tuple[int, int], Any] = {}
    for pair in _PAIRS:
        m = motions["body", pair]
        k = s4_names[pair]
        anim = animate_motion_comparison(
            m.original,
            m.approximate,
            geometry["body"],
            times=m.times,
            frames=settings.frames,
            title=f"[g{pair[0]},g{pair[1]}] (g{k}) motion, A = {m.amplitude:g}",
        )
        files = save_animation(anim, figures_dir, f"anim_g{k}", dpi=settings.animation_dpi)
        anim_files[pair] = files
        animations.extend(p for p in (files.gif, files.html, files.mp4) if p is not None)

    # amplitude study
    step(_STEPS[6])
    studies = {
        (key, pair): scaling_study(
            systems[key], pair, settings.amplitudes, approximation=approx[key]
        )
        for key in ("vf", "body")
        for pair in _PAIRS
    }
    slopes: dict[str, dict[str, float | None]] = {}
    for (key, pair), st in studies.items():
        name = f"{systems[key].name} [X{pair[0]},X{pair[1]}]"
        slopes[name] = {
            f"weight {w}": (None if v is None else round(v, 4)) for w, v in st.slopes.items()
        }
        header = ["amplitude"] + [f"error_weight_{w}" for w in st.errors]
        rows = np.column_stack([st.amplitudes, *st.errors.values()]).tolist()
        data.append(_write_csv(data_dir / f"amplitude_{key}_{pair[0]}{pair[1]}.csv", header, rows))
    data.append(_write_json(data_dir / "slopes.json", slopes))
    scaling_stems = {}
    for key, label in (("vf", "eq. vf"), ("body", "Section 4 robot")):
        from matplotlib.figure import Figure

        fig = Figure(figsize=(12, 4), layout="constrained")
        axes = fig.subplots(1, 3, sharey=True)
        for ax, pair in zip(axes, _PAIRS, strict=True):
            st = studies[key, pair]
            series = {f"weight {w}": e for w, e in st.errors.items() if st.slopes[w] is not None}
            bounds = {f"weight {w}": float(st.expected_slopes[w]) for w in st.errors}
            plot_error_scaling(
                st.amplitudes, series, lower_bounds=bounds, ax=ax, title=f"[g{pair[0]},g{pair[1]}]"
            )
            exact = [f"weight {w}" for w in st.errors if st.slopes[w] is None]
            if exact:
                ax.text(
                    0.02,
                    0.02,
                    ", ".join(exact) + f": below the noise floor {st.floor:.1g} (exact)",
                    transform=ax.transAxes,
                    fontsize=7,
                )
        fig.suptitle(
            f"{label}: largest error of the nilpotent approximation over one period "
            "(privileged coordinates by weight; theory: slope ≥ w + 1)"
        )
        stem = f"amplitude_{key}"
        figures.extend(save_figure(fig, figures_dir, stem, dpi=settings.dpi))
        scaling_stems[key] = stem

    step(_STEPS[7])
    fig, _ = plot_paper_singular_set(resolution=121 if quick else 241)
    figures.extend(save_figure(fig, figures_dir, "singular_set_vf", dpi=settings.dpi))

    step(_STEPS[8])
    from nilpotent.report.document import build_page

    html_text = build_page(
        paper=paper,
        audit=audit,
        systems=systems,
        filtrations=filt,
        approximations=approx,
        motions=motions,
        brackets=exact_brackets,
        studies=studies,
        s4_names=s4_names,
        fig_motion=fig_motion,
        fig_compare=fig_compare,
        anim_files=anim_files,
        scaling_stems=scaling_stems,
        settings=settings,
        quick=quick,
    )
    index = out / "index.html"
    index.write_text(html_text, encoding="utf-8")
    timings[_STEPS[-1]] = time.perf_counter() - last
    if progress is not None:
        progress("done", len(_STEPS), len(_STEPS))
    return Reproduction(
        out,
        index,
        audit_path,
        audit,
        tuple(figures),
        tuple(data),
        tuple(animations),
        slopes,
        quick,
        time.perf_counter() - start,
        timings,
    )
