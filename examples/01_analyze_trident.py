"""Growth vector, weights and adapted frame of the trident snake, at the origin and elsewhere.

Run:  python examples/01_analyze_trident.py
"""

import sympy as sp

from nilpotent import analyze, get_model, singular_locus

snake = get_model("trident-snake")  # body-velocity inputs; parameters r = l = 1
print(snake)

for point in (snake.origin(), snake.point({"phi1": sp.pi / 6, "phi2": -sp.pi / 4})):
    f = analyze(snake, point)  # exact values: ranks are decided exactly
    print(f"\nat {f.point}")
    print("  bracket generating:", f.bracket_generating)
    print("  growth vector:     ", f.growth_vector)
    print("  weights:           ", f.weights)
    print("  regular:           ", f.regular)
    print("  adapted frame:     ", ", ".join(f.frame_names))

# The frame found at the origin stops being a frame where det = 0 (an exact expression):
det = singular_locus(snake.specialized())
for point in (snake.origin(), snake.point({"phi1": sp.pi / 2, "phi2": sp.pi / 3})):
    value = det.xreplace(dict(zip(snake.coordinates, point, strict=True)))
    print(f"det of the frame at {point}: {float(value):.6f}")
