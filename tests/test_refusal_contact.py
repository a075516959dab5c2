"""A configuration refused for touching the world names what it touches and how deep.

Hand derivations on ``examples/worlds/room.toml`` (a wall ``x ∈ [4, 4.6]`` above
``y = 2.5``, a disc of radius 0.8 at ``(9, 2.5)``, bounds ``x ∈ [-5, 13]``) with the
trident snake (``r = l = 1``, legs straight: its wheels 2 from the centre).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from nilpotent.models import get_model
from nilpotent.planning.verify import Checker
from nilpotent.planning.world import load_world

ROOM = Path(__file__).resolve().parents[1] / "examples" / "worlds" / "room.toml"


@pytest.fixture(scope="module")
def checker():
    return Checker(get_model("trident-snake"), load_world(ROOM))


def _depth(text: str) -> float:
    return float(re.search(r"\(by ([-0-9.e+]+)\)", text).group(1))


def test_a_body_across_the_wall_overlaps_it_by_half_its_width(checker):
    # the body triangle (vertices 1 from (4.3, 4)) spans x 3.8..5.3 at y = 4: it covers the
    # wall's width 0.6, whose middle is 0.3 from its sides
    why = checker.why_invalid((4.3, 4.0, 0.0, 0.0, 0.0, 0.0))
    assert "polygon obstacle" in why and "(4, 2.5)" in why
    assert _depth(why) == pytest.approx(0.3, abs=2e-3)


def test_a_body_on_the_disc_centre_overlaps_it_by_its_radius(checker):
    why = checker.why_invalid((9.0, 2.5, 0.0, 0.0, 0.0, 0.0))
    assert "disc obstacle at (9, 2.5) of radius 0.8" in why
    assert _depth(why) == pytest.approx(0.8, abs=5e-3)


def test_a_goal_beyond_the_bounds_says_by_how_far(checker):
    # leg 1 points along +x: its wheel at x = 20 + 2 = 22, 9 beyond x = 13
    why = checker.why_invalid((20.0, 0.0, 0.0, 0.0, 0.0, 0.0))
    assert "leaves the bounds" in why and "obstacle" not in why
    assert _depth(why) == pytest.approx(9.0, abs=1e-9)


def test_an_admissible_configuration_has_no_reason(checker):
    assert checker.why_invalid((0.0, 0.0, 0.0, 0.0, 0.0, 0.0)) == ""
