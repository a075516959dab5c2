"""A bracket motion of the trident snake against its nilpotent approximation; saves a figure.

The loop u1 = −Aω sin ωt, u2 = Aω cos ωt moves the robot by about πA²[X1, X2](p).

Run:  python examples/03_bracket_motion.py [OUT_DIR]
"""

import sys
import tempfile
from pathlib import Path

import sympy as sp

from nilpotent import compare_bracket_motion, get_model

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp())

snake = get_model("trident-snake")
comp = compare_bracket_motion(snake, (1, 2), amplitude=0.2, point={"phi1": sp.pi / 10})
# (exact values: the privileged coordinates are decided exactly at p)

print("end point, original:      ", comp.final_original.round(6))
print("end point, approximation: ", comp.final_approximation.round(6))
print("prediction p + πA²[X1,X2]:", comp.prediction.round(6))
print("end-point difference:     ", f"{comp.endpoint_error:.2e}")
for w, e in comp.errors_by_weight.items():
    print(f"  weight {w}: max |y − ŷ| = {e:.2e}")

fig, _ = comp.plot()
path = out / "bracket_motion.png"
fig.savefig(path, dpi=100)
print(f"figure: {path}")
