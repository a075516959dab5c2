"""Figures and animations (matplotlib; every function returns handles, none calls ``plt.show()``).

* :mod:`~nilpotent.viz.robot` — the trident snake drawn at a configuration;
* :mod:`~nilpotent.viz.motion` — bracket motions (the paper's Figs 2–7);
* :mod:`~nilpotent.viz.animation` — GIF / MP4 / self-contained HTML animations;
* :mod:`~nilpotent.viz.scaling` — error against amplitude, log–log, fitted slopes;
* :mod:`~nilpotent.viz.simulation` — trajectories, comparisons, scaling studies and
  sweeps (their ``.plot()`` methods delegate here);
* :mod:`~nilpotent.viz.plan` — plans: the path (the robot for the trident
  snake), errors per iteration and inputs; GIF animation;
* :mod:`~nilpotent.viz.singular` — the singular set of the paper's eq. vf;
* :mod:`~nilpotent.viz.report_figures` — multi-panel figures of the paper reproduction;
* :mod:`~nilpotent.viz.export` — saving a figure as PNG + SVG (or PDF).

Figures are built with :class:`matplotlib.figure.Figure` directly (no pyplot
state, no GUI backend), so the same code runs headless, in notebooks and in the CLI;
in Jupyter they display as PNG without ``%matplotlib inline``
(:mod:`~nilpotent.viz.notebook`, registered when this package is imported).
"""

from nilpotent.viz.animation import AnimationFiles as AnimationFiles
from nilpotent.viz.animation import MotionAnimation as MotionAnimation
from nilpotent.viz.animation import animate_motion_comparison as animate_motion_comparison
from nilpotent.viz.animation import html_player as html_player
from nilpotent.viz.animation import save_animation as save_animation
from nilpotent.viz.export import save_figure as save_figure
from nilpotent.viz.motion import plot_bracket_motion as plot_bracket_motion
from nilpotent.viz.motion import plot_motion_comparison as plot_motion_comparison
from nilpotent.viz.notebook import enable_figure_display as enable_figure_display
from nilpotent.viz.report_figures import plot_amplitude_panels as plot_amplitude_panels
from nilpotent.viz.robot import TridentArtists as TridentArtists
from nilpotent.viz.robot import draw_trident as draw_trident
from nilpotent.viz.robot import update_trident as update_trident
from nilpotent.viz.scaling import fit_slope as fit_slope
from nilpotent.viz.scaling import plot_error_scaling as plot_error_scaling
from nilpotent.viz.singular import plot_paper_singular_set as plot_paper_singular_set

__all__ = [
    "AnimationFiles",
    "MotionAnimation",
    "TridentArtists",
    "animate_motion_comparison",
    "draw_trident",
    "enable_figure_display",
    "fit_slope",
    "html_player",
    "plot_amplitude_panels",
    "plot_bracket_motion",
    "plot_error_scaling",
    "plot_motion_comparison",
    "plot_paper_singular_set",
    "save_animation",
    "save_figure",
    "update_trident",
]

enable_figure_display()  # Jupyter shows the figures (nothing outside IPython)
