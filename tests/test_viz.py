"""Figures and animations: geometry drawn where it should be, files valid, slopes fitted."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.figure import Figure
from PIL import Image

from nilpotent.errors import OptionError
from nilpotent.models.trident import TridentGeometry
from nilpotent.viz import (
    animate_motion_comparison,
    draw_trident,
    fit_slope,
    html_player,
    plot_bracket_motion,
    plot_error_scaling,
    plot_motion_comparison,
    plot_paper_singular_set,
    save_animation,
    save_figure,
    update_trident,
)


def _loop(T: int = 25, scale: float = 0.3) -> np.ndarray:
    """A closed joint-angle loop (not a solution of anything; drawing only)."""
    s = np.linspace(0, 2 * np.pi, T)
    q = np.zeros((T, 6))
    q[:, 0] = scale * np.sin(s)
    q[:, 3] = scale * np.sin(s)
    q[:, 4] = scale * (1 - np.cos(s))
    q[:, 5] = -scale * np.sin(2 * s)
    return q


def test_robot_body_is_an_equilateral_triangle_of_circumradius_r() -> None:
    fig = Figure()
    ax = fig.subplots()
    r, l = 1.5, 0.7
    geom = TridentGeometry(r, l)
    q = [0.3, -0.2, 0.4, 0.1, -0.5, 0.9]
    art = draw_trident(ax, q, geom)
    verts = np.asarray(art.body.get_xy())[:3]
    sides = [np.linalg.norm(verts[i] - verts[(i + 1) % 3]) for i in range(3)]
    assert np.allclose(sides, np.sqrt(3) * r)  # side of an equilateral triangle
    assert np.allclose(np.linalg.norm(verts - q[:2], axis=1), r)
    for i in range(3):  # each leg has length l and ends at the wheel's centre
        xs, ys = art.legs[i].get_data()
        assert np.hypot(xs[1] - xs[0], ys[1] - ys[0]) == pytest.approx(l)
        wx, wy = art.wheels[i].get_data()
        assert np.mean(wx) == pytest.approx(xs[1]) and np.mean(wy) == pytest.approx(ys[1])
    update_trident(art, [0, 0, 0, 0, 0, 0], geom)
    assert np.allclose(np.asarray(art.body.get_xy())[0], [r, 0])


def test_motion_figures_have_labelled_axes_and_save(tmp_path) -> None:
    q = _loop()
    fig, (ax, axt) = plot_bracket_motion(q, times=np.linspace(0, 1, len(q)), title="t")
    assert ax.get_xlabel() == "x / r" and ax.get_ylabel() == "y / r"
    assert "rad" in axt.get_ylabel()
    paths = save_figure(fig, tmp_path, "motion", formats=("png", "svg", "pdf"))
    assert [p.suffix for p in paths] == [".png", ".svg", ".pdf"]
    assert paths[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert b"<svg" in paths[1].read_bytes()[:2000]
    assert paths[2].read_bytes()[:4] == b"%PDF"
    other = q + 0.01 * np.sin(np.linspace(0, 3, len(q)))[:, None]
    _fig2, (_ax, axt2) = plot_motion_comparison(q, other)
    drawn = [np.asarray(line.get_ydata(), dtype=float) for line in axt2.lines]
    for traj in (q, other):  # each coordinate's change of both runs is drawn against time
        for j in range(6):
            change = traj[:, j] - traj[0, j]
            assert any(d.shape == change.shape and np.allclose(d, change) for d in drawn), j


def test_bad_shapes_are_option_errors(tmp_path) -> None:
    with pytest.raises(OptionError):
        plot_bracket_motion(np.zeros((5, 4)))
    with pytest.raises(OptionError):
        plot_motion_comparison(np.zeros((5, 6)), np.zeros((6, 6)))
    with pytest.raises(OptionError):
        save_figure(Figure(), tmp_path / "missing", "x")
    with pytest.raises(OptionError):
        save_figure(Figure(), tmp_path, "x", formats=("bmp",))


@settings(max_examples=25, deadline=None)
@given(st.floats(0.5, 4.0), st.floats(0.01, 100.0))
def test_fit_slope_recovers_power_laws(k: float, c: float) -> None:
    a = np.geomspace(0.01, 0.5, 7)
    slope, intercept = fit_slope(a, c * a**k)
    assert slope == pytest.approx(k, abs=1e-9)
    assert 10**intercept == pytest.approx(c, rel=1e-9)


def test_error_plot_reports_slopes() -> None:
    a = np.geomspace(0.02, 0.4, 5)
    _fig, ax, slopes = plot_error_scaling(a, {"w1": a**2, "w2": a**3}, lower_bounds={"w1": 2})
    assert slopes["w1"] == pytest.approx(2) and slopes["w2"] == pytest.approx(3)
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("theory ≥ 2" in s for s in labels)


def _wheels_collinearity(x4: float, x5: float, x6: float) -> float:
    """Cross product of p2 − p1 and p3 − p1, ``p_i = e^{ic_i}(1 + e^{i x_{3+i}})`` (r = l = 1).

    The wheels' body-frame positions for the paper's offsets ``c = (−2π/3, 0, 2π/3)``;
    collinear (0) exactly on the singular set (``paper_singular_locus``' derivation).
    """
    c = np.array([-2 * np.pi / 3, 0.0, 2 * np.pi / 3])
    p = np.exp(1j * c) * (1 + np.exp(1j * np.array([x4, x5, x6])))
    a, b = p[1] - p[0], p[2] - p[0]
    return float(a.real * b.imag - a.imag * b.real)


def test_singular_set_panels_draw_where_the_wheels_are_collinear() -> None:
    from nilpotent.viz.singular import DEFAULT_SLICES

    _fig, axes = plot_paper_singular_set(resolution=161)
    assert len(axes) == len(DEFAULT_SLICES)
    for ax, (x6, _label) in zip(axes, DEFAULT_SLICES, strict=True):
        assert "rad" in ax.get_xlabel()
        zero_set = ax.collections[-1]  # the black level-0 contour
        points = np.concatenate([path.vertices for path in zero_set.get_paths()])
        assert len(points) > 20  # the singular set crosses every panel
        worst = max(abs(_wheels_collinearity(a, b, x6)) for a, b in points)
        assert worst < 2e-3, (x6, worst)
        # and the origin, marked in every panel, is regular: the wheels form a triangle
        (marker,) = [line for line in ax.lines if line.get_marker() == "o"]
        assert tuple(marker.get_xydata()[0]) == (0.0, 0.0)
        assert abs(_wheels_collinearity(0.0, 0.0, 0.0)) > 1.0


def test_html_player_is_self_contained() -> None:
    page = html_player([b"\x89PNG-one", b"\x89PNG-two", b"\x89PNG-three"], title="a <b>")
    assert page.count("data:image/png;base64,") == 3 + 1  # three frames + the first shown
    assert not re.search(r"(src|href)=\"(https?:)?//", page)
    assert "a &lt;b&gt;" in page and 'data-frames="3"' in page
    with pytest.raises(OptionError):
        html_player([])


def test_animation_files(tmp_path) -> None:
    q = _loop(T=12)
    anim = animate_motion_comparison(q, q * 1.1, frames=5, title="loop")
    files = save_animation(anim, tmp_path, "loop", dpi=40)
    with Image.open(files.gif) as gif:
        assert gif.n_frames == 5
    text = files.html.read_text()
    assert text.count("data:image/png;base64,") == 5 + 1
    assert files.frames == 5
    with pytest.raises(OptionError):
        animate_motion_comparison(q, q[:5])
