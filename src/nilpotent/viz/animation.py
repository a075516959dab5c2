"""Animations of the trident snake performing a bracket motion, original beside approximation.

:func:`animate_motion_comparison` builds a two-panel figure (left: the original
system, right: its nilpotent approximation; the same inputs) and a
:class:`matplotlib.animation.FuncAnimation` over the samples of the two
trajectories.  :func:`save_animation` writes it as

* a GIF (matplotlib's ``PillowWriter``; always available),
* an MP4 where ffmpeg is installed (``FFMpegWriter.isAvailable()``), and
* a self-contained HTML player (:func:`html_player`): every frame embedded as a
  base64 PNG, a few lines of inline JavaScript (play/pause, slider, speed), no
  network access — it works offline, opened straight from disk.

The player carries a self-check: once every frame has decoded it writes
``data-frames-loaded`` and ``data-errors`` on the element ``#player-selfcheck``,
which a headless browser reads (``tests/test_browser.py``).
"""

from __future__ import annotations

import base64
import html
import io
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.animation import FuncAnimation
from matplotlib.artist import Artist
from matplotlib.figure import Figure

from nilpotent.errors import OptionError
from nilpotent.models.trident import TridentGeometry
from nilpotent.viz.robot import LEG_COLORS, draw_trident, update_trident

__all__ = [
    "AnimationFiles",
    "MotionAnimation",
    "animate_motion_comparison",
    "html_player",
    "save_animation",
]


@dataclass(frozen=True)
class MotionAnimation:
    """A figure, a per-frame update and the matplotlib animation driving it."""

    figure: Figure
    update: Callable[[int], tuple[Artist, ...]]
    frames: int
    animation: FuncAnimation
    title: str


@dataclass(frozen=True)
class AnimationFiles:
    """Where :func:`save_animation` wrote an animation (``mp4`` is None without ffmpeg)."""

    gif: Path
    html: Path
    mp4: Path | None
    frames: int


def _subsample(q: np.ndarray, frames: int) -> np.ndarray:
    idx = np.unique(np.linspace(0, q.shape[0] - 1, frames).round().astype(int))
    return idx


def animate_motion_comparison(
    q_original: np.ndarray,
    q_approx: np.ndarray,
    geometry: TridentGeometry | None = None,
    *,
    times: np.ndarray | None = None,
    frames: int = 60,
    title: str = "",
    labels: tuple[str, str] = ("original fields", "nilpotent approximation"),
    figsize: tuple[float, float] = (8.0, 4.0),
    interval_ms: int = 80,
) -> MotionAnimation:
    """Animate one motion for the original system (left) and the approximation (right).

    Parameters
    ----------
    q_original, q_approx:
        ``(T, 6)`` trajectories at the same times, in the coordinates
        ``geometry`` reads.
    geometry:
        Default ``TridentGeometry()``.
    times:
        ``(T,)`` sample times, shown in the title of each frame.
    frames:
        Number of frames (samples are picked evenly; at most ``T``).
    title, labels, figsize, interval_ms:
        Figure title, panel titles, size, delay between frames.
    """
    qo = np.asarray(q_original, dtype=float)
    qa = np.asarray(q_approx, dtype=float)
    if qo.ndim != 2 or qo.shape[1] != 6 or qo.shape != qa.shape or qo.shape[0] < 2:
        raise OptionError(
            f"need two (T, 6) trajectories of equal shape, got {qo.shape}, {qa.shape}"
        )
    if frames < 2:
        raise OptionError(f"an animation needs at least 2 frames, got {frames}")
    geom = geometry if geometry is not None else TridentGeometry()
    idx = _subsample(qo, frames)
    t = np.arange(qo.shape[0], dtype=float) if times is None else np.asarray(times, float)
    fig = Figure(figsize=figsize)  # fixed margins: a layout engine per frame is slow
    fig.subplots_adjust(left=0.09, right=0.98, bottom=0.12, top=0.86, wspace=0.08)
    axes = fig.subplots(1, 2, sharex=True, sharey=True)
    both = np.concatenate([qo, qa])
    pts = np.concatenate([geom.wheels(both).reshape(-1, 2), geom.vertices(both).reshape(-1, 2)])
    lo, hi = pts.min(axis=0) - 0.3 * geom.r, pts.max(axis=0) + 0.3 * geom.r
    robots = []
    trails = []
    for ax, q, label in zip(axes, (qo, qa), labels, strict=True):
        wheels = geom.wheels(q)
        for i in range(3):
            ax.plot(wheels[:, i, 0], wheels[:, i, 1], color=LEG_COLORS[i], linewidth=0.6, alpha=0.3)
        centre = geom.body_centre(q)
        ax.plot(centre[:, 0], centre[:, 1], color="black", linewidth=0.6, alpha=0.3)
        draw_trident(ax, q[0], geom, alpha=0.25, linestyle="--", zorder=2)
        robots.append(draw_trident(ax, q[0], geom))
        lines = tuple(ax.plot([], [], color=LEG_COLORS[i], linewidth=1.4)[0] for i in range(3))
        trails.append(lines)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal")
        ax.set_title(label, fontsize=10)
        ax.set_xlabel("x / r")
        ax.grid(True, linewidth=0.3, alpha=0.5)
    axes[0].set_ylabel("y / r")
    heading = fig.suptitle(title, fontsize=10)

    def update(k: int) -> tuple[Artist, ...]:
        s = int(idx[k])
        changed: list[Artist] = []
        for q, robot, lines in zip((qo, qa), robots, trails, strict=True):
            update_trident(robot, q[s], geom)
            wheels = geom.wheels(q[: s + 1])
            for i in range(3):
                lines[i].set_data(wheels[:, i, 0], wheels[:, i, 1])
            changed += [*robot.all(), *lines]
        heading.set_text(f"{title}   t = {t[s]:.2f} s")
        return (*changed, heading)

    anim = FuncAnimation(fig, update, frames=len(idx), interval=interval_ms, blit=False)
    return MotionAnimation(fig, update, len(idx), anim, title)


def _frame_png(anim: MotionAnimation, k: int, dpi: int) -> bytes:
    anim.update(k)
    buf = io.BytesIO()
    anim.figure.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def html_player(
    frames: Sequence[bytes], *, title: str = "", fps: float = 12.0, mime: str = "image/png"
) -> str:
    """A self-contained HTML page that plays ``frames`` (encoded images), offline.

    Frames are embedded as base64 data URIs; the inline script preloads them,
    then plays at ``fps`` with play/pause, a frame slider and a speed choice.
    ``#player-selfcheck`` receives ``data-frames``, ``data-frames-loaded`` and
    ``data-errors`` (frames that failed to decode plus script errors).
    """
    if not frames:
        raise OptionError("an HTML player needs at least one frame")
    uris = [f"data:{mime};base64,{base64.b64encode(f).decode('ascii')}" for f in frames]
    data = ",\n".join(f'"{u}"' for u in uris)
    name = html.escape(title or "animation")
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{name}</title>
<style>
body {{ font-family: system-ui, sans-serif; margin: 1em; color: #222; }}
.player img {{ max-width: 100%; border: 1px solid #ccc; }}
.controls {{ display: flex; gap: .6em; align-items: center; margin: .4em 0; }}
.controls input[type=range] {{ flex: 1; }}
</style></head>
<body>
<div class="player">
<h1 style="font-size:1.1em">{name}</h1>
<img id="player-frame" alt="{name}" src="{uris[0]}">
<div class="controls">
<button id="player-play" type="button">pause</button>
<input id="player-slider" type="range" min="0" max="{len(uris) - 1}" value="0"
 aria-label="frame">
<span id="player-counter">1 / {len(uris)}</span>
<label>speed <select id="player-speed"><option value="0.5">½×</option>
<option value="1" selected>1×</option><option value="2">2×</option></select></label>
</div>
<div id="player-selfcheck" data-frames="{len(uris)}" data-frames-loaded="0" data-errors="0"
 data-done="false"></div>
</div>
<script>
(function () {{
  var frames = [{data}];
  var check = document.getElementById("player-selfcheck");
  var errors = 0;
  window.addEventListener("error", function () {{
    errors += 1; check.dataset.errors = String(errors);
  }});
  var img = document.getElementById("player-frame");
  var slider = document.getElementById("player-slider");
  var counter = document.getElementById("player-counter");
  var button = document.getElementById("player-play");
  var speed = document.getElementById("player-speed");
  var k = 0, playing = true, loaded = 0, timer = null;
  function show(i) {{
    k = i; img.src = frames[k]; slider.value = String(k);
    counter.textContent = (k + 1) + " / " + frames.length;
  }}
  function tick() {{ show((k + 1) % frames.length); }}
  function restart() {{
    if (timer) {{ clearInterval(timer); timer = null; }}
    if (playing) {{ timer = setInterval(tick, 1000 / ({fps} * Number(speed.value))); }}
  }}
  frames.forEach(function (src) {{
    var pre = new Image();
    pre.onload = function () {{
      if (pre.naturalWidth > 0) {{ loaded += 1; }} else {{ errors += 1; }}
      check.dataset.framesLoaded = String(loaded); check.dataset.errors = String(errors);
      if (loaded + errors === frames.length) {{ check.dataset.done = "true"; }}
    }};
    pre.onerror = function () {{
      errors += 1; check.dataset.errors = String(errors);
      if (loaded + errors === frames.length) {{ check.dataset.done = "true"; }}
    }};
    pre.src = src;
  }});
  button.addEventListener("click", function () {{
    playing = !playing; button.textContent = playing ? "pause" : "play"; restart();
  }});
  slider.addEventListener("input", function () {{
    playing = false; button.textContent = "play"; restart(); show(Number(slider.value));
  }});
  speed.addEventListener("change", restart);
  restart();
}})();
</script>
</body></html>
"""


def save_animation(
    anim: MotionAnimation,
    directory: str | Path,
    stem: str,
    *,
    fps: float = 12.0,
    dpi: int = 80,
    mp4: bool = True,
) -> AnimationFiles:
    """Write ``stem.gif``, ``stem.html`` (self-contained player) and, with ffmpeg, ``stem.mp4``.

    Parameters
    ----------
    anim:
        From :func:`animate_motion_comparison`.
    directory:
        An existing folder.
    fps, dpi:
        Frames per second and resolution of the written frames.
    mp4:
        Also write an MP4 where ``FFMpegWriter.isAvailable()``.
    """
    from matplotlib.animation import FFMpegWriter, PillowWriter

    from nilpotent.progress import progress

    out = Path(directory)
    if not out.is_dir():
        raise OptionError(f"cannot save the animation: {out} is not a folder")
    gif = out / f"{stem}.gif"
    with_mp4 = mp4 and FFMpegWriter.isAvailable()
    passes: tuple[str, ...] = ("GIF", "MP4", "HTML player") if with_mp4 else ("GIF",
                                                                              "HTML player")
    n = anim.frames
    with progress(f"animation {stem}: frames", total=n * len(passes)) as bar:

        def frame_done(k: int, _total: int, done: int) -> None:
            bar.update(done + k + 1)

        # matplotlib's stubs say int; the writers take any positive frame rate
        anim.animation.save(gif, writer=PillowWriter(fps=fps), dpi=dpi,  # pyright: ignore[reportArgumentType]
                            progress_callback=lambda k, t: frame_done(k, t, 0))
        bar.update(n, detail=passes[1])
        video: Path | None = None
        if with_mp4:
            video = out / f"{stem}.mp4"
            anim.animation.save(video, writer=FFMpegWriter(fps=fps), dpi=dpi,  # pyright: ignore[reportArgumentType]
                                progress_callback=lambda k, t: frame_done(k, t, n))
            bar.update(2 * n, detail=passes[-1])
        frames = []
        for k in range(n):
            frames.append(_frame_png(anim, k, dpi))
            bar.update((len(passes) - 1) * n + k + 1)
    page = out / f"{stem}.html"
    page.write_text(html_player(frames, title=anim.title, fps=fps), encoding="utf-8")
    return AnimationFiles(gif, page, video, anim.frames)
