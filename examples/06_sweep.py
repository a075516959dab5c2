"""A sweep of bracket motions over amplitudes and start points near p; CSV + summary.

Over one period the loop frequency ω drops out (s = ωt), so the sweep is over (A, q0).
Locally the batched numba engine runs the chunks; pass `local` (or a scheduler address)
as the second argument to run them on Dask (pip install "nilpotent[dask]").

Run:  python examples/06_sweep.py [OUT_DIR] [local|tcp://HOST:8786]
"""

import json
import sys
import tempfile
from pathlib import Path

from nilpotent import amplitude_range, get_model
from nilpotent.simulation import sweep


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp())
    dask = sys.argv[2] if len(sys.argv) > 2 else None

    result = sweep(
        get_model("trident-snake"),
        (1, 2),
        amplitude_range(0.02, 0.16, 4),  # log-spaced
        samples=25,  # random start points q0 ...
        radius=1e-3,  # ... uniform in the ball of radius 0.001 round p = 0 (|q0 - p| << A)
        seed=1,
        dask=dask,
        chunk_size=4096 if dask is None else 1000,
    )
    print(f"{len(result)} pairs of trajectories on {result.engine} ({result.backend}), "
          f"{result.wall_time:.2f} s; blow-ups: {result.summary()['blow_ups']}")
    for fit in result.fits():
        for w, slope in fit["slopes"].items():
            print(f"weight {w}: error ~ A^{slope:.2f} (expected A^{fit['expected_slopes'][w]})")
    fig, _ = result.plot()
    fig.savefig(out / "sweep.png", dpi=100)
    result.to_csv(out / "sweep.csv")
    (out / "sweep.json").write_text(json.dumps(result.to_json(), indent=1))
    print(f"rows: {out / 'sweep.csv'}")


if __name__ == "__main__":  # needed for Dask: its workers are spawned processes
    main()
