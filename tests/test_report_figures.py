"""The reproduction's multi-panel figure: each panel draws its errors, names exact groups."""

from __future__ import annotations

import numpy as np
import pytest

import nilpotent as nil
from nilpotent.viz import plot_amplitude_panels


def _drawn(ax) -> list[np.ndarray]:
    return [np.asarray(line.get_ydata(), dtype=float) for line in ax.lines]


def test_each_panel_draws_its_studys_errors_and_names_exact_groups() -> None:
    amps = [0.02, 0.04, 0.08]
    unicycle = nil.scaling_study(nil.get_model("unicycle"), (1, 2), amps)
    heisenberg = nil.scaling_study(nil.get_model("heisenberg"), (1, 2), amps)  # its own approx.
    fig, axes = plot_amplitude_panels([((1, 2), unicycle), ((2, 1), heisenberg)], "two models")
    assert len(axes) == 2 and "two models" in fig.get_suptitle()
    assert axes[0].get_title() == "[g1,g2]" and axes[1].get_title() == "[g2,g1]"
    for w, errors in unicycle.errors.items():
        assert unicycle.slopes[w] is not None
        assert any(d.shape == errors.shape and np.allclose(d, errors) for d in _drawn(axes[0])), w
    exact = [w for w, s in heisenberg.slopes.items() if s is None]
    assert exact  # the nilpotent Heisenberg system: errors at round-off
    notes = " ".join(t.get_text() for t in axes[1].texts)
    assert all(f"weight {w}" in notes for w in exact) and "exact" in notes
    assert axes[0].get_xscale() == axes[0].get_yscale() == "log"


def test_no_study_is_refused() -> None:
    with pytest.raises(ValueError, match="at least one study"):
        plot_amplitude_panels([], "nothing")
