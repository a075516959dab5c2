"""Snapshot the ``--json`` output of the CLI commands, and compare two snapshots.

Used to check that a refactoring leaves behaviour unchanged (issue 18, item 7):
run it on the tree before and on the tree after, then compare::

    git worktree add /tmp/before <commit>
    PYTHONPATH=/tmp/before/src python tools/json_snapshot.py run /tmp/snap-before
    PYTHONPATH=$PWD/src        python tools/json_snapshot.py run /tmp/snap-after
    python tools/json_snapshot.py compare /tmp/snap-before /tmp/snap-after

``run`` executes every command of :data:`COMMANDS` (``python -m nilpotent ... --json
--quiet``, each in its own process, with a time limit) and writes one file per command,
``<name>.json``: the exit status, the JSON printed on stdout (or the text, when it is
not JSON) and, on a non-zero exit, the last line of stderr (the error message).  Every
run uses its own fresh code cache (``NILPOTENT_CACHE``, a temporary folder removed at the
end): the engine that ``"auto"`` picks for a plan depends on whether compiled kernels are
already on disk, so a shared cache that other processes fill would make two runs of one
tree differ.  The commands use modest sizes (a few seconds each), so the whole run takes
a few minutes on a loaded two-core machine.  Cases come from the published/hostile cases directory
(``--cases``, default ``/work/shared/cases``) and from the built-in models.

``compare`` prints, per command, ``same`` or the JSON paths whose values differ, after
masking the volatile fields of :data:`VOLATILE` (wall-clock timings and file paths:
they differ between two runs of one tree).  Floats are compared exactly (the claim is
byte-identical output); ``--rtol`` relaxes that for a second look.
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

#: Keys whose values are volatile (masked before comparing), wherever they occur:
#: wall-clock timings (``seconds``, ``planner_seconds``, ``elapsed``...) differ
#: between two runs of one tree (a sweep's ``wall_time`` and ``pairs_per_second``
#: too); ``cache``/``path`` name local files.
VOLATILE = frozenset({
    "seconds", "planner_seconds", "elapsed", "elapsed_seconds", "wall_seconds",
    "time_seconds", "timings", "timing", "duration_seconds", "path", "cache",
    "version", "created", "wall_time", "pairs_per_second",
})

#: (name, arguments after ``nilpotent``): ``--json --quiet`` is added to each.
#: ``{cases}`` is replaced by the cases directory.
COMMANDS: list[tuple[str, list[str]]] = [
    # built-ins: analyze
    ("analyze-heisenberg", ["analyze", "heisenberg"]),
    ("analyze-unicycle", ["analyze", "unicycle", "--at", "theta=1"]),
    ("analyze-engel", ["analyze", "engel"]),
    ("analyze-cartan", ["analyze", "cartan"]),
    ("analyze-martinet-singular", ["analyze", "martinet", "--singular-locus"]),
    ("analyze-car-trailers-5", ["analyze", "car-trailers:5", "--at", "theta0=pi,theta1=pi/2"]),
    ("analyze-trident", ["analyze", "trident-snake", "--at", "phi1=pi/7,phi2=pi/5"]),
    ("analyze-trident-2", ["analyze", "trident-snake", "--at", "phi1=1,phi3=1"]),
    # built-ins: approximate
    ("approximate-heisenberg", ["approximate", "heisenberg"]),
    ("approximate-engel-linear", ["approximate", "engel", "--method", "linear"]),
    ("approximate-engel-algebraic", ["approximate", "engel", "--method", "algebraic"]),
    ("approximate-engel-exponential", ["approximate", "engel", "--method", "exponential"]),
    ("approximate-unicycle", ["approximate", "unicycle", "--at", "theta=1/3"]),
    ("approximate-trident", ["approximate", "trident-snake", "--at", "phi1=pi/7,phi2=pi/5"]),
    # built-ins: simulate, scaling, sweep (small)
    ("simulate-heisenberg", ["simulate", "heisenberg", "--bracket", "1,2", "--amplitude", "0.1"]),
    ("simulate-unicycle", ["simulate", "unicycle", "--bracket", "1,2", "--amplitude", "0.2",
                           "--periods", "2", "--at", "theta=1/2"]),
    ("simulate-engel", ["simulate", "engel", "--bracket", "1,2", "--amplitude", "0.05",
                        "--omega", "2"]),
    ("scaling-heisenberg", ["scaling", "heisenberg", "--bracket", "1,2"]),
    ("scaling-unicycle", ["scaling", "unicycle", "--bracket", "1,2",
                          "--amplitudes", "0.05,0.1,0.2"]),
    ("sweep-heisenberg", ["sweep", "heisenberg", "--bracket", "1,2", "--amplitudes",
                          "0.01:0.1:3", "--samples", "4", "--radius", "0.3", "--seed", "1"]),
    ("sweep-unicycle-random", ["sweep", "unicycle", "--bracket", "1,2", "--amplitudes",
                               "0.05,0.1", "--samples", "3", "--design", "random",
                               "--radius", "0.5", "--seed", "2"]),
    ("sweep-car-vary", ["sweep", "car-trailers:1", "--bracket", "1,2", "--amplitudes",
                        "0.05,0.1", "--vary", "d1=1,2"]),
    # built-ins: plan (small)
    ("plan-unicycle", ["plan", "unicycle", "--to", "x=0.1,y=0.1"]),
    ("plan-heisenberg", ["plan", "heisenberg", "--to", "x3=0.1"]),
    ("plan-unicycle-goal-anchor", ["plan", "unicycle", "--to", "y=0.2", "--anchor", "goal"]),
    ("plan-unicycle-tol-bad", ["plan", "unicycle", "--to", "x=0.1", "--tol", "-1"]),
    # shared cases: field
    ("analyze-generic-rank", ["analyze", "{cases}/field/fail-generic-rank.toml",
                              "--at", "x2=1/10"]),
    ("analyze-float-params", ["analyze", "{cases}/field/fail-float-params.toml",
                              "--at", "theta0=pi/2"]),
    ("analyze-grushin-locus", ["analyze", "{cases}/field/fail-singular-locus.toml",
                               "--singular-locus"]),
    ("analyze-hopping-locus", ["analyze", "{cases}/field/hopping-robot.toml",
                               "--singular-locus"]),
    ("analyze-rolling-ball", ["analyze", "{cases}/field/rolling-ball.toml", "--at", "theta=1"]),
    ("analyze-fire-truck", ["analyze", "{cases}/field/fire-truck.toml"]),
    ("analyze-offhooked", ["analyze", "{cases}/field/offhooked-trailer.toml",
                           "--at", "theta0=pi"]),
    ("analyze-brockett-3", ["analyze", "{cases}/field/brockett-3.toml"]),
    ("analyze-heisenberg-5", ["analyze", "{cases}/field/heisenberg-5.toml"]),
    ("analyze-rolling-disk", ["analyze", "{cases}/field/rolling-disk.toml"]),
    ("analyze-chained-5", ["analyze", "{cases}/field/chained-5.toml"]),
    ("analyze-grushin", ["analyze", "{cases}/field/grushin.toml"]),
    ("analyze-omni", ["analyze", "{cases}/field/omni-3-swedish.toml"]),
    ("approximate-chained-5-linear", ["approximate", "{cases}/field/chained-5.toml",
                                      "--at", "x1=1,x2=2,x3=-1,x4=3,x5=5",
                                      "--method", "linear"]),
    ("approximate-rolling-ball", ["approximate", "{cases}/field/rolling-ball.toml",
                                  "--at", "theta=1"]),
    ("approximate-float-params", ["approximate", "{cases}/field/fail-float-params.toml",
                                  "--at", "theta0=pi/2"]),
    # the time limit well above the plan's ~40 s: under load the default 60 s is reached,
    # and the outcome would depend on the machine's load instead of the code
    ("plan-json-nan", ["plan", "{cases}/field/fail-plan-json-nan.toml", "--to", "y=0.2",
                       "--time-limit", "600"]),
    # shared cases: field3
    ("approximate-lu-inverse", ["approximate", "{cases}/field3/fail-float-lu-inverse.toml",
                                "--at", "theta=1,phi=1/2"]),
    ("approximate-lu-crash", ["approximate", "{cases}/field3/fail-float-lu-crash.toml",
                              "--at", "alpha1=-116/100,alpha2=-103/100,theta=134/100"]),
    ("approximate-cert", ["approximate", "{cases}/field3/fail-cert-false-negative.toml",
                          "--at", "alpha1=119/100,alpha2=-31/100,theta=-121/100"]),
    ("plan-chart-edge", ["plan", "{cases}/field3/fail-plan-chart-edge.toml",
                         "--from", "q1=0.6,q2=0.7", "--to", "q1=0.6,q2=0.7,q3=0.05"]),
    # shared cases: hostile
    ("analyze-markup-name", ["analyze", "{cases}/hostile/markup-name.toml"]),
    ("analyze-ansi-name", ["analyze", "{cases}/hostile/ansi-name.toml"]),
    ("analyze-big-rational", ["analyze", "{cases}/hostile/big-rational.toml"]),
    ("analyze-bigint", ["analyze", "{cases}/hostile/bigint-literal.json"]),
    ("analyze-tiny-scale", ["analyze", "{cases}/hostile/tiny-scale-1e-18.toml"]),
    ("analyze-bom", ["analyze", "{cases}/hostile/bom.toml"]),
    ("analyze-dupkey", ["analyze", "{cases}/hostile/dupkey.json"]),
    ("analyze-lookalike", ["analyze", "{cases}/hostile/lookalike.json"]),
]


def _run_one(args: list[str], timeout: float, cache: str) -> dict[str, Any]:
    cmd = [sys.executable, "-m", "nilpotent", *args, "--json", "--quiet"]
    start = time.monotonic()
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                              env=dict(os.environ, COLUMNS="100", NILPOTENT_CACHE=cache),
                              check=False)
    except subprocess.TimeoutExpired:
        return {"args": args, "exit": "timeout", "seconds": timeout}
    record: dict[str, Any] = {"args": args, "exit": done.returncode,
                              "seconds": round(time.monotonic() - start, 2)}
    try:
        record["stdout"] = json.loads(done.stdout) if done.stdout.strip() else None
    except json.JSONDecodeError:
        record["stdout_text"] = done.stdout
    if done.returncode != 0:
        lines = [line for line in done.stderr.splitlines() if line.strip()]
        record["stderr_last"] = lines[-1] if lines else ""
    return record


def run(out: Path, cases: Path, timeout: float, only: list[str]) -> None:
    """Run the commands and write ``out/<name>.json``."""
    out.mkdir(parents=True, exist_ok=True)
    cache = tempfile.mkdtemp(prefix="nilpotent-snapshot-cache-")
    try:
        _run_all(out, cases, timeout, only, cache)
    finally:
        shutil.rmtree(cache, ignore_errors=True)


def _run_all(out: Path, cases: Path, timeout: float, only: list[str], cache: str) -> None:
    for name, args in COMMANDS:
        if only and not any(fnmatch.fnmatchcase(name, pattern) for pattern in only):
            continue
        full = [a.replace("{cases}", str(cases)) for a in args]
        record = _run_one(full, timeout, cache)
        record["args"] = args  # the cases directory is not part of the snapshot
        (out / f"{name}.json").write_text(json.dumps(record, indent=1, sort_keys=True) + "\n")
        print(f"{name}: exit {record['exit']} in {record.get('seconds')} s", file=sys.stderr)


def _mask(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: ("<masked>" if k in VOLATILE else _mask(v)) for k, v in value.items()}
    if isinstance(value, list):
        return [_mask(v) for v in value]
    return value


def _diff(a: Any, b: Any, where: str, rtol: float, found: list[str]) -> None:
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            if key not in a:
                found.append(f"{where}.{key}: added")
            elif key not in b:
                found.append(f"{where}.{key}: removed")
            else:
                _diff(a[key], b[key], f"{where}.{key}", rtol, found)
        return
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            found.append(f"{where}: length {len(a)} -> {len(b)}")
            return
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _diff(x, y, f"{where}[{i}]", rtol, found)
        return
    if (isinstance(a, float) and isinstance(b, float) and rtol > 0
            and math.isclose(a, b, rel_tol=rtol, abs_tol=0.0)):
        return
    if a != b or type(a) is not type(b):
        found.append(f"{where}: {_short(a)} -> {_short(b)}")


def _short(value: Any) -> str:
    text = json.dumps(value)
    return text if len(text) <= 100 else text[:97] + "..."


def compare(before: Path, after: Path, rtol: float, limit: int) -> int:
    """Print what differs per command; the number of commands that differ."""
    differing = 0
    names = sorted({p.stem for p in before.glob("*.json")} | {p.stem for p in after.glob("*.json")})
    for name in names:
        pa, pb = before / f"{name}.json", after / f"{name}.json"
        if not (pa.exists() and pb.exists()):
            print(f"{name}: only in {'before' if pa.exists() else 'after'}")
            differing += 1
            continue
        a, b = json.loads(pa.read_text()), json.loads(pb.read_text())
        a.pop("seconds", None)
        b.pop("seconds", None)
        found: list[str] = []
        _diff(_mask(a), _mask(b), "", rtol, found)
        if not found:
            print(f"{name}: same")
            continue
        differing += 1
        print(f"{name}: {len(found)} difference(s)")
        for line in found[:limit]:
            print(f"    {line}")
        if len(found) > limit:
            print(f"    ... {len(found) - limit} more")
    print(f"{differing} of {len(names)} commands differ")
    return differing


def main(argv: list[str] | None = None) -> int:
    """The command line (see the module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="what", required=True)
    p_run = sub.add_parser("run", help="run the commands, write one JSON per command")
    p_run.add_argument("out", type=Path)
    p_run.add_argument("--cases", type=Path, default=Path("/work/shared/cases"))
    p_run.add_argument("--timeout", type=float, default=120.0)
    p_run.add_argument("--only", nargs="*", default=[],
                       help="only the commands whose names match these patterns ('plan-*')")
    p_cmp = sub.add_parser("compare", help="compare two snapshot directories")
    p_cmp.add_argument("before", type=Path)
    p_cmp.add_argument("after", type=Path)
    p_cmp.add_argument("--rtol", type=float, default=0.0)
    p_cmp.add_argument("--limit", type=int, default=8, help="differences shown per command")
    args = parser.parse_args(argv)
    if args.what == "run":
        run(args.out, args.cases, args.timeout, args.only)
        return 0
    return 1 if compare(args.before, args.after, args.rtol, args.limit) else 0


if __name__ == "__main__":
    sys.exit(main())
