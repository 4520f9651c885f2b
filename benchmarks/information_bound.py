"""How well can the random motors' data pin each parameter at all? The local bound at the truth.

For each motor of the random-motor sample (``random_motors.py``: the same Sobol' draw, the same
run-up and load curve), the objective the joint fit searches (``bouncedisk.fitting.pose_fit``,
``--e-sigma fit``) is set up and, at the generating point itself, its covariance is measured there
(as the search does at its best point) and the Jacobian of its whitened residuals is taken by
central differences (``bouncedisk.fitting.uncertainty.jacobian``, common random numbers). The
inverse of ``JᵀJ`` is the covariance of a linearized fit centred on the truth: its 95 %
half-widths are what profile intervals about the truth would be, at the plain threshold (no
widening, no level on fresh members), if the likelihood with its covariance measured at the truth
were quadratic there (the Cramér–Rao bound of the fit's statistics). No search is run, so no basin can
be missed: a width found here is a property of the data and the statistics, not of the method.

``R_phi``'s factor is ``10 ** (2 * 1.96 * sd(log10 R_phi))``, the ratio of the linearized
interval's ends (as ``random_motors.py`` reports it). The Jacobian is taken at two steps (1 % and
3 % of each range) so that Monte-Carlo noise (chaotic motors) and curvature show as disagreement;
on average noise in a Jacobian adds to ``JᵀJ``, making a bound narrower, not wider. Where
``e_sigma = 0`` and the motor is chaotic the members coincide, the covariance measured there holds
the reading noise only, and ``chi2`` at the truth reads far above its degrees of freedom
(docs/fitting_method.md, "What the data can pin").

Run:  python benchmarks/information_bound.py [--motors 16] [--first 0] [--count N]
      [--cores 2] [--json OUT.jsonl] [--record]

One JSON line per motor, then the count of motors whose bound allows ``R_phi`` to a factor below
2 at both steps (the random-motor target asks for 80 %). ``--record`` needs the whole sample.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from random_motors import (
    FIT_SEED,
    LOADS,
    READING_NOISE,
    REPEATS,
    SAMPLE_SEED,
    make_motor_data,
    run_slice,
    slice_arguments,
)
from record import write_record
from scipy.stats import chi2 as chi2_dist

from bouncedisk.fitting import FitSettings, pose_fit
from bouncedisk.fitting.objective import snap
from bouncedisk.fitting.search import measure_cov
from bouncedisk.fitting.uncertainty import combinations, curvature, jacobian
from bouncedisk.io.load_curves import read_load_curve
from bouncedisk.io.runup_curves import read_curve

#: Central-difference steps, as fractions of each coordinate's search range.
STEPS = (0.01, 0.03)
#: Two-sided 95 % normal quantile.
Z95 = 1.959963984540054


def truth_x(names: list[str], true: dict) -> np.ndarray:
    """The generating point in the search coordinates ``names``."""
    value = {**true, "log10_r_phi": math.log10(true["r_phi"])}
    return snap(np.array([value[n] for n in names], float))


def bound(true: dict, k: int, cores: int) -> dict:
    """The linearized 95 % half-widths at motor ``k``'s truth, at each of :data:`STEPS`."""
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        run, load = make_motor_data(Path(tmp), true, k, LOADS, REPEATS, READING_NOISE)
        settings = FitSettings(seed=FIT_SEED, cores=cores, e_sigma=None)
        posed = pose_fit(read_curve(run), settings, load=[read_load_curve(load)])
    obj, members = posed.obj, posed.settings.members
    x = truth_x(obj.names, true)
    obj.set_cov(measure_cov(obj, x, posed.settings.pilot_members))
    row = {"motor": k, "true": true, "n": obj.n_stats,
           "chi2_truth": round(obj.chi2(x, members), 3), "steps": {}}  # fmt: skip
    for step in STEPS:
        jac = jacobian(obj, x, members, rel_step=step)
        _, _, sd = curvature(jac)
        comb_sd, _ = combinations(jac, obj.span)
        half = {n: round(Z95 * s, 4) for n, s in zip(obj.names, sd, strict=True)}
        row["steps"][str(step)] = {
            "half_width": half,
            "r_phi_factor": round(10.0 ** (2.0 * half["log10_r_phi"]), 3),
            # sd of the eigen-combinations as fractions of the ranges, best pinned first
            "combination_sd": [float(f"{v:.3g}") for v in comb_sd],
        }
    row["seconds"] = round(time.perf_counter() - start, 1)
    return row


def below_two(rows: list[dict]) -> dict:
    """Motors whose bound allows ``R_phi`` to a factor below 2: at each step alone, and at both
    (the larger of the two factors, the cautious reading: noise narrows a bound)."""
    out = {s: int(sum(r["steps"][s]["r_phi_factor"] < 2.0 for r in rows)) for s in map(str, STEPS)}
    out["both"] = int(sum(larger_factor(r) < 2.0 for r in rows))
    return out


def larger_factor(row: dict) -> float:
    """The larger of a motor's ``R_phi`` factors at the two steps."""
    return max(row["steps"][str(s)]["r_phi_factor"] for s in STEPS)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    slice_arguments(ap)
    ap.add_argument("--record", action="store_true",
                    help="write benchmarks/out/information.json (the whole sample only)")  # fmt: skip
    args = ap.parse_args()
    if args.record and (args.first != 0 or args.count is not None):
        ap.exit(2, "information_bound.py: --record: the record is of the whole sample; drop "
                   "--first and --count\n")  # fmt: skip
    rows = run_slice(args, lambda true, k: bound(true, k, args.cores))
    counts = below_two(rows)
    factors = [larger_factor(r) for r in rows]
    print(f"R_phi bound below a factor 2 on {counts['both']} of {len(rows)} motors at both steps "
          f"({counts}); median factor {float(np.median(factors)):.3g}", file=sys.stderr)  # fmt: skip
    if args.record:
        write_record("information", "Random motors: what the data can pin at the truth",
                     record_rows(rows, counts, factors))  # fmt: skip


def record_rows(rows: list[dict], counts: dict, factors: list[float]) -> list[tuple[str, str]]:
    """The record's rows: the summary, then one per motor."""
    misfit = [r["motor"] for r in rows if r["chi2_truth"] > chi2_dist.ppf(0.999, r["n"])]
    zero = [r["motor"] for r in rows if r["true"]["e_sigma"] == 0.0]
    out = [(f"motors (seed {SAMPLE_SEED}) whose linearized bound at the truth allows R_phi to a "
            "factor below 2",
            f"{counts['both']} of {len(rows)} at both steps (median of the larger factor "
            f"{float(np.median(factors)):.3g}); {counts[str(STEPS[0])]} at the 1 % step alone, "
            f"{counts[str(STEPS[1])]} at the 3 % step alone"),
           ("motors whose generating point does not reproduce its own data under the likelihood "
            "with its covariance measured there (chi2 at the truth above the 99.9 % point)",
            ", ".join(map(str, misfit)) or "none"),
           ("motors at e_sigma = 0, where a chaotic motor has members that coincide and a "
            "covariance of the reading noise only: their widths are not a bound",
            ", ".join(map(str, zero)) or "none")]  # fmt: skip
    for r in rows:
        h = r["steps"][str(STEPS[0])]["half_width"]
        f = [r["steps"][str(s)]["r_phi_factor"] for s in STEPS]
        out.append((f"motor {r['motor']}: 95 % half-widths at the truth (e / log10 R_phi / psi / "
                    "omega_s / e_sigma, step 1 %)",
                    " / ".join(f"{h[n]:.3g}" for n in h) + f"; R_phi factor {f[0]:.3g} (step 1 %), "
                    f"{f[1]:.3g} (3 %); chi2 at the truth {r['chi2_truth']:.3g} on {r['n']}"))  # fmt: skip
    return out


if __name__ == "__main__":
    main()
