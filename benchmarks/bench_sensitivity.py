"""What the global sensitivity study costs, measured on whole shards of its own sample.

Run:  python benchmarks/bench_sensitivity.py [--size small|full] [--shards K] [--first F]
      python benchmarks/bench_sensitivity.py --by-r [--record]

Evaluates shards F … F+K−1 of the size's split (the pipeline's ``sensitivity_shard`` jobs, one
after another on one core, with the pipeline's model bouncedisk.studies.sensitivity.MotorModel)
and prints each shard's CPU time, the CPU per point, the share of the sample measured and the
whole sample's CPU at that rate. A shard is a contiguous block of the Sobol' sample, so its points
spread over every parameter's range; the pipeline's own measurement is the shard jobs'
``cpu_time_s`` (docs/sensitivity_method.md, "What it costs"). The first call loads the numba
cache and is not timed.

``--by-r`` measures instead what a point costs as a function of ``R_phi``: the first
:data:`BY_R_POINTS` base points of the size's sample (Saltelli's ``A`` rows, every ``D + 2``-th
row, so no two share coordinates), each evaluated at every ``log10 R_phi`` of
:data:`BY_R_GRID` (the other coordinates its own), CPU per point; then the mean over a
log-uniform ``R_phi`` on the study's range and on its upper decade (trapezoid rule on the grid).
A run lasts ``(discard + duration)/R_phi``, so the small ``R_phi`` dominate the study's cost.
``--record`` writes ``benchmarks/out/sensitivity_cost.json`` (the performance page).
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
#: ``log10 R_phi`` at which ``--by-r`` evaluates every point, and how many points.
BY_R_GRID = (-3.0, -2.5, -2.0, -1.5, -1.0)
BY_R_POINTS = 12


def cost_by_r(model: sens.MotorModel, x: np.ndarray, names: list[str]) -> list[float]:
    """CPU seconds per point at each ``log10 R_phi`` of :data:`BY_R_GRID`, over the points ``x``
    (rows of the sample, ``names`` its columns) with their ``log10 R_phi`` replaced."""
    out = []
    for lr in BY_R_GRID:
        t0 = time.process_time()
        for row in x:
            model({**dict(zip(names, row, strict=True)), "log10_r_phi": lr})
        out.append((time.process_time() - t0) / len(x))
    return out


def log_uniform_mean(cost: list[float], lo: float, hi: float) -> float:
    """Mean of the per-point cost over ``log10 R_phi`` uniform on ``[lo, hi]`` (grid points of
    :data:`BY_R_GRID` inside it, trapezoid rule)."""
    g = np.array(BY_R_GRID)
    keep = (g >= lo - 1e-12) & (g <= hi + 1e-12)
    c, g = np.array(cost)[keep], g[keep]
    return float(np.sum(0.5 * (c[1:] + c[:-1]) * np.diff(g)) / (hi - lo))


def by_r(model: sens.MotorModel, st, x: np.ndarray, record: bool) -> None:
    """The ``--by-r`` measurement (module docstring), printed and with ``record`` recorded."""
    names = list(st.ranges)
    cost = cost_by_r(model, x[:: len(names) + 2][:BY_R_POINTS], names)
    lo, hi = st.ranges["log10_r_phi"]
    rows = [(f"CPU per point at log10 R_phi = {lr:g} (mean of {BY_R_POINTS} base points)",
             f"{1e3 * c:.1f} ms") for lr, c in zip(BY_R_GRID, cost, strict=True)]  # fmt: skip
    whole, upper = log_uniform_mean(cost, lo, hi), log_uniform_mean(cost, hi - 1.0, hi)
    rows.append((f"mean over log10 R_phi uniform on [{lo:g}, {hi:g}], the study range",
                 f"{1e3 * whole:.1f} ms"))  # fmt: skip
    rows.append((f"mean over its upper decade [{hi - 1:g}, {hi:g}]",
                 f"{1e3 * upper:.1f} ms ({whole / upper:.1f} times cheaper)"))  # fmt: skip
    for m, r in rows:
        print(f"{m}: {r}")
    if record:
        from record import write_record

        print(write_record("sensitivity_cost", "The sensitivity study: the cost of a point against R_phi",
                           rows))  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="small", choices=("small", "full"))
    ap.add_argument("--shards", type=int, default=1, help="shards to evaluate")
    ap.add_argument("--first", type=int, default=0, help="the first of them")
    ap.add_argument("--by-r", action="store_true", help="a point's CPU against R_phi instead")
    ap.add_argument("--record", action="store_true", help="with --by-r: write its record")
    args = ap.parse_args()
    if args.record and not args.by_r:
        ap.error("--record goes with --by-r")
    cfg = yaml.safe_load((ROOT / "workflow" / "config" / "config.yaml").read_text())
    st = study_settings({**cfg, "sensitivity": args.size})
    model = sens.MotorModel(st)
    x = sens.sample(st.ranges, st.base_samples, st.seed)
    model(dict(zip(st.ranges, x[0], strict=True)))  # numba cache
    if args.by_r:
        by_r(model, st, x, args.record)
        return
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
