"""Random-motor recovery: the joint fit on motors it was never tuned on (the test of record).

A seeded scrambled Sobol' sample (``scipy.stats.qmc.Sobol``) of motors over the search box
(``bouncedisk.fitting.members.BOUNDS``: ``e``, ``log10 R_phi``, ``psi``, ``omega_s``, and the
restitution noise ``e_sigma`` over [0, 0.1]); every fourth motor has ``e_sigma = 0`` (the
deterministic limit). For each, made by the model: one run-up (one member, 0.06 s at 15 kHz,
Gaussian reading noise 0.05 rad/s) and one load curve of ``--loads`` loads from 0 to 1.25 times
the stall torque (found on one noise-free member), each load read ``--repeats`` times (separate
runs from rest, each with its own restitution noise) plus independent Gaussian reading noise of
``--reading-noise`` rad/s per reading (the CSV holds the mean and the spread). The fit is
``bouncedisk fit RUN.csv --load LOAD.csv --e-sigma fit`` with ``--scan``/``--zoom``. The
tuning cases (the shipped motor and the three recovery cases of ``joint_recovery.py``) are not
in the sample.

Per motor: adequate (p >= 0.001), every joint interval holding the generating value, each
interval's width (search coordinates), ``R_phi``'s factor (the ratio of its interval's ends,
``10 ** width`` of ``log10 R_phi``), wall time. Then the success rates against the targets: >= 90 %
adequate, each parameter's interval holding the truth on >= 90 %, ``R_phi`` known to a factor
below 2 on >= 80 %.

Run:  nice -n 5 python benchmarks/random_motors.py [--motors 16] [--first 0] [--count N]
      [--scan 192] [--zoom 16] [--cores 2] [--json OUT.json]

``--first``/``--count`` run a slice of the sample (the same motors whatever the slice), so a
table can be made in parts. One JSON line per motor, then the rates of the motors run.

The measured rows and rates are in ``benchmarks/out/fit.json``; docs/fitting_method.md,
"Random motors and validation motors", states the rates and the command that produces them (``--motors 16 --cores 2``
at the default sizes). A fit takes minutes a motor.

The last line printed holds the rates and the pooled coverage (:func:`coverage`); ``--rates
ROWS.json`` prints them for rows already made (the slices' ``--json`` files put together).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy.stats import binom, binomtest

from bouncedisk.fitting import FitSettings, fit_curve, fit_dataset, synthesize_curve
from bouncedisk.fitting import loadpart as lp
from bouncedisk.fitting.members import BOUNDS
from bouncedisk.fitting.synthetic import synthetic_load_curve
from bouncedisk.io.load_curves import LoadCurveData, read_load_curve
from bouncedisk.io.runup_curves import read_curve, write_curve

F_HZ, PHI0, SPAN, DT, SIGMA = 15000.0, 3.0e-4, 0.06, 2.5e-5, 0.05
ROTOR = {"m_r_kg": 0.01, "r_g_m": 0.004, "r_c_m": 0.002}
PRELOAD = 0.77
WINDOW = (0.03, 0.06)
#: The sample's coordinates, in the order of the Sobol' dimensions.
AXES = ("e", "log10_r_phi", "psi", "omega_s", "e_sigma")
SAMPLE_SEED = 20261125
#: Each motor's load curve by default: loads, readings per load, reading noise (rad/s).
LOADS, REPEATS, READING_NOISE = 12, 5, 0.05
#: The seed of every fit of the sample.
FIT_SEED = 1


def motors(n: int, seed: int = SAMPLE_SEED) -> list[dict[str, float]]:
    """``n`` motors of the seeded scrambled Sobol' sample over the search box (module docstring);
    every fourth (index 3, 7, ...) at ``e_sigma = 0``."""
    from scipy.stats import qmc

    u = qmc.Sobol(d=len(AXES), scramble=True, seed=seed).random(n)
    out = []
    for k, row in enumerate(u):
        x = {
            a: float(BOUNDS[a][0] + v * (BOUNDS[a][1] - BOUNDS[a][0]))
            for a, v in zip(AXES, row, strict=True)
        }
        out.append({"e": round(x["e"], 4), "r_phi": round(10.0 ** x["log10_r_phi"], 7),
                    "psi": round(x["psi"], 4), "omega_s": round(x["omega_s"], 4),
                    "e_sigma": 0.0 if k % 4 == 3 else round(x["e_sigma"], 4)})  # fmt: skip
    return out


def _fake_load(torques: np.ndarray) -> LoadCurveData:
    return LoadCurveData(torque=np.asarray(torques, float), speed=np.zeros(len(torques)),
                         speed_sd=None, drive_frequency_hz=F_HZ, phi0_rad=PHI0, rotor=ROTOR,
                         preload_n=PRELOAD, window_s=WINDOW, synthetic=True, path="<bench>")  # fmt: skip


def stall_torque(true: dict) -> tuple[float, float]:
    """``(torque scale, stall torque)`` in N·m: the first of 24 loads up to twice the torque
    scale at which one noise-free member's reading is not positive (twice the scale if none)."""
    theta = {"e": true["e"], "log10_r_phi": math.log10(true["r_phi"]), "psi": true["psi"],
             "omega_s": true["omega_s"], "e_sigma": 0.0}  # fmt: skip
    scale = lp.motor_scales(theta, _fake_load([0.0]))[2]
    loads = np.linspace(0.0, 2.0, 25)[1:] * scale
    speed = lp.curve_readings(theta, _fake_load(loads), 0, 0.0, 1)
    stop = np.flatnonzero(~(speed > 0.0))
    return scale, float(loads[stop[0]] if len(stop) else loads[-1])


def make_motor_data(folder: Path, true: dict, k: int, loads: int, repeats: int,
                    reading_noise: float) -> tuple[Path, Path]:  # fmt: skip
    """The run-up and load curve of motor ``k`` (module docstring), written to ``folder``."""
    rng = np.random.default_rng([SAMPLE_SEED, k])
    run = folder / "run.csv"
    df = synthesize_curve(true, F_HZ, PHI0, SPAN, DT, SIGMA, 1000 + k, member=0,
                          e_sigma=true["e_sigma"])  # fmt: skip
    write_curve(df, run, {"source": "benchmark", "synthetic": True,
                          "units": {"time": "s", "omega": "rad/s"},
                          "motor": {"drive_frequency_hz": F_HZ, "Phi0_rad": PHI0}})  # fmt: skip
    _, stall = stall_torque(true)
    params = {n: true[n] for n in ("e", "r_phi", "psi", "omega_s")}
    spec = {"parameters": params, "e_sigma": true["e_sigma"], "drive_frequency_hz": F_HZ,
            "Phi0_rad": PHI0, "rotor": ROTOR, "preload_N": PRELOAD,
            "load_curve": {"loads_Nm": list(np.linspace(0.0, 1.25 * stall, loads)),
                           "repeats": repeats, "window_s": list(WINDOW), "seed": 2000 + k}}  # fmt: skip
    if true["e_sigma"] == 0.0:  # deterministic: the repeats are one run, read `repeats` times
        spec["load_curve"]["repeats"] = 1
    ldf, side = synthetic_load_curve(spec)
    side["repeats"] = repeats
    ldf["speed_sd_rad_s"] = ldf["speed_sd_rad_s"].fillna(0.0)
    # independent reading noise: each of the `repeats` readings gets its own draw, so the mean
    # moves by noise/sqrt(repeats) and the spread adds the noise in quadrature (its expectation)
    ldf["speed_rad_s"] += rng.normal(0.0, reading_noise / math.sqrt(repeats), len(ldf))
    ldf["speed_sd_rad_s"] = np.sqrt(ldf["speed_sd_rad_s"] ** 2 + reading_noise**2)
    load = folder / "load.csv"
    write_curve(ldf, load, side)
    return run, load


def recover(true: dict, k: int, args) -> dict:
    """Fit motor ``k``; the row of the table (module docstring)."""
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        run, load = make_motor_data(Path(tmp), true, k, args.loads, args.repeats,
                                    args.reading_noise)  # fmt: skip
        made = time.perf_counter() - start
        settings = FitSettings(seed=FIT_SEED, scan=args.scan, zoom=args.zoom, cores=args.cores,
                               e_sigma=None)  # fmt: skip
        progress = (
            (lambda msg: print(f"motor {k}: {msg}", file=sys.stderr, flush=True))
            if args.progress
            else None
        )
        fit = fit_curve(read_curve(run), settings, progress, load=[read_load_curve(load)])
        ds = fit_dataset(fit)
    row = {"motor": k, "true": true, "chi2": round(float(ds.attrs["chi2"]), 3),
           "chi2_fresh": round(float(ds.attrs["chi2_fresh_members"]), 3),
           "n": int(ds.attrs["n_statistics"]), "adequate": ds.attrs["identified"] == "yes",
           "wall_s": round(time.perf_counter() - start - made, 1), "holds": {}, "widths": {},
           "chi2_truth": {part: round(float(ds.attrs.get(f"chi2_generating_{part}", math.nan)), 3)
                          for part in ("runup", "load", "both")}}  # fmt: skip
    for j, name in enumerate(str(n) for n in ds["parameter"].values):
        t = math.log10(true["r_phi"]) if name == "log10_r_phi" else true[name]
        lo, hi = float(ds["interval_low"].values[2, j]), float(ds["interval_high"].values[2, j])
        row["holds"][name] = bool(lo <= t <= hi)  # NaN (inadequate): False
        row["widths"][name] = round(hi - lo, 4)
    w = row["widths"]["log10_r_phi"]
    row["r_phi_factor"] = round(10.0**w, 3) if math.isfinite(w) else None
    row["all_hold"] = all(row["holds"].values())
    return row


def rates(rows: list[dict]) -> dict:
    """Success rates of ``rows`` against the targets (module docstring), and the intervals'
    coverage pooled over every parameter of every motor (:func:`coverage`)."""
    n = len(rows)
    names = list(rows[0]["holds"]) if rows else []
    return {
        "motors": n,
        "adequate": sum(r["adequate"] for r in rows) / n if n else math.nan,
        "holds": {m: sum(r["holds"][m] for r in rows) / n for m in names},
        "r_phi_factor_below_2": sum((r["r_phi_factor"] or math.inf) < 2 for r in rows) / n if n else math.nan,
        "coverage": coverage([sum(r["holds"].values()) for r in rows], len(names)),
        "targets": {"adequate": 0.9, "holds": 0.9, "r_phi_factor_below_2": 0.8},
    }  # fmt: skip


#: Seed and size of the bootstrap over motors of :func:`coverage`.
COVERAGE_SEED, COVERAGE_RESAMPLES = 20261126, 20000


def coverage(held: list[int], parameters: int) -> dict:
    """Intervals holding the truth, ``held[k]`` of motor ``k``'s ``parameters``, pooled.

    The 95 % interval of the pooled coverage resamples whole motors (a seeded bootstrap): one
    motor's intervals miss together (a wrong basin misses several), so the binomial interval
    of independent intervals (Clopper–Pearson, ``ci95_if_independent``) is too narrow. Also the
    chance that intervals of exactly 95 % coverage hold the truth on at least 90 % of the motors
    for one parameter (the per-parameter target): with 16 motors it is 0.81.
    """
    held = np.asarray(held, int)
    motors, intervals = len(held), len(held) * parameters
    if intervals == 0:
        return {"held": 0, "intervals": 0}
    rng = np.random.default_rng(COVERAGE_SEED)
    boot = held[rng.integers(0, motors, (COVERAGE_RESAMPLES, motors))].sum(axis=1) / intervals
    exact = binomtest(int(held.sum()), intervals).proportion_ci(0.95, method="exact")
    one = float(binom.cdf(motors - math.ceil(0.9 * motors), motors, 0.05))
    return {"held": int(held.sum()), "intervals": intervals, "rate": held.sum() / intervals,
            "ci95_motors": [round(float(q), 3) for q in np.percentile(boot, [2.5, 97.5])],
            "ci95_if_independent": [round(exact.low, 3), round(exact.high, 3)],
            "exact_intervals_meet_one_target": round(one, 3)}  # fmt: skip


def slice_arguments(ap: argparse.ArgumentParser, motors: int = 16) -> None:
    """The options that pick a slice of the sample and where its rows go (shared by the
    benchmarks that run motor by motor)."""
    ap.add_argument("--motors", type=int, default=motors, help="size of the Sobol' sample")
    ap.add_argument("--first", type=int, default=0, help="first motor of the slice run")
    ap.add_argument("--count", type=int, default=None, help="motors run (default: all)")
    ap.add_argument("--cores", type=int, default=2, help="threads for the members (default: 2)")
    ap.add_argument("--json", help="append each row to this file (JSON lines)")


def read_rows(ap: argparse.ArgumentParser, path: str) -> list[dict]:
    """The rows of a ``--json`` file (JSON lines); one argparse line when it holds none."""
    try:
        with open(path, encoding="utf-8") as f:
            return [json.loads(line) for line in f if line.strip()]
    except (OSError, ValueError) as ex:
        ap.error(f"--rates {path}: not rows of this benchmark ({ex})")


def run_slice(
    args: argparse.Namespace, one: Callable[[dict, int], dict], sample: list[dict] | None = None
) -> list[dict]:
    """``one(true, k)`` for every motor ``k`` of the slice ``args`` picks (of ``sample``, by
    default this benchmark's), each row printed as a JSON line (and appended to ``--json``) as
    soon as it is made."""
    sample = motors(args.motors) if sample is None else sample
    stop = len(sample) if args.count is None else min(len(sample), args.first + args.count)
    rows = []
    for k in range(args.first, stop):
        rows.append(one(sample[k], k))
        line = json.dumps(rows[-1])
        print(line, flush=True)
        if args.json:
            with open(args.json, "a", encoding="utf-8") as f:
                f.write(line + "\n")
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    slice_arguments(ap)
    ap.add_argument("--scan", type=int, default=192)
    ap.add_argument("--zoom", type=int, default=16)
    ap.add_argument("--loads", type=int, default=LOADS)
    ap.add_argument("--repeats", type=int, default=REPEATS)
    ap.add_argument("--reading-noise", type=float, default=READING_NOISE, help="rad/s per reading")
    ap.add_argument("--progress", action="store_true", help="the fits' progress on stderr")
    ap.add_argument("--rates", metavar="ROWS.json",
                    help="print the rates of the rows in this file (JSON lines, e.g. slices' "
                         "--json) instead of fitting")  # fmt: skip
    args = ap.parse_args()
    if args.rates:
        rows = read_rows(ap, args.rates)
        try:
            print(json.dumps(rates(rows)))
        except (KeyError, TypeError) as ex:
            ap.error(f"--rates {args.rates}: not rows of this benchmark ({ex})")
        return
    rows = run_slice(args, lambda true, k: recover(true, k, args))
    print(json.dumps(rates(rows)))


if __name__ == "__main__":
    main()
