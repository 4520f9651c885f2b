"""Coverage of the fit's 95 % interval of ``R_phi``: many noise seeds of one motor.

It fits as many noise seeds of the periodic case of ``tests/test_fitting.py`` as asked, with that
module's curves (0.03 s run-ups, a 96-point scan with 8 zoom points per centre, the profile of
``R_phi`` only), and reports how many intervals hold the generating ``R_phi``, with the Wilson
95 % interval of that coverage, the intervals' widths (the ratio of their ends) and the wall time
of a fit. A check of the intervals' coverage needs many seeds (tens of seconds a fit): it is
this benchmark and its record, not a test.

Run:  nice -n 5 python benchmarks/fit_coverage.py [--first 0] [--count 20] [--json OUT.jsonl]
      [--record]
      python benchmarks/fit_coverage.py --totals-of OUT.jsonl [--record]   (rows made in parts)

One JSON line per seed, then the totals; ``--record`` writes the performance page's record
(``benchmarks/out/fit_coverage.json``).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import statistics
import tempfile
import time
from pathlib import Path

from bouncedisk.analysis.statistics import wilson
from bouncedisk.fitting import FitSettings, fit_curve, fit_dataset
from bouncedisk.io.runup_curves import read_curve

ROOT = Path(__file__).resolve().parents[1]
CASE = "periodic"
#: The fits' settings (16 band members: the band is not what is measured).
SETTINGS = dict(
    seed=1, cores=2, e_sigma=0.03, scan=96, zoom=8, band_members=16, profile=("log10_r_phi",)
)
SPAN_S = 0.03


def _tests_module():
    """``tests/test_fitting.py``: its cases and curve maker, the one copy of them."""
    spec = importlib.util.spec_from_file_location("fit_cases", ROOT / "tests" / "test_fitting.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def fit_seed(seed: int, cases=None) -> dict:
    """Fit seed ``seed`` of the case; its row: interval of ``R_phi``, whether it holds the truth."""
    cases = cases or _tests_module()
    true = cases.CASES[CASE]
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        path = cases.make_curve(Path(tmp) / "c.csv", true, 100 + seed, member=seed, span=SPAN_S)
        ds = fit_dataset(fit_curve(read_curve(path), FitSettings(**SETTINGS)))
    a = ds["r_phi"].attrs
    lo, hi = float(a["ci_low"]), float(a["ci_high"])
    return {"seed": seed, "r_phi": float(ds["r_phi"]), "ci_low": lo, "ci_high": hi,
            "holds": bool(lo <= true["r_phi"] <= hi), "identified": bool(a["identified"]),
            "two_sided": not (a["open_low"] or a["open_high"]),
            "factor": round(hi / lo, 4) if lo > 0 else None,
            "chi2": round(float(ds.attrs["chi2"]), 3),
            "wall_s": round(time.perf_counter() - start, 1)}  # fmt: skip


def totals(rows: list[dict]) -> dict:
    """Coverage with its Wilson interval, the largest width factor, the wall times."""
    k, n = sum(r["holds"] for r in rows), len(rows)
    lo, hi = wilson(k, n)
    walls = sorted(r["wall_s"] for r in rows)
    factors = [r["factor"] for r in rows if r["factor"] is not None]
    return {"fits": n, "held": k, "coverage": k / n, "coverage_ci95": [lo, hi],
            "identified": sum(r["identified"] for r in rows),
            "two_sided": sum(r["two_sided"] for r in rows),
            "largest_factor": max(factors) if factors else math.nan,
            "median_factor": statistics.median(factors) if factors else math.nan,
            "median_wall_s": statistics.median(walls), "largest_wall_s": walls[-1]}  # fmt: skip


def write_coverage_record(t: dict) -> None:
    """The performance page's record of the totals ``t`` (:func:`totals`)."""
    from record import write_record

    lo, hi = t["coverage_ci95"]
    write_record("fit_coverage", "Coverage of the 95 % interval of R_phi fitted", [
        (f"intervals holding the generating R_phi ({t['fits']} seeds of the periodic case)",
         f"{t['held']}/{t['fits']} ({t['coverage']:.0%}; Wilson 95 % [{lo:.2f}, {hi:.2f}])"),
        ("intervals identified (not open on both sides)", f"{t['identified']}/{t['fits']}"),
        ("intervals two-sided (closed on both sides)", f"{t['two_sided']}/{t['fits']}"),
        ("largest ratio of an interval's ends", f"{t['largest_factor']:.3g}"),
        ("median ratio of an interval's ends", f"{t['median_factor']:.3g}"),
        ("wall time of a fit, median / largest (2 cores)",
         f"{t['median_wall_s']:.0f} s / {t['largest_wall_s']:.0f} s"),
    ])  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--first", type=int, default=0, help="first seed")
    ap.add_argument("--count", type=int, default=20, help="seeds fitted")
    ap.add_argument("--json", help="append each row to this file (JSON lines)")
    ap.add_argument("--totals-of", metavar="ROWS.jsonl",
                    help="fit nothing: the totals (and --record) of rows saved with --json")  # fmt: skip
    ap.add_argument("--record", action="store_true", help="write the performance page's record")
    args = ap.parse_args()
    if args.totals_of:
        with open(args.totals_of, encoding="utf-8") as f:
            rows = [json.loads(line) for line in f if line.strip()]
    else:
        rows = fit_rows(range(args.first, args.first + args.count), args.json)
    t = totals(rows)
    print(json.dumps(t))
    if args.record:
        write_coverage_record(t)


def fit_rows(seeds: range, jsonl: str | None) -> list[dict]:
    """Fit every seed, printing (and appending to ``jsonl``) each row as it comes."""
    cases, rows = _tests_module(), []
    for seed in seeds:
        rows.append(fit_seed(seed, cases))
        line = json.dumps(rows[-1])
        print(line, flush=True)
        if jsonl:
            with open(jsonl, "a", encoding="utf-8") as f:
                f.write(line + "\n")
    return rows


if __name__ == "__main__":
    main()
