"""Engine throughput of two source trees, measured alternately in one run (before/after a change).

Run:  python benchmarks/compare_engine.py OLD_SRC NEW_SRC [--events N] [--rounds R] [--only S]

e.g. ``git worktree add /tmp/before HEAD~1`` then
``python benchmarks/compare_engine.py /tmp/before/src src``. Each round runs both trees in fresh
processes (numba cache warmed first), alternating, so both see the same machine load; for each
scene the best and the median of the rounds are reported, and the median of the rounds' ratios
new/old of impacts per second. Times are CPU times of the process (less sensitive than wall
time to other work on the machine). Run it once with the same tree twice (``OLD_SRC OLD_SRC``)
to see the machine's noise floor at the time; the trajectory case allocates its samples and is
the noisiest. Each case's outputs (events, samples, final state) are hashed in the child: a
case whose hash differs between the trees is marked ``BITS DIFFER``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

CHILD = """
import hashlib, json, sys, time
from bouncedisk.engine import EngineConfig, simulate_arrays
events = int(sys.argv[1])
only = sys.argv[2]
cases = {
    "axial-only, omega_s=1.5": dict(e=0.3, omega_s=1.5),
    "torsion+load e=0.3, omega_s=1.5": dict(
        e=0.3, omega_s=1.5, torsion=True, r_phi=0.01, load_torque=0.3
    ),
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
    res = simulate_arrays(EngineConfig(max_events=events, **kw))
    rate = events / (time.process_time() - t0)
    h = hashlib.sha256()
    for k in sorted(res.events):
        h.update(res.events[k].tobytes())
    h.update(res.traj.tobytes())
    h.update(repr(sorted(res.final.items())).encode())
    out[name] = (rate, h.hexdigest())
print(json.dumps(out))
"""


def measure(src: str, events: int, only: str = "") -> dict[str, tuple[float, str]]:
    """Impacts per second and the outputs' hash of each case (whose name contains ``only``), in
    a fresh process importing ``src``."""
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
    ap.add_argument(
        "--record", action="store_true", help="write benchmarks/out/engine_compare.json"
    )
    args = ap.parse_args()
    measure(args.old, 10)  # compile or load the numba caches of both trees
    measure(args.new, 10)
    rates = {"old": {}, "new": {}}
    digests = {"old": {}, "new": {}}
    for _ in range(args.rounds):
        for which in ("old", "new"):
            for k, (v, h) in measure(getattr(args, which), args.events, args.only).items():
                rates[which].setdefault(k, []).append(v)
                digests[which].setdefault(k, set()).add(h)
    print(f"{args.events:,} impacts per case, {args.rounds} alternating rounds")
    print(
        f"{'case':<34}{'old best /s':>13}{'new best /s':>13}{'old median':>12}{'new median':>12}"
        f"{'new/old':>9}"
    )
    rows = []
    for k, old in rates["old"].items():
        new = rates["new"][k]
        ratio = statistics.median(n / o for o, n in zip(old, new, strict=True))
        same = "" if digests["old"][k] == digests["new"][k] else "  BITS DIFFER"
        rows.append(
            (
                f"{k}: impacts/s old → new (medians), median ratio",
                f"{statistics.median(old) / 1e6:.2f} → {statistics.median(new) / 1e6:.2f} million,"
                f" {ratio:.3f}×{', outputs bit-identical' if not same else same}",
            )
        )
        print(
            f"{k:<34}{max(old):>13,.0f}{max(new):>13,.0f}{statistics.median(old):>12,.0f}"
            f"{statistics.median(new):>12,.0f}{ratio:>9.3f}{same}"
        )
    if args.record:
        from record import write_record

        write_record("engine_compare", "The engine beside the previous version, one run", rows)


if __name__ == "__main__":
    main()
