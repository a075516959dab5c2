"""How the approximation error scales with the loop amplitude: slope w + 1 per weight group.

Run:  python examples/04_scaling.py [OUT_DIR]
"""

import sys
import tempfile
from pathlib import Path

from nilpotent import get_model, scaling_study

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp())

study = scaling_study(get_model("trident-snake"), (1, 2), [0.01, 0.02, 0.04, 0.08, 0.16])
for w, slope in study.slopes.items():
    shown = "exact" if slope is None else f"{slope:.3f}"
    print(f"weight {w}: fitted slope {shown} (expected {study.expected_slopes[w]})")

fig, _ = study.plot()
path = out / "scaling.png"
fig.savefig(path, dpi=100)
print(f"figure: {path}")
