"""The nilpotent approximation of your own system: from Python, or from a model file.

Run:  python examples/02_approximate_any_system.py [OUT_DIR]
"""

import sys
import tempfile
from pathlib import Path

import sympy as sp

from nilpotent import ControlSystem, approximate, load_model_file

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp())

# 1. In Python: a unicycle with a trailer-like coupling, X1 = (cos θ, sin θ, 0, sin(φ−θ)/L), X2 = ∂θ
x, y, th, ph = sp.symbols("x y theta phi")
L = sp.Symbol("L")
mine = ControlSystem(
    "unicycle-with-trailer",
    (x, y, th, ph),
    ((sp.cos(th), sp.sin(th), 0, sp.sin(th - ph) / L), (0, 0, 1, 0)),
    parameters=(("L", sp.Integer(2)),),
    description="a unicycle pulling a trailer of length L",
)
approx = approximate(mine)  # at the origin, cheapest privileged coordinates
print(approx)
print("weights:", approx.filtration.weights, "method:", approx.coordinates.method)
print("certificate:", approx.certificate)

# 2. From a model file (TOML; the expressions are parsed by a safe grammar, never eval'd)
model = out / "engel-like.toml"
model.write_text(
    'name = "engel-like"\n'
    'coordinates = ["x1", "x2", "x3", "x4"]\n'
    "[[fields]]\n"
    'x1 = "1"\n'
    "[[fields]]\n"
    'x2 = "1"\n'
    'x3 = "x1"\n'
    'x4 = "x1**2/2 + sin(x2)"\n'
)
engel = load_model_file(model)
approx = approximate(engel)
print(f"\n{engel.name}: weights {approx.filtration.weights}")
for i, field in enumerate(approx.fields, start=1):
    print(f"  X̂{i} =", field)
print(f"(model file written to {model})")
