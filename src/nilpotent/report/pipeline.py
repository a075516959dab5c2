r"""``reproduce``: the paper's pipeline end to end, written as an offline web page.

:func:`reproduce` runs, in order,

1. the audit (:func:`nilpotent.report.audit.run_audit`): every checkable
   statement of the paper against a computation;
2. the two models — ``trident-snake`` (body-velocity inputs, the paper's
   Section 4, ``r = l = 1``) and ``trident-snake-paper`` (its eq. ``vf``) — with
   their growth vector, weights and adapted frame
    (:func:`~nilpotent.core.analysis.filtration.analyze`);
3. privileged coordinates and the nilpotent approximation of each
   (:func:`~nilpotent.core.coordinates.approximation.approximate`), in ``y`` and in ``x``;
4. the bracket motions of Figs 2–4 (Section 4 robot) and the comparisons of
   Figs 5–7 (eq. vf against its approximation, as in the paper; the Section 4
   robot against its approximation as well), with animations of the robot;
5. the amplitude study (error against amplitude, log–log, fitted slopes);
6. the singular set of eq. vf;

each a small named function (``_audit_paper``, ``_analyse_models``,
``_approximate_models``, ``_bracket_motions``, ``_amplitude_study``) whose
results fill one typed :class:`~nilpotent.report.reproduction_data.ReproductionData`;
writing steps then turn it into files (``_write_data``, ``_write_figures``,
``_write_animations``, ``_write_page``).  It writes ``DIR/index.html``
(self-contained: inline CSS and script, images as relative files under
``DIR/figures/``, nothing fetched), ``DIR/figures/`` (PNG + SVG of every
figure, GIF + HTML player (+ MP4 with ffmpeg) of every animation), ``DIR/data/``
(CSV/JSON of every number shown) and
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

import os
import shutil
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import sympy as sp

from nilpotent import interrupts
from nilpotent.outputs import remove_stale_temporaries, temporary_prefix
from nilpotent.progress import Progress, ProgressCallback, ProgressEvent
from nilpotent.progress import progress as report_progress
from nilpotent.report.output import check_target, move_into_place, write_csv, write_json
from nilpotent.report.reproduction_data import (
    BRACKET_PAIRS,
    MODEL_KEYS,
    PageFigures,
    ReproductionData,
    Settings,
)
from nilpotent.strict_json import json_object

if TYPE_CHECKING:
    from nilpotent.core.model.system import ControlSystem
    from nilpotent.report.audit import Audit

__all__ = [
    "DEFAULT_OUT",
    "FULL",
    "QUICK",
    "PageFigures",
    "Reproduction",
    "ReproductionData",
    "Settings",
    "reproduce",
]

#: Where ``nilpotent reproduce`` writes when no ``--out`` is given.
DEFAULT_OUT = "nilpotent-paper"

#: The full reproduction.
FULL = Settings(0.3, 181, 48, tuple(float(a) for a in np.geomspace(0.02, 0.5, 10)), 150, 80)
#: ``--quick``: fewer amplitudes, samples and frames (tests, CI).
QUICK = Settings(0.3, 61, 8, (0.05, 0.1, 0.2, 0.4), 90, 60)


@dataclass(frozen=True)
class Reproduction:
    """What :func:`reproduce` wrote (paths are inside ``out_dir``) and its key numbers.

    Attributes
    ----------
    out_dir:
        The folder written.
    index, audit_path:
        ``index.html`` and ``audit.json``.
    audit:
        The audit of the paper.
    figures, data, animations:
        The files written under ``figures/`` and ``data/``.
    slopes:
        The fitted log–log slopes of the error study, by model and bracket.
    quick:
        Whether the quick settings were used.
    seconds:
        Wall-clock time of the whole reproduction.
    timings:
        Wall-clock seconds of each step.
    """

    out_dir: Path
    index: Path
    audit_path: Path
    audit: Audit
    figures: tuple[Path, ...]
    data: tuple[Path, ...]
    animations: tuple[Path, ...]
    slopes: dict[str, dict[str, float | None]]
    quick: bool
    seconds: float
    timings: dict[str, float] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        """The ``nilpotent/reproduce@1`` summary that ``nilpotent reproduce --json`` prints."""
        return json_object({
            "schema": "nilpotent/reproduce@1",
            "out": str(self.out_dir),
            "index": str(self.index),
            "audit": str(self.audit_path),
            "quick": self.quick,
            "audit_summary": self.audit.to_json()["summary"],
            "differs": [e.id for e in self.audit.differing],
            "figures": [str(p) for p in self.figures],
            "animations": [str(p) for p in self.animations],
            "data": [str(p) for p in self.data],
            "slopes": self.slopes,
            "seconds": round(self.seconds, 3),
            "timings": {k: round(v, 3) for k, v in self.timings.items()},
        })


# --- formatting ----------------------------------------------------------------------
def _fmt(value: Any) -> str:
    from nilpotent.core.model.expressions import format_expression

    return format_expression(sp.S(value))


def _model_payload(system, filtration, approx) -> dict[str, Any]:
    from nilpotent.core.lie.brackets import format_word

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
def reproduce(
    out_dir: str | os.PathLike[str] = DEFAULT_OUT,
    quick: bool = False,
    *,
    progress: ProgressCallback | None = None,
) -> Reproduction:
    """Reproduce the paper end to end and write the page, figures, data and audit.

    Parameters
    ----------
    out_dir : str or path
        The folder to write (default ``./nilpotent-paper``); replaced whole at
        the end (see the module docstring for when it is refused).
    quick : bool
        Fewer amplitudes, samples and frames (:data:`QUICK` instead of :data:`FULL`).
    progress : ProgressCallback or None
        Called with ``ProgressEvent(step, done, total)`` before each step (the
        step's name, the steps done, their number; :mod:`nilpotent.progress`) and
        ``ProgressEvent("done", total, total)`` at the end (the steps are also
        reported on stderr through :mod:`nilpotent.progress` when that is enabled).

    Returns
    -------
    Reproduction
        The files written (inside ``out_dir``) and the audit.

    Raises
    ------
    OptionError
        ``out_dir`` cannot be written or is a folder that is not a previous
        reproduction.
    """
    target = Path(out_dir).resolve()
    check_target(target)
    existed = target.exists()
    remove_stale_temporaries(target)  # left by runs killed outright
    settings = QUICK if quick else FULL
    tmp: Path | None = None
    try:
        with interrupts.deferred():  # created and known to the clean-up below as one step
            tmp = Path(tempfile.mkdtemp(prefix=temporary_prefix(target), dir=target.parent))
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o777 & ~mask)  # mkdtemp makes it private; the result is ordinary
        result = _run(tmp, settings, quick, progress)
        move_into_place(tmp, target, existed)
    except BaseException:
        if tmp is not None:
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
    "bracket motions (Figs 2-7)",
    "amplitude study",
    "writing the data",
    "figures (Figs 2-7, amplitude, singular set)",
    "animations",
    "writing the page",
)


class _Steps:
    """Times the named steps and reports them (callback and :mod:`nilpotent.progress`)."""

    def __init__(self, callback: ProgressCallback | None, bar: Progress) -> None:
        self.callback = callback
        self.bar = bar
        self.done = 0
        self.timings: dict[str, float] = {}

    @contextmanager
    def step(self, name: str) -> Iterator[None]:
        event = ProgressEvent(name, self.done, len(_STEPS))
        if self.callback is not None:
            self.callback(event)
        self.bar(event)
        start = time.perf_counter()
        yield
        self.timings[name] = time.perf_counter() - start
        self.done += 1
        self.bar(ProgressEvent(name, self.done, len(_STEPS)))


@dataclass
class _Files:
    """The folders written into and the files written so far (paths under ``out``)."""

    out: Path
    figures: list[Path] = field(default_factory=list)
    data: list[Path] = field(default_factory=list)
    animations: list[Path] = field(default_factory=list)

    @property
    def figures_dir(self) -> Path:
        return self.out / "figures"

    @property
    def data_dir(self) -> Path:
        return self.out / "data"


def _run(out: Path, settings: Settings, quick: bool,
         callback: ProgressCallback | None) -> Reproduction:
    start = time.perf_counter()
    files = _Files(out)
    files.figures_dir.mkdir()
    files.data_dir.mkdir()
    with report_progress("reproduce", total=len(_STEPS)) as bar:
        steps = _Steps(callback, bar)
        with steps.step(_STEPS[0]):
            paper, audit = _audit_paper()
        with steps.step(_STEPS[1]):
            systems, filtrations = _analyse_models()
        with steps.step(_STEPS[2]):
            approximations = _approximate_models(systems)
        with steps.step(_STEPS[3]):
            motions, brackets = _bracket_motions(systems, approximations, settings)
        with steps.step(_STEPS[4]):
            studies = _amplitude_study(systems, approximations, settings)
        data = ReproductionData(
            paper=paper,
            audit=audit,
            settings=settings,
            quick=quick,
            systems=systems,
            filtrations=filtrations,
            approximations=approximations,
            brackets=brackets,
            motions=motions,
            studies=studies,
        )
        with steps.step(_STEPS[5]):
            audit_path = _write_data(data, files)
        with steps.step(_STEPS[6]):
            stems = _write_figures(data, files)
        with steps.step(_STEPS[7]):
            anim_files = _write_animations(data, files, bar)
        with steps.step(_STEPS[8]):
            index = _write_page(data, PageFigures(**stems, animations=anim_files), out)
    if callback is not None:
        callback(ProgressEvent("done", len(_STEPS), len(_STEPS)))
    return Reproduction(
        out,
        index,
        audit_path,
        audit,
        tuple(files.figures),
        tuple(files.data),
        tuple(files.animations),
        data.slopes,
        quick,
        time.perf_counter() - start,
        steps.timings,
    )


# --- computing steps: each fills part of ReproductionData -----------------------------
def _audit_paper() -> tuple[Any, Audit]:
    """The paper read from its source, and its audit."""
    from nilpotent.report.audit import run_audit
    from nilpotent.report.paper import read_paper

    paper = read_paper()
    return paper, run_audit(paper)


def _analyse_models() -> tuple[dict[str, ControlSystem], dict[str, Any]]:
    """The two models (``r = l = 1`` for the Section 4 fields) and their filtrations at 0."""
    from nilpotent.core.analysis.filtration import analyze
    from nilpotent.models import get_model

    systems = {
        "body": get_model("trident-snake", {"r": sp.Integer(1), "l": sp.Integer(1)}),
        "vf": get_model("trident-snake-paper"),
    }
    return systems, {key: analyze(systems[key]) for key in MODEL_KEYS}


def _approximate_models(systems: dict[str, ControlSystem]) -> dict[str, Any]:
    """Privileged coordinates and the nilpotent approximation of each model."""
    from nilpotent.core.coordinates.approximation import approximate

    return {key: approximate(systems[key]) for key in MODEL_KEYS}


def _bracket_motions(
    systems: dict[str, ControlSystem], approximations: dict[str, Any], settings: Settings
) -> tuple[dict[tuple[str, tuple[int, int]], Any], dict[tuple[str, tuple[int, int]], Any]]:
    """One period of each periodic bracket input, original against approximation.

    Also the exact brackets ``[g_i, g_j](0)``.
    """
    from nilpotent.core.lie.brackets import word_values_at
    from nilpotent.simulation import compare_bracket_motion

    motions: dict[tuple[str, tuple[int, int]], Any] = {}
    brackets: dict[tuple[str, tuple[int, int]], tuple[sp.Expr, ...]] = {}
    for key in MODEL_KEYS:
        spec = systems[key].specialized()
        for pair in BRACKET_PAIRS:
            motions[key, pair] = compare_bracket_motion(
                systems[key],
                pair,
                settings.figure_amplitude,
                approximation=approximations[key],
                samples=settings.samples,
            )
            (brackets[key, pair],) = word_values_at(spec, [pair], spec.origin())
    return motions, brackets


def _amplitude_study(
    systems: dict[str, ControlSystem], approximations: dict[str, Any], settings: Settings
) -> dict[tuple[str, tuple[int, int]], Any]:
    """Error of the approximation against amplitude, for every model and bracket."""
    from nilpotent.simulation import scaling_study

    jobs = [(key, pair) for key in ("vf", "body") for pair in BRACKET_PAIRS]
    out: dict[tuple[str, tuple[int, int]], Any] = {}
    with report_progress("amplitude study: brackets", total=len(jobs)) as bar:
        for key, pair in jobs:
            bar.update(detail=f"{key} [g{pair[0]},g{pair[1]}], "
                              f"{len(settings.amplitudes)} amplitudes")
            out[key, pair] = scaling_study(
                systems[key], pair, settings.amplitudes, approximation=approximations[key]
            )
            bar.advance()
    return out


# --- writing steps: files from ReproductionData ----------------------------------------
def _write_data(data: ReproductionData, files: _Files) -> Path:
    """``audit.json`` and ``data/`` (audit, models, motions, amplitude study); the audit's path."""
    audit = data.audit
    audit_path = write_json(files.out / "audit.json", audit.to_json())
    d = files.data_dir
    files.data.append(
        write_csv(
            d / "audit.csv",
            ["id", "section", "verdict", "statement", "paper", "computed", "explanation"],
            [
                [e.id, e.section, e.verdict, e.statement, e.paper, e.computed, e.explanation]
                for e in audit.entries
            ],
        )
    )
    payload = {
        key: _model_payload(data.systems[key], data.filtrations[key], data.approximations[key])
        for key in MODEL_KEYS
    }
    files.data.append(write_json(d / "models.json", payload))
    motion_rows = []
    for (key, pair), m in data.motions.items():
        names = data.systems[key].coordinate_names
        header = ["t"] + [f"{c}_original" for c in names] + [f"{c}_approximation" for c in names]
        rows = np.column_stack([m.times, m.original, m.approximate]).tolist()
        files.data.append(write_csv(d / f"motion_{key}_{pair[0]}{pair[1]}.csv", header, rows))
        motion_rows.append(
            {
                "model": data.systems[key].name,
                "bracket": list(pair),
                "amplitude": m.amplitude,
                "bracket_at_0": [_fmt(v) for v in data.brackets[key, pair]],
                "final_original": m.original[-1].tolist(),
                "final_approximation": m.approximate[-1].tolist(),
                "prediction": m.prediction.tolist(),
                "endpoint_error": m.endpoint_error,
            }
        )
    files.data.append(write_json(d / "motions.json", motion_rows))
    for (key, pair), st in data.studies.items():
        header = ["amplitude"] + [f"error_weight_{w}" for w in st.errors]
        rows = np.column_stack([st.amplitudes, *st.errors.values()]).tolist()
        files.data.append(write_csv(d / f"amplitude_{key}_{pair[0]}{pair[1]}.csv", header, rows))
    files.data.append(write_json(d / "slopes.json", data.slopes))
    return audit_path


def _write_figures(data: ReproductionData, files: _Files) -> dict[str, Any]:
    """Figs 2–7 (and the robot's comparisons), the amplitude study, the singular set."""
    from nilpotent.models.trident import TridentGeometry
    from nilpotent.viz import (
        plot_amplitude_panels,
        plot_bracket_motion,
        plot_motion_comparison,
        plot_paper_singular_set,
        save_figure,
    )

    dpi = data.settings.dpi
    names = data.s4_names
    geometry = {
        "body": TridentGeometry.for_form("trident-snake"),
        "vf": TridentGeometry.for_form("trident-snake-paper"),
    }

    def save(fig: Any, stem: str) -> str:
        files.figures.extend(save_figure(fig, files.figures_dir, stem, dpi=dpi))
        return stem

    motion: dict[tuple[int, int], str] = {}
    for n, pair in enumerate(BRACKET_PAIRS):
        m, k = data.motions["body", pair], names[pair]
        fig, _ = plot_bracket_motion(
            m.original,
            geometry["body"],
            times=m.times,
            title=f"Fig. {n + 2}: g{k} = [g{pair[0]},g{pair[1]}] motion of the robot "
            f"(Section 4 fields, A = {m.amplitude:g})",
        )
        motion[pair] = save(fig, f"fig{n + 2}_g{k}_motion")
    comparison: dict[tuple[str, tuple[int, int]], str] = {}
    for key, label in (("vf", "eq. vf (the paper's form)"), ("body", "Section 4 robot")):
        for n, pair in enumerate(BRACKET_PAIRS):
            m, k = data.motions[key, pair], names[pair]
            fig, _ = plot_motion_comparison(
                m.original,
                m.approximate,
                geometry[key],
                times=m.times,
                title=f"[g{pair[0]},g{pair[1]}] (g{k}): {label}, original (solid) vs "
                f"nilpotent approximation (dashed), A = {m.amplitude:g}",
            )
            stem = (
                f"fig{n + 5}_g{k}_comparison"
                if key == "vf"
                else f"fig{n + 5}b_g{k}_comparison_robot"
            )
            comparison[key, pair] = save(fig, stem)
    amplitude: dict[str, str] = {}
    for key, label in (("vf", "eq. vf"), ("body", "Section 4 robot")):
        fig, _ = plot_amplitude_panels(
            [(pair, data.studies[key, pair]) for pair in BRACKET_PAIRS], label
        )
        amplitude[key] = save(fig, f"amplitude_{key}")
    fig, _ = plot_paper_singular_set(resolution=121 if data.quick else 241)
    singular_set = save(fig, "singular_set_vf")
    return {
        "motion": motion,
        "comparison": comparison,
        "amplitude": amplitude,
        "singular_set": singular_set,
    }


def _write_animations(data: ReproductionData, files: _Files, bar: Any = None
                      ) -> dict[tuple[int, int], Any]:
    """Animations of the robot (Section 4 fields) and of its approximation, per bracket."""
    from nilpotent.models.trident import TridentGeometry
    from nilpotent.viz import animate_motion_comparison, save_animation

    geometry = TridentGeometry.for_form("trident-snake")
    out: dict[tuple[int, int], Any] = {}
    for pair in BRACKET_PAIRS:
        m, k = data.motions["body", pair], data.s4_names[pair]
        stage = f"animation g{k}: [g{pair[0]},g{pair[1]}], {data.settings.frames} frames"
        if bar is not None:
            bar.update(detail=stage)
        anim = animate_motion_comparison(
            m.original,
            m.approximate,
            geometry,
            times=m.times,
            frames=data.settings.frames,
            title=f"[g{pair[0]},g{pair[1]}] (g{k}) motion, A = {m.amplitude:g}",
        )
        saved = save_animation(
            anim, files.figures_dir, f"anim_g{k}", dpi=data.settings.animation_dpi
        )
        out[pair] = saved
        files.animations.extend(p for p in (saved.gif, saved.html, saved.mp4) if p is not None)
    return out


def _write_page(data: ReproductionData, figures: PageFigures, out: Path) -> Path:
    """``index.html``."""
    from nilpotent.report.document import build_page

    index = out / "index.html"
    index.write_text(build_page(data, figures), encoding="utf-8")
    return index
