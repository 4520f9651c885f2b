"""What the global sensitivity study costs, measured on whole shards of its own sample.

Run:  python benchmarks/bench_sensitivity.py [--size small|full] [--shards K] [--first F]
      python benchmarks/bench_sensitivity.py --by-r [--record]
      python benchmarks/bench_sensitivity.py --rows [--record]

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

``--rows`` measures what one axial trajectory for every load would save (the axial motion does
not depend on the load: :func:`bouncedisk.engine.loads.omega_integrals`): on the first
:data:`ROWS_POINTS` base points, CPU per point of the study's own evaluation (each member's
loads continued one from the other) against each member's ``∫Ω dt`` of every load **from rest**
on one axial trajectory, for the study's loads (one running direction), for them and their
negatives (the mirror motor's loads: both directions, as the study needs before it knows which
way the motor runs) and for no load alone (the axial trajectory and one rotation). Only
``∫Ω dt`` is read, no statistics, so the rows' times are lower bounds. ``--record`` writes
``benchmarks/out/sensitivity_rows.json``.
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
#: Base points ``--rows`` times.
ROWS_POINTS = 40


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


def rows_cost(model: sens.MotorModel, st, x: np.ndarray, names: list[str]) -> dict[str, float]:
    """CPU seconds per point (``--rows``, module docstring) over the points ``x``: the study's
    evaluation, and the loads as rows from rest for each set of loads."""
    from dataclasses import replace

    from bouncedisk.analysis.statistics import ensemble_window
    from bouncedisk.engine.loads import omega_integrals
    from bouncedisk.model.engine_config import engine_config

    loads = np.array(st.loads, float)
    sets = {"study": None, "rows, the loads": loads,
            "rows, the loads and their negatives": np.concatenate([loads, -loads[loads > 0]]),
            "rows, no load alone": np.zeros(1)}  # fmt: skip
    out = dict.fromkeys(sets, 0.0)
    for row in x:
        point = dict(zip(names, row, strict=True))
        t0 = time.process_time()
        model(point)
        out["study"] += time.process_time() - t0
        scene = model.scene(point, load=True)
        t_from, _ = ensemble_window(scene)
        cfg = replace(engine_config(scene), stats_from=t_from, traj_dt=0.0, stroboscopic=False)
        for name, ld in sets.items():
            if ld is None:
                continue
            t0 = time.process_time()
            for m in range(st.members):
                omega_integrals(replace(cfg, member=m), ld, scene.initial)
            out[name] += time.process_time() - t0
    return {k: v / len(x) for k, v in out.items()}


def rows(model: sens.MotorModel, st, x: np.ndarray, record: bool) -> None:
    """The ``--rows`` measurement (module docstring), printed and with ``record`` recorded."""
    names = list(st.ranges)
    cost = rows_cost(model, st, x[:: len(names) + 2][:ROWS_POINTS], names)
    base = cost["study"]
    timed = len(x[:: len(names) + 2][:ROWS_POINTS])
    out = [(f"CPU per point of the study ({st.members} members, {len(st.loads)} loads continued, "
            f"mean of {timed} base points)", f"{1e3 * base:.1f} ms")]  # fmt: skip
    out += [(f"{k} from rest on one axial trajectory a member",
             f"{1e3 * v:.1f} ms ({base / v:.2f} times cheaper)")
            for k, v in cost.items() if k != "study"]  # fmt: skip
    for m, r in out:
        print(f"{m}: {r}")
    if record:
        from record import write_record

        print(write_record("sensitivity_rows",
                           "The sensitivity study: every load from one axial trajectory", out))  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="small", choices=("small", "full"))
    ap.add_argument("--shards", type=int, default=1, help="shards to evaluate")
    ap.add_argument("--first", type=int, default=0, help="the first of them")
    ap.add_argument("--by-r", action="store_true", help="a point's CPU against R_phi instead")
    ap.add_argument("--rows", action="store_true",
                    help="the loads from rest on one axial trajectory instead")  # fmt: skip
    ap.add_argument("--record", action="store_true", help="with --by-r or --rows: write its record")
    args = ap.parse_args()
    if args.record and not (args.by_r or args.rows):
        ap.error("--record goes with --by-r or --rows")
    if args.by_r and args.rows:
        ap.error("--by-r and --rows are two measurements: one at a time")
    cfg = yaml.safe_load((ROOT / "workflow" / "config" / "config.yaml").read_text())
    st = study_settings({**cfg, "sensitivity": args.size})
    model = sens.MotorModel(st)
    x = sens.sample(st.ranges, st.base_samples, st.seed)
    model(dict(zip(st.ranges, x[0], strict=True)))  # numba cache
    if args.by_r:
        by_r(model, st, x, args.record)
        return
    if args.rows:
        rows(model, st, x, args.record)
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
