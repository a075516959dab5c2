"""Figures display in Jupyter without ``%matplotlib inline``.

The figures of :mod:`nilpotent.viz` are :class:`matplotlib.figure.Figure` objects built
without pyplot (no global state, no GUI backend).  IPython only knows how to show a
``Figure`` once its inline backend is activated, which happens when pyplot is imported
or ``%matplotlib inline`` is run; a notebook that only calls ``result.plot()`` would
show ``<Figure size 1000x420 with 2 Axes>``.  :func:`enable_figure_display` gives
IPython the same PNG formatter ``%matplotlib inline`` installs (IPython's own
``print_figure``, cropped to the drawn area), and only where no formatter for
``Figure`` is registered yet: a user's ``%matplotlib`` choice is left alone.  Outside
IPython it does nothing, and it never imports IPython.
"""

from __future__ import annotations

import sys
from functools import partial
from typing import Any


def enable_figure_display(shell: Any = None) -> bool:
    """Register a PNG display of matplotlib figures with the running IPython shell.

    Parameters
    ----------
    shell : IPython.core.interactiveshell.InteractiveShell or None
        The shell; default: the running one (``IPython.get_ipython()``), none when
        IPython is not imported.

    Returns
    -------
    bool
        Whether a formatter for figures is now registered (``False`` outside IPython).
    """
    if shell is None:
        ipython = sys.modules.get("IPython")
        get = getattr(ipython, "get_ipython", None)
        shell = get() if get is not None else None
    formatters = getattr(getattr(shell, "display_formatter", None), "formatters", None)
    if not formatters or "image/png" not in formatters:
        return False
    from matplotlib.figure import Figure

    png = formatters["image/png"]
    if any(Figure in f.type_printers for f in formatters.values()):
        return True  # the inline backend (or the user) already shows figures
    from IPython.core.pylabtools import print_figure

    png.for_type(Figure, partial(print_figure, fmt="png", base64=True, bbox_inches="tight"))
    return True
