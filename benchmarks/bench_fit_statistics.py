"""What the fit's statistics cost per ensemble: the members' statistics reduced one
record at a time on the member threads (as before) against all records at once
(:func:`bouncedisk.fitting.summary_stats.records_stats`, one Welch call for every member), at the
shipped motor's generating point on its run-up's grid. Both give the same bits (checked here).

Run:  python benchmarks/bench_fit_statistics.py [--members 16] [--repeat 5]

Prints the best of ``--repeat`` wall times of one ensemble (simulation and statistics) each way
on 1 and 2 cores, and their ratio. Run it on a quiet machine: the ratio is what to compare.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from bouncedisk.fitting.core import data_layout, prepare_runs
from bouncedisk.fitting.members import EnsembleSpec, member_records
from bouncedisk.fitting.summary_stats import record_stats, records_stats
from bouncedisk.io.runup_curves import read_curve

ROOT = Path(__file__).resolve().parents[1]
THETA = {"e": 0.55, "log10_r_phi": math.log10(0.002), "psi": 0.4, "omega_s": 1.7}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--members", type=int, default=16)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    runs, curve, _note = prepare_runs(read_curve(ROOT / "data/prototype/synthetic_motor.csv"))
    layout = data_layout(runs)[0]
    members = range(args.members)
    ways = {
        "per record": lambda spec: np.array(
            member_records(THETA, curve, members, spec, lambda r: record_stats(r, layout))
        ),
        "all at once": lambda spec: records_stats(
            np.array(member_records(THETA, curve, members, spec)), layout
        ),
    }
    for cores in (1, 2):
        spec = EnsembleSpec(e_sigma=0.03, seed=1, cores=cores)
        best, values = {}, {}
        for _ in range(args.repeat):
            for name, way in ways.items():
                t = time.perf_counter()
                values[name] = way(spec)
                best[name] = min(best.get(name, math.inf), time.perf_counter() - t)
        same = values["per record"].tobytes() == values["all at once"].tobytes()
        print(f"{cores} core(s), {args.members} members: "
              + ", ".join(f"{k} {v * 1e3:.1f} ms" for k, v in best.items())
              + f"; ratio {best['per record'] / best['all at once']:.2f}; same bits: {same}")  # fmt: skip


if __name__ == "__main__":
    main()
