"""Recovery of the run-up fit on model-generated curves: the three cases of ``tests/test_fitting.py``.

For each case (periodic; near the period doubling; chaotic with chatter reinjection, from 64
run-ups) the curves the test makes, the fit at the test's settings, and what it misses: the fitted
trend against the generating model's (steady speed within 3 %, time constant within 10 %) and every
identified 95 % interval against the generating value. ``tests/test_fitting.py`` fits the periodic
case alone (one run-up, the default search; it fails on a planted search range that leaves out the
generating point); the three together cost minutes of CPU, and the chaotic case alone 64 run-ups.

Run:  nice -n 5 python benchmarks/fit_recovery.py [CASE ...] [--record]

One JSON line per case; ``--record`` writes the performance page's record
(``benchmarks/out/fit_recovery.json``).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NAMES = ("e", "r_phi", "psi", "omega_s")


def _tests_module():
    """``tests/test_fitting.py``: its cases, curve maker and recovery, the one copy of them."""
    spec = importlib.util.spec_from_file_location("fit_cases", ROOT / "tests" / "test_fitting.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def recovery_row(case: str, tests) -> dict:
    """Fit ``case`` as the test does; its row: adequacy, the misses, the intervals, CPU and wall."""
    wall, cpu = time.perf_counter(), time.process_time()
    with tempfile.TemporaryDirectory() as tmp:
        ds, truth = tests.recover(Path(tmp), case)
    misses = tests.recovery_failures(ds, truth, case)
    return {
        "case": case,
        "adequate": int(ds.attrs["fit_adequate"]),
        "chi2": round(float(ds.attrs["chi2"]), 3),
        "misses": misses,
        "intervals": {
            n: [round(float(ds[n].attrs["ci_low"]), 5), round(float(ds[n].attrs["ci_high"]), 5)]
            for n in NAMES
            if ds[n].attrs["identified"]
        },
        "wall_s": round(time.perf_counter() - wall, 1),
        "cpu_s_main_process": round(time.process_time() - cpu, 1),
    }


def write_recovery_record(rows: list[dict]) -> None:
    """The performance page's record of the rows (:func:`recovery_row`)."""
    from record import write_record

    write_record(
        "fit_recovery",
        "Recovery of the run-up fit on the three cases of tests/test_fitting.py",
        [
            (
                r["case"],
                f"adequate {r['adequate']} (chi2 {r['chi2']}); identified "
                f"{', '.join(r['intervals']) or 'none'}; "
                f"{'; '.join(r['misses']) or 'trend and every identified interval hold'}; "
                f"{r['wall_s']:.0f} s wall",
            )
            for r in rows
        ],
    )


def main() -> None:
    tests = _tests_module()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="*", help=f"of {', '.join(tests.CASES)} (default: all three)")
    ap.add_argument("--record", action="store_true", help="write the performance page's record")
    args = ap.parse_args()
    unknown = sorted(set(args.cases) - set(tests.CASES))
    if unknown:
        ap.error(f"unknown case(s) {', '.join(unknown)}; known: {', '.join(tests.CASES)}")
    rows = []
    for case in args.cases or list(tests.CASES):
        rows.append(recovery_row(case, tests))
        print(json.dumps(rows[-1]), flush=True)
    if args.record:
        write_recovery_record(rows)


if __name__ == "__main__":
    main()
