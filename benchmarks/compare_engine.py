"""Engine throughput of two source trees, measured alternately in one run (before/after a change).

Run:  python benchmarks/compare_engine.py OLD_SRC NEW_SRC [--events N] [--rounds R] [--only S]

e.g. ``git worktree add /tmp/before HEAD~1`` then
``python benchmarks/compare_engine.py /tmp/before/src src``. Each round runs both trees in fresh
processes (numba cache warmed first), alternating, so both see the same machine load; the best
of the rounds is reported for each scene, and the ratio new/old of impacts per second. Times are
CPU times of the process (less sensitive than wall time to other work on the machine). Run it
once with the same tree twice (``OLD_SRC OLD_SRC``) to see the machine's noise floor at the
time; the trajectory case allocates its samples and is the noisiest.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

CHILD = """
import json, sys, time
from bouncedisk.engine import EngineConfig, simulate_arrays
events = int(sys.argv[1])
only = sys.argv[2]
cases = {
    "axial-only, omega_s=1.5": dict(e=0.3, omega_s=1.5),
    "contact+torsion, omega_s=1.5": dict(e=0.6, omega_s=1.5, torsion=True, r_phi=0.01),
    "torsion+load, omega_s=1.5": dict(
        e=0.6, omega_s=1.5, torsion=True, r_phi=0.01, load_torque=0.3
    ),
    "axial-only, omega_s=100": dict(e=0.3, omega_s=100.0),
    "noise+stats (ensemble member)": dict(
        e=0.6, omega_s=1.5, torsion=True, r_phi=0.01, e_sigma=1e-9, stats_from=0.0
    ),
    "e=0 contact+torsion, omega_s=1.5": dict(e=0.0, omega_s=1.5, torsion=True, r_phi=0.01),
    "axial-only + trajectory dt=5": dict(e=0.3, omega_s=1.5, traj_dt=5.0),
}
out = {}
for name, kw in cases.items():
    if only not in name:
        continue
    simulate_arrays(EngineConfig(max_events=10, **kw))
    t0 = time.process_time()
    simulate_arrays(EngineConfig(max_events=events, **kw))
    out[name] = events / (time.process_time() - t0)
print(json.dumps(out))
"""


def measure(src: str, events: int, only: str = "") -> dict[str, float]:
    """Impacts per second of each case (whose name contains ``only``), in a fresh process
    importing ``src``."""
    env = {**os.environ, "PYTHONPATH": os.path.abspath(src)}
    out = subprocess.run(
        [sys.executable, "-c", CHILD, str(events), only], env=env, capture_output=True, text=True
    )
    if out.returncode != 0:
        raise SystemExit(out.stderr)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--events", type=int, default=1_000_000)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--only", default="", help="run only the cases whose name contains this")
    args = ap.parse_args()
    measure(args.old, 10)  # compile or load the numba caches of both trees
    measure(args.new, 10)
    best = {"old": {}, "new": {}}
    for _ in range(args.rounds):
        for which in ("old", "new"):
            for k, v in measure(getattr(args, which), args.events, args.only).items():
                best[which][k] = max(best[which].get(k, 0.0), v)
    print(f"{args.events:,} impacts per case, best of {args.rounds} alternating rounds")
    print(f"{'case':<32}{'old /s':>14}{'new /s':>14}{'new/old':>9}")
    for k in best["old"]:
        o, n = best["old"][k], best["new"][k]
        print(f"{k:<32}{o:>14,.0f}{n:>14,.0f}{n / o:>9.3f}")


if __name__ == "__main__":
    main()
