"""What the global sensitivity study costs: CPU time per point, and the full study extrapolated.

Run:  python benchmarks/bench_sensitivity.py [--size small|full] [--points K] [--stride S]

Evaluates K points of the size's own Sobol' sample (every S-th row, so all parameters vary) with
the pipeline's model (bouncedisk.studies.sensitivity.MotorModel) on one core, and prints the CPU time of
each. A point's run lasts (discard + duration)/R_phi, so its cost grows like 1/R_phi; the
extrapolation to the whole sample (and the design maps) scales the measured CPU per unit of
1/R_phi by the sample's sum of 1/R_phi (a ratio estimator), beside the plain mean. The first
call loads the numba cache and is not timed.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

import numpy as np
import yaml

from bouncedisk.studies import sensitivity as sens
from bouncedisk.studies.sensitivity_settings import study_settings

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="full", choices=("small", "full"))
    ap.add_argument("--points", type=int, default=8)
    ap.add_argument("--stride", type=int, default=97)
    args = ap.parse_args()
    cfg = yaml.safe_load((ROOT / "workflow" / "config" / "config.yaml").read_text())
    st = study_settings({**cfg, "sensitivity": args.size})
    model = sens.MotorModel(st)
    x = sens.sample(st.ranges, st.base_samples, st.seed)
    names = list(st.ranges)
    model(dict(zip(names, x[0], strict=True)))  # numba cache
    rows = x[:: args.stride][: args.points]
    cpu, inv_r = [], []
    for row in rows:
        c = time.process_time()
        model(dict(zip(names, row, strict=True)))
        cpu.append(time.process_time() - c)
        inv_r.append(10.0 ** -row[names.index("log10_r_phi")])
        print(f"  point {np.round(row, 3)}: {cpu[-1]:.2f} s CPU", flush=True)
    cpu, inv_r = np.array(cpu), np.array(inv_r)
    per_unit = cpu.sum() / inv_r.sum()
    all_inv = 10.0 ** -x[:, names.index("log10_r_phi")]
    maps = [sens.map_sample(st, e)[0] for e in st.map_e]
    map_inv = sum(float(np.sum(10.0 ** -m[:, names.index("log10_r_phi")])) for m in maps)
    n_map = sum(len(m) for m in maps)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    print(f"size {st.size}: {len(x)} sample points, {n_map} design-map points, "
          f"{st.members} members, {len(st.loads)} loads")  # fmt: skip
    print(f"measured {len(rows)} points: mean {cpu.mean():.2f} s CPU per point, "
          f"{per_unit * 1e3:.3f} ms CPU per unit of 1/R_phi")  # fmt: skip
    sample_h = per_unit * all_inv.sum() / 3600
    maps_h = per_unit * map_inv / 3600
    print(f"extrapolated (ratio to 1/R_phi): sample {sample_h:.2f} core-hours, "
          f"design maps {maps_h:.2f} core-hours, total {sample_h + maps_h:.2f}")  # fmt: skip
    print(f"extrapolated (plain mean): {cpu.mean() * (len(x) + n_map) / 3600:.2f} core-hours")


if __name__ == "__main__":
    main()
