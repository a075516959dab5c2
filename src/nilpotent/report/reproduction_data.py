"""What a reproduction of the paper holds: the settings, the computed objects, the figure files.

:class:`ReproductionData` is filled by the named steps of
:mod:`nilpotent.report.pipeline` (audit, models, approximations, motions,
amplitude study) and read by the page (:func:`nilpotent.report.document.build_page`)
together with :class:`PageFigures`, the names of the figure and animation files
written for it.  Both are immutable values.

The two models are keyed ``"body"`` (``trident-snake``: the paper's Section 4
fields, ``r = l = 1``) and ``"vf"`` (``trident-snake-paper``: its eq. vf);
per-bracket values are keyed ``(model key, (i, j))`` for ``[g_i, g_j]``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import sympy as sp

    from nilpotent.core.analysis.filtration import Filtration
    from nilpotent.core.coordinates.approximation import NilpotentApproximation
    from nilpotent.core.model.system import ControlSystem
    from nilpotent.report.audit import Audit
    from nilpotent.report.paper import PaperContent
    from nilpotent.simulation import Comparison, ScalingStudy
    from nilpotent.viz import AnimationFiles

__all__ = ["BRACKET_PAIRS", "MODEL_KEYS", "PageFigures", "ReproductionData", "Settings"]

#: The first-order brackets ``[g_i, g_j]`` of the paper's Figs 2–7, in its order.
BRACKET_PAIRS: tuple[tuple[int, int], ...] = ((1, 2), (2, 3), (1, 3))
#: The two models of the reproduction: ``"body"`` (Section 4 fields), ``"vf"`` (eq. vf).
MODEL_KEYS: tuple[str, ...] = ("body", "vf")

Pair = tuple[int, int]


@dataclass(frozen=True)
class Settings:
    """How much to compute: amplitudes, samples per trajectory, animation frames.

    Attributes
    ----------
    figure_amplitude : float
        Input amplitude ``A`` of the motions of Figs 2–7.
    samples : int
        Samples per simulated period.
    frames : int
        Frames per animation.
    amplitudes : tuple of float
        Amplitudes of the amplitude study.
    dpi, animation_dpi : int
        Resolution of the figures and of the animations.
    """

    figure_amplitude: float
    samples: int
    frames: int
    amplitudes: tuple[float, ...]
    dpi: int
    animation_dpi: int


@dataclass(frozen=True)
class ReproductionData:
    """The computed side of a reproduction: everything the page and the data files show.

    Attributes
    ----------
    paper : PaperContent
        The paper's statements, read from its LaTeX source.
    audit : Audit
        Every checkable statement against a computation.
    settings : Settings
        How much was computed.
    quick : bool
        Whether ``settings`` are the quick ones.
    systems : mapping str -> ControlSystem
        ``"body"`` and ``"vf"`` (see the module docstring).
    filtrations : mapping str -> Filtration
        Their analysis at the origin.
    approximations : mapping str -> NilpotentApproximation
        Their nilpotent approximations.
    brackets : mapping (str, (i, j)) -> tuple of sympy expressions
        ``[g_i, g_j](0)``, exact.
    motions : mapping (str, (i, j)) -> Comparison
        One period of the ``(i, j)`` periodic input, original against
        approximation, at ``settings.figure_amplitude``.
    studies : mapping (str, (i, j)) -> ScalingStudy
        Error against amplitude over ``settings.amplitudes``.
    """

    paper: PaperContent
    audit: Audit
    settings: Settings
    quick: bool
    systems: Mapping[str, ControlSystem]
    filtrations: Mapping[str, Filtration]
    approximations: Mapping[str, NilpotentApproximation]
    brackets: Mapping[tuple[str, Pair], tuple[sp.Expr, ...]]
    motions: Mapping[tuple[str, Pair], Comparison]
    studies: Mapping[tuple[str, Pair], ScalingStudy]

    @property
    def s4_names(self) -> dict[Pair, int]:
        """Section 4's bracket names: ``(1, 2) -> 4`` for ``g4 = [g1, g2]``."""
        return {pair: k for k, pair in self.paper.bracket_labels_sec4.items()}

    @property
    def slopes(self) -> dict[str, dict[str, float | None]]:
        """Fitted log–log slopes by study (``"trident-snake [X1,X2]"``) and weight group.

        ``None`` where the errors are below the round-off floor (exact).
        """
        out: dict[str, dict[str, float | None]] = {}
        for (key, pair), st in self.studies.items():
            name = f"{self.systems[key].name} [X{pair[0]},X{pair[1]}]"
            out[name] = {
                f"weight {w}": (None if v is None else round(v, 4)) for w, v in st.slopes.items()
            }
        return out


@dataclass(frozen=True)
class PageFigures:
    """The stems (file names without suffix, under ``figures/``) of the page's pictures.

    Attributes
    ----------
    motion : mapping (i, j) -> str
        Figs 2–4: the Section 4 robot's bracket motions.
    comparison : mapping (str, (i, j)) -> str
        Figs 5–7 (``"vf"``) and their Section 4 counterparts (``"body"``).
    animations : mapping (i, j) -> AnimationFiles
        The animations of the robot and its approximation.
    amplitude : mapping str -> str
        The amplitude study of each model.
    singular_set : str
        The singular set of eq. vf.
    """

    motion: Mapping[Pair, str]
    comparison: Mapping[tuple[str, Pair], str]
    animations: Mapping[Pair, AnimationFiles]
    amplitude: Mapping[str, str]
    singular_set: str
