"""What the global sensitivity study costs, measured on whole shards of its own sample.

Run:  python benchmarks/bench_sensitivity.py [--size small|full] [--shards K] [--first F]

Evaluates shards F … F+K−1 of the size's split (the pipeline's ``sensitivity_shard`` jobs, one
after another on one core, with the pipeline's model bouncedisk.studies.sensitivity.MotorModel)
and prints each shard's CPU time, the CPU per point, the share of the sample measured and the
whole sample's CPU at that rate. A shard is a contiguous block of the Sobol' sample, so its points
spread over every parameter's range; the pipeline's own measurement is the shard jobs'
``cpu_time_s`` (docs/sensitivity_method.md, "What it costs"). The first call loads the numba
cache and is not timed.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

import yaml

from bouncedisk.studies import sensitivity as sens
from bouncedisk.studies.sensitivity_settings import study_settings

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="small", choices=("small", "full"))
    ap.add_argument("--shards", type=int, default=1, help="shards to evaluate")
    ap.add_argument("--first", type=int, default=0, help="the first of them")
    args = ap.parse_args()
    cfg = yaml.safe_load((ROOT / "workflow" / "config" / "config.yaml").read_text())
    st = study_settings({**cfg, "sensitivity": args.size})
    model = sens.MotorModel(st)
    x = sens.sample(st.ranges, st.base_samples, st.seed)
    model(dict(zip(st.ranges, x[0], strict=True)))  # numba cache
    cpu, points = 0.0, 0
    wall = time.perf_counter()
    for shard in range(args.first, min(st.shards, args.first + args.shards)):
        ds = sens.run_shard(st, model, shard)
        cpu += float(ds.attrs["cpu_time_s"])
        points += int(ds.sizes["point"])
        print(f"  shard {shard}: {ds.sizes['point']} points, {ds.attrs['cpu_time_s']:.1f} s CPU",
              flush=True)  # fmt: skip
    wall = time.perf_counter() - wall
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    print(f"size {st.size}: {len(x)} points in {st.shards} shards, {st.members} members, "
          f"{len(st.loads)} loads, {st.discard:g} + {st.duration:g} units of 1/R_phi")  # fmt: skip
    print(f"measured {points} points ({100 * points / len(x):.1f} % of the sample): "
          f"{cpu:.1f} s CPU, {wall:.1f} s wall, {1e3 * cpu / max(points, 1):.1f} ms CPU per point")  # fmt: skip
    print(f"the sample at that rate: {cpu / max(points, 1) * len(x) / 3600:.2f} core-hours")


if __name__ == "__main__":
    main()
