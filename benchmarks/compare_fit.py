"""A fit's cost in two source trees, measured alternately in one run, and whether the two give
the same fit.

Run:  python benchmarks/compare_fit.py OLD_SRC NEW_SRC [--rounds R] [--out FILE]

e.g. ``git worktree add /tmp/base <rev>`` then
``python benchmarks/compare_fit.py /tmp/base/src src``. The fit is the periodic case of
``tests/test_fitting.py`` (a 0.03 s run-up, the default search, one core), run in a fresh process
per tree and round, alternating, so both trees see the same machine load. Reports each tree's
CPU seconds (median of the rounds), the ratio new/old, and the fitted parameters and χ² of each
(equal to the last digits when a change is only numerical housekeeping).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

CHILD = """
import json, sys, tempfile, time
from pathlib import Path
sys.path.insert(0, sys.argv[1])
from test_fitting import CASES, make_curve
from bouncedisk.fitting import FitSettings, fit_curve, fit_dataset
from bouncedisk.io.runup_curves import read_curve
path = Path(tempfile.mkdtemp()) / "periodic.csv"
curve = read_curve(make_curve(path, CASES["periodic"], 3, member=0, span=0.03))
t0 = time.process_time()
ds = fit_dataset(fit_curve([curve], FitSettings(seed=1, cores=1, e_sigma=0.03)))
cpu = time.process_time() - t0
print(json.dumps({"cpu_s": cpu, "chi2": float(ds.attrs["chi2"]),
                  **{k: float(ds[k]) for k in ("e", "r_phi", "psi", "omega_s")}}))
"""


def run(src: str) -> dict:
    """One fit with the package at ``src`` and the test cases of its own tree (``src/../tests``)."""
    tests = str(Path(src).resolve().parent / "tests")
    env = dict(os.environ, PYTHONPATH=os.path.abspath(src))
    out = subprocess.run(
        [sys.executable, "-c", CHILD, tests], env=env, check=True, capture_output=True, text=True
    ).stdout
    return json.loads(out.strip().splitlines()[-1])


def _revision(src: str) -> str:
    """The commit of the tree holding ``src`` (with ``+`` when it has uncommitted changes)."""
    git = ["git", "-C", str(Path(src).resolve().parent)]
    head = subprocess.run([*git, "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    dirty = subprocess.run([*git, "status", "--porcelain", "src"], capture_output=True, text=True)
    return head.stdout.strip() + ("+" if dirty.stdout.strip() else "")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--out", type=Path, default=None, help="write the record (JSON) here")
    args = ap.parse_args()
    rows: dict[str, list[dict]] = {"old": [], "new": []}
    for _ in range(args.rounds):
        for key in ("old", "new"):
            rows[key].append(run(getattr(args, key)))
            print(key, rows[key][-1], flush=True)
    cpu = {k: statistics.median(r["cpu_s"] for r in v) for k, v in rows.items()}
    record = {
        "command": "python benchmarks/compare_fit.py " + " ".join(sys.argv[1:]),
        "cpu_s": cpu,
        "ratio_new_over_old": cpu["new"] / cpu["old"],
        "fits": {k: v[0] for k, v in rows.items()},
        "cpus": os.cpu_count(),
        "revisions": {k: _revision(getattr(args, k)) for k in ("old", "new")},
    }
    print(json.dumps(record, indent=1))
    if args.out:
        args.out.write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main()
