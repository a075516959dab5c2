"""Figures display in Jupyter without ``%matplotlib inline`` (``nilpotent.viz.notebook``).

IPython's display machinery (its ``DisplayFormatter``, the object a Jupyter kernel
formats every cell result with) is used directly: a figure of a result's ``.plot()``
must come out as a PNG image, not only as ``<Figure size ...>``.
"""

from __future__ import annotations

import base64
from types import SimpleNamespace

import pytest

pytest.importorskip("IPython")

from IPython.core.formatters import DisplayFormatter
from matplotlib.figure import Figure

from nilpotent.viz.notebook import enable_figure_display

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _shell() -> SimpleNamespace:
    return SimpleNamespace(display_formatter=DisplayFormatter())


def test_a_figure_displays_as_png_once_enabled():
    shell = _shell()
    fig = Figure(figsize=(3, 2))
    fig.add_subplot().plot([0, 1], [1, 0])
    before, _ = shell.display_formatter.format(fig)
    assert "image/png" not in before  # what a notebook showed: only the text repr
    assert enable_figure_display(shell) is True
    after, _ = shell.display_formatter.format(fig)
    png = base64.b64decode(after["image/png"])
    assert png.startswith(PNG_MAGIC) and len(png) > 1000


def test_a_formatter_already_registered_is_left_alone():
    shell = _shell()

    def mine(fig):
        return "mine"

    shell.display_formatter.formatters["image/svg+xml"].for_type(Figure, mine)
    assert enable_figure_display(shell) is True
    png = shell.display_formatter.formatters["image/png"]
    assert Figure not in png.type_printers  # the user's choice (svg) is kept
    assert shell.display_formatter.formatters["image/svg+xml"].type_printers[Figure] is mine


def test_nothing_happens_outside_ipython():
    assert enable_figure_display(SimpleNamespace()) is False
    assert enable_figure_display(None) in (False, True)  # True only inside a running shell


def test_a_result_plot_displays_as_png():
    from nilpotent.models import get_model
    from nilpotent.simulation.comparison import compare_bracket_motion

    shell = _shell()
    enable_figure_display(shell)
    motion = compare_bracket_motion(get_model("unicycle"), (1, 2), 0.1)
    fig, _ = motion.plot()
    data, _ = shell.display_formatter.format(fig)
    assert base64.b64decode(data["image/png"]).startswith(PNG_MAGIC)


@pytest.mark.slow
def test_a_notebook_shows_the_figure_of_plot_without_magic():
    """End to end, in a real kernel: no ``%matplotlib``, no pyplot import."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_code_cell(
            "import nilpotent as nil\n"
            "motion = nil.compare_bracket_motion(nil.get_model('unicycle'), (1, 2), 0.1)\n"
            "fig, axes = motion.plot()\n"
            "fig"
        )
    ]
    nbclient.NotebookClient(nb, timeout=120, kernel_name="python3").execute()
    (result,) = [o for o in nb.cells[0].outputs if o.output_type == "execute_result"]
    assert base64.b64decode(result["data"]["image/png"]).startswith(PNG_MAGIC)
