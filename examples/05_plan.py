"""Steer the unicycle and the trident snake between two points with sinusoidal controls.

``nilpotent.steer`` is the local steering of the true system (no world, no limits);
``nilpotent.plan`` is what the command ``nilpotent plan`` does (a global plan, with a
world, limits and margins, made of such local steerings).

Run:  python examples/05_plan.py [OUT_DIR]
"""

import json
import sys
import tempfile
from pathlib import Path

from nilpotent import get_model, steer

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp())

# A sideways parking move: the unicycle cannot go along y directly ([X1, X2] does it).
p = steer(get_model("unicycle"), (0, 0, 0), (0.0, 0.1, 0.0), tol=1e-8)
print(f"unicycle: reached {p.reached} (error {p.error:.1e}) in {len(p.iterations)} iterations, "
      f"{len(p.segments)} segments")

# The trident snake: move the body sideways and turn it a little.
snake = get_model("trident-snake")
goal = (0.0, 0.05, 0.05, 0.0, 0.0, 0.0)
q = steer(snake, (0,) * 6, goal, tol=1e-6)
print(f"trident snake: error {q.error:.1e}, converged {q.converged}")

# The plan as data: the `nilpotent/plan@1` object of docs/interface.md (segments of sinusoids).
# `to_json()` is strict JSON: a number that is not finite is null and listed under
# "undefined", so `allow_nan=False` (the JSON standard) always holds.
path = out / "plan.json"
path.write_text(json.dumps(q.to_json(), indent=1, allow_nan=False))
print(f"plan: {path}")
