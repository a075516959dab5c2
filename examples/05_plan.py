"""Steer the unicycle and the trident snake between two points with sinusoidal controls.

Run:  python examples/05_plan.py [OUT_DIR]
"""

import json
import sys
import tempfile
from pathlib import Path

from nilpotent import get_model, plan

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp())

# A sideways parking move: the unicycle cannot go along y directly ([X1, X2] does it).
p = plan(get_model("unicycle"), (0, 0, 0), (0.0, 0.1, 0.0), tol=1e-8)
print(f"unicycle: reached {p.reached} (error {p.error:.1e}) in {len(p.iterations)} iterations, "
      f"{len(p.segments)} segments")

# The trident snake: move the body sideways and turn it a little.
snake = get_model("trident-snake")
goal = (0.0, 0.05, 0.05, 0.0, 0.0, 0.0)
q = plan(snake, (0,) * 6, goal, tol=1e-6)
print(f"trident snake: error {q.error:.1e}, converged {q.converged}")

# The plan as data: the `nilpotent/plan@1` object of INTERFACE.md (segments of sinusoids)
path = out / "plan.json"
path.write_text(json.dumps(q.to_json(), indent=1))
print(f"plan: {path}")
