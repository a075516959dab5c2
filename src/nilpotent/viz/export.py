"""Saving figures in several formats at once (PNG for pages, SVG/PDF for print)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from matplotlib.figure import Figure

from nilpotent.errors import OptionError

__all__ = ["FIGURE_FORMATS", "save_figure"]

#: Formats :func:`save_figure` writes.
FIGURE_FORMATS: tuple[str, ...] = ("png", "svg", "pdf")


def save_figure(
    fig: Figure,
    directory: str | Path,
    stem: str,
    formats: Sequence[str] = ("png", "svg"),
    *,
    dpi: int = 150,
) -> tuple[Path, ...]:
    """Write ``fig`` as ``directory/stem.<fmt>`` for each format; return the paths.

    Text stays text in SVG (``svg.fonttype = none``) so the figures remain
    searchable and small.
    """
    import matplotlib

    out = Path(directory)
    if not out.is_dir():
        raise OptionError(f"cannot save figures: {out} is not a folder")
    paths = []
    for fmt in formats:
        if fmt not in FIGURE_FORMATS:
            raise OptionError(f"unknown figure format {fmt!r} (choose from {FIGURE_FORMATS})")
        path = out / f"{stem}.{fmt}"
        with matplotlib.rc_context({"svg.fonttype": "none"}):
            fig.savefig(path, format=fmt, dpi=dpi)
        paths.append(path)
    return tuple(paths)
