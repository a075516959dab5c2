"""The reproduction page in a real browser: headless Chromium, offline, from disk.

The page and the animation players carry self-checks (inline JavaScript) that
write, once loaded, how many images decoded and how many script errors
happened onto an element; ``chromium --headless --dump-dom`` prints the DOM
after a virtual-time budget and the test reads those attributes.  Console
messages are captured from Chromium's own log (``--enable-logging=stderr``):
the page logs nothing, so any ``CONSOLE`` line is a failure.  A screenshot of
the page goes to ``test-artifacts/``.

Chromium comes from the Debian package ``chromium``; the set-up installs it
with ``apt-get`` when it is missing and the tests run as root, and skips with
the reason otherwise.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest

pytestmark = [pytest.mark.browser, pytest.mark.slow]

ARTIFACTS = Path(__file__).resolve().parents[1] / "test-artifacts"
FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--enable-logging=stderr",
    "--v=0",
)


def _find_chromium() -> str | None:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return "/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else None


@pytest.fixture(scope="module")
def chromium() -> str:
    path = _find_chromium()
    if path:
        return path
    if os.geteuid() != 0:
        pytest.skip(
            "Chromium is not installed and the tests do not run as root, so the "
            "set-up cannot `apt-get install -y chromium`; install it to run these"
        )
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    steps = (["apt-get", "update"], ["apt-get", "install", "-y", "chromium"])
    for cmd in steps:
        done = subprocess.run(
            cmd, env=env, capture_output=True, text=True, timeout=1200, check=False
        )
        if done.returncode != 0:
            pytest.skip(
                f"`{' '.join(cmd)}` failed ({done.returncode}): {done.stderr.strip()[-300:]}"
            )
    path = _find_chromium()
    if path is None:
        pytest.skip("apt-get installed chromium but no chromium executable was found")
    return path


@pytest.fixture(scope="module")
def site(quick_reproduction) -> Path:
    """The suite's one quick reproduction (``tests/conftest.py``; read only here)."""
    status, _, _, result = quick_reproduction
    assert status == 0
    return result.out_dir


def _run(chromium: str, *args: str, timeout: int = 180) -> subprocess.CompletedProcess[str]:
    with tempfile.TemporaryDirectory(prefix="chromium-profile-") as profile:
        return subprocess.run(
            [chromium, *FLAGS, f"--user-data-dir={profile}", *args],
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
        )


def _attrs(dom: str, element_id: str) -> dict[str, str]:
    m = re.search(rf'<[^>]*\bid="{element_id}"[^>]*>', dom)
    assert m, f"#{element_id} not found in the dumped DOM"
    return dict(re.findall(r'(data-[\w-]+)="([^"]*)"', m.group(0)))


def _console_lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if ":CONSOLE" in line]


def test_page_loads_every_image_without_errors(chromium: str, site: Path) -> None:
    url = (site / "index.html").as_uri()
    done = _run(chromium, "--virtual-time-budget=15000", "--dump-dom", url)
    assert done.returncode == 0, done.stderr[-2000:]
    check = _attrs(done.stdout, "selfcheck")
    assert check.get("data-done") == "true", check
    assert int(check["data-images"]) >= 10, check
    assert check["data-images-loaded"] == check["data-images"], check
    assert check["data-missing"] == "", check
    assert check["data-errors"] == "0", check
    assert _console_lines(done.stderr) == []
    # the GIF animations are among the images that loaded
    assert len(re.findall(r'<img src="figures/anim_\w+\.gif"', done.stdout)) == 3


def test_formulas_are_sized_mathml_with_their_latex(chromium: str, site: Path) -> None:
    """Every formula is a MathML element the browser laid out (non-empty box), with its LaTeX."""
    source = (site / "index.html").read_text(encoding="utf-8")
    assert "<script src" not in source and "http://" not in source.replace(
        "http://www.w3.org/1998/Math/MathML", ""
    )
    assert "https://" not in source
    url = (site / "index.html").as_uri()
    done = _run(chromium, "--virtual-time-budget=15000", "--dump-dom", url)
    assert done.returncode == 0, done.stderr[-2000:]
    check = _attrs(done.stdout, "selfcheck")
    assert check.get("data-done") == "true", check
    # the fields (3 + 3), frames (2 x 6), coordinates (2 x 6), approximations (2 x 6),
    # brackets (3 x 4) and the matrices are all typeset
    assert int(check["data-formulas"]) >= 60, check
    assert check["data-formulas-sized"] == check["data-formulas"], check
    assert check["data-errors"] == "0", check
    assert _console_lines(done.stderr) == []
    # a long formula is typeset in pieces inside one ``formula wrapped`` element
    spans = re.findall(r'<(?:span|div) class="formula(?: wrapped)?" data-latex="([^"]+)"><math',
                       done.stdout)
    assert len(spans) == int(check["data-formulas"])
    assert any("\\partial_{" in s for s in spans) and any("pmatrix" in s for s in spans)
    assert done.stdout.count('class="copy-latex"') == len(spans)


def test_animation_players_load_all_frames(chromium: str, site: Path) -> None:
    players = sorted((site / "figures").glob("anim_*.html"))
    assert len(players) == 3
    for player in players:
        done = _run(chromium, "--virtual-time-budget=10000", "--dump-dom", player.as_uri())
        assert done.returncode == 0, done.stderr[-2000:]
        check = _attrs(done.stdout, "player-selfcheck")
        assert check["data-done"] == "true", (player.name, check)
        assert check["data-frames-loaded"] == check["data-frames"], (player.name, check)
        assert int(check["data-frames"]) >= 2
        assert check["data-errors"] == "0", (player.name, check)
        assert _console_lines(done.stderr) == [], player.name


def test_screenshot(chromium: str, site: Path) -> None:
    ARTIFACTS.mkdir(exist_ok=True)
    shot = ARTIFACTS / "reproduce-index.png"
    if shot.exists():
        shot.unlink()
    done = _run(
        chromium,
        "--virtual-time-budget=10000",
        "--window-size=1280,2400",
        f"--screenshot={shot}",
        (site / "index.html").as_uri(),
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert shot.exists() and shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert shot.stat().st_size > 20_000  # a rendered page, not a blank image


def test_notebook_displays_render_as_sized_mathml(chromium: str, tmp_path: Path) -> None:
    """What Jupyter shows (``_repr_html_``) renders in the browser: every formula sized."""
    import nilpotent as nil
    from nilpotent.report.page import page

    snake = nil.get_model("trident-snake")
    approx = nil.approximate(snake)
    shown = (snake, approx.filtration, approx.coordinates, approx)
    sections = [(f"s{k}", type(obj).__name__, obj._repr_html_()) for k, obj in enumerate(shown)]
    path = tmp_path / "reprs.html"
    path.write_text(page("reprs", "notebook displays", sections), encoding="utf-8")
    done = _run(chromium, "--virtual-time-budget=10000", "--dump-dom", path.as_uri())
    assert done.returncode == 0, done.stderr[-2000:]
    check = _attrs(done.stdout, "selfcheck")
    assert check.get("data-done") == "true", check
    assert int(check["data-formulas"]) >= 40, check
    assert check["data-formulas-sized"] == check["data-formulas"], check
    assert check["data-errors"] == "0" and _console_lines(done.stderr) == []
