"""The generating point's chi2 under the covariance measured at the generating point itself.

The fit holds the across-member covariance measured near its best point (docs/fitting_method.md
"The likelihood"). Where a validation fit's intervals miss the truth although the generating
point reads far above the fit's best, this reads the generating point again under the covariance
measured *there* (the same rule the search applies at its own point: :func:`.search.measure_cov`,
32 members for the run-ups' covariance, the load part's pilot for the load curves'), on the
fit's 12 members, for the motors of a rows file named on the command line, with the same data
(:func:`validation_motors.make_data`).

    python benchmarks/truth_own_covariance.py benchmarks/out/fit_validation_2drives_rows.jsonl \\
        --motors 18,22 [--record]

``--record`` writes ``benchmarks/out/fit_truth_own_covariance.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
from pathlib import Path

import numpy as np
from scipy.stats import chi2 as chi2_dist
from validation_motors import FIT_SEED, conditions_of, make_data

from bouncedisk.fitting import FitSettings
from bouncedisk.fitting.core import pose_fit
from bouncedisk.fitting.search import measure_cov
from bouncedisk.io.load_curves import read_load_curve
from bouncedisk.io.runup_curves import read_curve

#: Members of the fit's evaluations and of its covariance (FitSettings' defaults for one run-up).
MEMBERS, PILOT = 12, FitSettings.pilot_members


def own_reading(row: dict, cores: int) -> tuple[float, int]:
    """The generating point's chi2 under its own covariance, and the number of statistics."""
    m, k = row["true"], row["motor"]
    with tempfile.TemporaryDirectory() as tmp:
        run, loads = make_data(Path(tmp), m, k, tuple(conditions_of(row)))
        settings = FitSettings(seed=FIT_SEED, cores=cores)
        obj = pose_fit(read_curve(run), settings, None, [read_load_curve(x) for x in loads]).obj
        values = {**m, "log10_r_phi": math.log10(m["r_phi"])}
        x = np.array([values[n] for n in obj.names], float)
        obj.set_cov(measure_cov(obj, x, PILOT))
        return obj.chi2_now(x, MEMBERS), obj.n_stats


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rows", help="a rows file of benchmarks/validation_motors.py")
    ap.add_argument("--motors", required=True, help="motor numbers, comma-separated")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--record", action="store_true")
    args = ap.parse_args()
    wanted = {int(v) for v in args.motors.split(",")}
    rows = [json.loads(line) for line in open(args.rows) if line.strip()]
    out = []
    for row in (r for r in rows if r["motor"] in wanted):
        own, n = own_reading(row, args.cores)
        limit = float(chi2_dist.ppf(0.95, n))
        result = (
            f"{own:.4g} under its own covariance (95 % point of chi2({n}): {limit:.3g}); "
            f"{row['chi2_truth']:g} under the covariance of the fit, whose best is {row['chi2']:g}"
        )
        out.append((f"validation motor {row['motor']}, drives {row['drives']}", result))
        print(out[-1][0], "=>", result, flush=True)
    if args.record:
        from record import write_record

        print(
            write_record(
                "fit_truth_own_covariance", "The generating point under its own covariance", out
            )
        )


if __name__ == "__main__":
    main()
