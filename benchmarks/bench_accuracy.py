"""Work-precision and scaling at full size; prints the targets as ratios from this one run.

Run:  python benchmarks/bench_accuracy.py [--out DIR]

Targets (issue: accuracy costs): the exact solver at least 100x faster than the fastest
solve_ivp configuration that reaches impact-time error 1e-8, and more accurate than every
comparator at every CPU budget; time linear in the number of impacts (1e3...1e7); peak memory of
a 1e7-impact events-only run under 1 GB. Tables are written to DIR (default: benchmarks/out).
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np
import yaml

from bouncedisk.studies.scaling import scaling
from bouncedisk.studies.work_precision import work_precision, work_precision_summary

CONFIG = Path(__file__).resolve().parents[1] / "workflow" / "config" / "config.yaml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "out"))
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(
        f"machine: {platform.machine()} {platform.processor() or ''}, "
        f"python {platform.python_version()}, one core per measurement"
    )
    t0 = time.perf_counter()
    wp = work_precision()
    wp.to_csv(out / "work_precision.csv", index=False)
    summary = work_precision_summary(wp)
    (out / "work_precision_summary.json").write_text(json.dumps(summary, indent=2))
    print(f"work-precision ({time.perf_counter() - t0:.0f} s):")
    print(
        f"  exact vs fastest solve_ivp reaching 1e-8: {summary['speedup_vs_fastest_ivp_at_1e-8']:.0f}x"
        " faster (target >= 100x)"
    )
    print(
        f"  exact more accurate than every comparator at every budget: "
        f"{summary['exact_more_accurate_at_every_budget']} {summary['counterexample']}"
    )
    t0 = time.perf_counter()
    sizes = yaml.safe_load(CONFIG.read_text())["accuracy"]["scaling"]  # the pipeline's sizes,
    sc = scaling(  # here larger, to the 1e7 impacts the flat-cost claim is about
        **{
            **sizes,
            "sizes": (*sizes["sizes"], 10_000_000),
            "memory_sizes": (*sizes["memory_sizes"], 10_000_000),
            "per_omega": 500_000,
        }
    )
    sc.to_csv(out / "scaling.csv", index=False)
    print(f"scaling ({time.perf_counter() - t0:.0f} s):")
    w = sc[sc.study == "omega"]
    base = float(w.s_per_impact.iloc[0])
    for _, r in w.iterrows():
        print(
            f"  omega_s = {r.omega_s:7g}: {1e9 * r.s_per_impact:6.0f} ns/impact "
            f"({r.s_per_impact / base:.2f}x omega_s = 1.5)"
        )
    n = sc[sc.study == "impacts"]
    slope = np.polyfit(np.log10(n.n_impacts), np.log10(n.seconds), 1)[0]
    for _, r in n.iterrows():
        print(f"  {int(r.n_impacts):>10,} impacts: {r.seconds:8.4f} s")
    print(f"  log-log slope of time against impacts: {slope:.3f} (linear = 1)")
    for _, r in sc[sc.study == "memory"].iterrows():
        print(
            f"  {int(r.n_impacts):>10,} impacts streamed (events only): peak RSS {r.peak_mb:.0f} MB"
        )
    for _, r in sc[sc.study == "effects"].iterrows():
        print(f"  {r.effect:<36}: {1e9 * r.s_per_impact:6.0f} ns/impact")


if __name__ == "__main__":
    main()
