"""Validation motors: the fit on motors and data designs drawn apart from any tuning.

Each motor is drawn with this benchmark's own seed (:data:`VALIDATION_SEED`, never the random
motors' of ``benchmarks/random_motors.py``): its parameters from a scrambled Sobol' sample over
the search box (every fourth at ``e_sigma = 0``), and its data design too: drive frequency 1-40
kHz and ``Phi0`` 0.1-2 mrad (log-uniform), a rotor of 0.5-20 g with its radius of gyration 2-8
mm, a run-up of 0.05-1 s sampled at 0.4 drive periods, and a load curve of 12 loads from none to
1.25 times the stall torque (its last loads on the slow branch past stall) read over a window of
30-3000 drive periods after as long a settling. The fit is the default joint fit
(``bouncedisk fit RUN.csv --load LOAD.csv``: ``e_sigma`` fitted, the default search). With
``--second-drive 0.7`` each motor also has a second load curve, of the same loads' design, at
0.7 times its drive frequency (the stator's amplitude, ``Phi0``, rotor and preload held: a
second condition, docs/user_guide/fitting.md "Conditions"); with ``--second-voltage 0.5`` a
second load curve at the same drive with both stator amplitudes (``U0`` and ``Phi0``) halved,
every curve stating its ``U0_m``. The fitted parameters are those at the run-up's condition. Nothing in the package names or reads these motors. ``--seed S`` draws
other motors of the same design (a tuning draw, kept apart from the validation motors; their
noise streams are keyed by the motor's index as the validation motors' are) and ``--scan N``
sets the fit's scan points, to compare search settings on tuning motors.

    python benchmarks/validation_motors.py --motors 32 [--first K --count N] [--cores 2]
        [--second-drive 0.7 | --second-voltage 0.5] [--seed S] [--scan N] [--json benchmarks/out/fit_validation_rows.jsonl]
    python benchmarks/validation_motors.py --rates benchmarks/out/fit_validation_rows.jsonl [--record]
    python benchmarks/validation_motors.py --rates benchmarks/out/fit_validation_2drives_rows.jsonl \
        --record --name fit_validation_2drives

Each row: the motor, its data design, ``χ²``, adequacy, which 95 % intervals hold the truth,
their widths (``R_phi`` as a factor, ``e``, ``psi``, ``omega_s``), the estimate, the generating
point's ``χ²`` under the fit's metric, both points' own likelihood (``loglik_own``,
:func:`bouncedisk.fitting.joint.generating_point_better`) and the wall time; ``--rates`` prints the success rate (adequate), the pooled coverage with its
interval over motors (resampling whole motors) and the widths' quartiles; with ``--record`` it
also writes them, and one line per motor, as the performance page's record
``benchmarks/out/fit_validation.json`` (another name with ``--name``, e.g.
``benchmarks/out/fit_validation_2drives.json``).
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from pathlib import Path

import numpy as np
from random_motors import coverage, read_rows, run_slice, slice_arguments

from bouncedisk.fitting import FitSettings, fit_curve, fit_dataset, synthesize_curve
from bouncedisk.fitting import loadpart as lp
from bouncedisk.fitting.joint import generating_point_better
from bouncedisk.fitting.members import BOUNDS
from bouncedisk.fitting.synthetic import synthetic_load_curve
from bouncedisk.io.load_curves import LoadCurveData, read_load_curve
from bouncedisk.io.runup_curves import read_curve, write_curve

#: The fit file's estimates kept in each row (global attributes).
ESTIMATE = ("e", "r_phi", "psi", "omega_s", "e_sigma")
#: This benchmark's own seed: its motors are drawn apart from every other sample.
VALIDATION_SEED = 49_2026_1127
#: The sample's coordinates: the parameters, then the data design (unit-box columns).
PARAMS = ("e", "log10_r_phi", "psi", "omega_s", "e_sigma")
DESIGN = ("log10_f_hz", "log10_phi0", "log10_m_r", "r_g_m", "log10_span_s", "log10_window")
#: Ranges of the data design (log10 where named so).
RANGES = {"log10_f_hz": (3.0, math.log10(4e4)), "log10_phi0": (-4.0, math.log10(2e-3)),
          "log10_m_r": (math.log10(5e-4), math.log10(2e-2)), "r_g_m": (2e-3, 8e-3),
          "log10_span_s": (math.log10(0.05), 0.0), "log10_window": (math.log10(30), 3.0)}  # fmt: skip
#: Samples per drive period of a run-up, its measurement noise (fraction of the steady speed's
#: scale R_phi Phi0 / t_c), the load curve's loads, repeats and reading noise (fraction, idem).
PER_PERIOD, NOISE, LOADS, REPEATS, READING_NOISE = 0.4, 0.005, 12, 5, 0.005
FIT_SEED = 1


def draw(n: int, seed: int = VALIDATION_SEED) -> list[dict]:
    """``n`` motors with their data designs (module docstring)."""
    from scipy.stats import qmc

    u = qmc.Sobol(d=len(PARAMS) + len(DESIGN), scramble=True, seed=seed).random(n).tolist()
    out = []
    for k, row in enumerate(u):
        p = {
            a: BOUNDS[a][0] + v * (BOUNDS[a][1] - BOUNDS[a][0])
            for a, v in zip(PARAMS, row[: len(PARAMS)], strict=True)
        }
        d = {a: RANGES[a][0] + v * (RANGES[a][1] - RANGES[a][0])
             for a, v in zip(DESIGN, row[len(PARAMS) :], strict=True)}  # fmt: skip
        f = 10.0 ** d["log10_f_hz"]
        window = 10.0 ** d["log10_window"] / f
        out.append({
            "e": round(p["e"], 4), "r_phi": round(10.0 ** p["log10_r_phi"], 7),
            "psi": round(p["psi"], 4), "omega_s": round(p["omega_s"], 4),
            "e_sigma": 0.0 if k % 4 == 3 else round(p["e_sigma"], 4),
            "f_hz": round(f, 1), "phi0": float(f"{10.0 ** d['log10_phi0']:.3g}"),
            "rotor": {"m_r_kg": float(f"{10.0 ** d['log10_m_r']:.3g}"),
                      "r_g_m": round(d["r_g_m"], 5), "r_c_m": round(d["r_g_m"] / 2, 5)},
            "span_s": float(f"{10.0 ** d['log10_span_s']:.3g}"),
            "window_s": [float(f"{window:.4g}"), float(f"{2 * window:.4g}")],
        })  # fmt: skip
    return out


def _theta(m: dict, noise: bool = True) -> dict:
    return {"e": m["e"], "log10_r_phi": math.log10(m["r_phi"]), "psi": m["psi"],
            "omega_s": m["omega_s"], **({"e_sigma": 0.0} if not noise else {})}  # fmt: skip


def _load(m: dict, torques) -> LoadCurveData:
    return LoadCurveData(torque=np.asarray(torques, float), speed=np.zeros(len(torques)),
                         speed_sd=None, drive_frequency_hz=m["f_hz"], phi0_rad=m["phi0"],
                         rotor=m["rotor"], preload_n=PRELOAD, window_s=tuple(m["window_s"]),
                         synthetic=True, path="<validation>")  # fmt: skip


#: The preload of every motor's load curve (N); the torque scale depends on the rotor only.
PRELOAD = 0.77


def stall(m: dict) -> float:
    """The first of 24 loads up to twice the torque scale at which one noise-free member's
    reading is not positive (twice the scale if none), N·m."""
    th = _theta(m, noise=False)
    scale = lp.motor_scales(th, _load(m, [0.0]))[2]
    loads = np.linspace(0.0, 2.0, 25)[1:] * scale
    speed = lp.curve_readings(th, _load(m, loads), 0, 0.0, 1)
    stop = np.flatnonzero(~(speed > 0.0))
    return float(loads[stop[0]] if len(stop) else loads[-1])


def u0(m: dict) -> float:
    """Motor ``m``'s axial amplitude ``U0 = g_eff t_c²`` (m), ``t_c = omega_s / 2π f``."""
    g_eff = 9.81 + PRELOAD / m["rotor"]["m_r_kg"]
    return g_eff * (m["omega_s"] / (2 * math.pi * m["f_hz"])) ** 2


def at_condition(m: dict, condition: tuple[float, float]) -> dict:
    """Motor ``m`` driven at ``drive`` times its drive frequency and ``voltage`` times its
    stator's amplitudes (``U0`` and ``Phi0``; ``condition = (drive, voltage)``), its rotor and
    preload held: ``omega_s`` and ``R_phi`` converted (:func:`bouncedisk.fitting.loadpart.convert`),
    and ``u0_m``, the amplitude its curve states, where ``m`` states one."""
    drive, voltage = condition
    if condition == (1.0, 1.0):
        return m
    a = u0(m)
    src = lp.Setup(m["f_hz"], m["phi0"], m["rotor"], PRELOAD, a)
    dst = lp.Setup(m["f_hz"] * drive, m["phi0"] * voltage, m["rotor"], PRELOAD, a * voltage)
    at = lp.convert(_theta(m), src, dst)
    out = dict(m, f_hz=dst.f, phi0=dst.phi0, omega_s=at["omega_s"], r_phi=10.0 ** at["log10_r_phi"])
    if "u0_m" in m:  # the curves state their amplitudes (make_data)
        out["u0_m"] = dst.u0
    return out


def write_load_curve(path: Path, m: dict, seed: int, key: list[int]) -> Path:
    """Motor ``m``'s 12-load curve to 1.25 times its stall torque, ``REPEATS`` readings a load
    (members' seed ``seed``) with the reading noise (stream ``key``) added (module docstring),
    written to ``path``."""
    rng = np.random.default_rng([VALIDATION_SEED, *key])
    speed = m["r_phi"] * m["phi0"] / (m["omega_s"] / (2 * math.pi * m["f_hz"]))
    params = {n: m[n] for n in ("e", "r_phi", "psi", "omega_s")}
    spec = {"parameters": params, "e_sigma": m["e_sigma"], "drive_frequency_hz": m["f_hz"],
            "Phi0_rad": m["phi0"], "rotor": m["rotor"], "preload_N": PRELOAD,
            "load_curve": {"loads_Nm": list(np.linspace(0.0, 1.25 * stall(m), LOADS)),
                           "repeats": REPEATS if m["e_sigma"] > 0 else 1,
                           "window_s": m["window_s"], "seed": seed}}  # fmt: skip
    ldf, side = synthetic_load_curve(spec)
    side["repeats"] = REPEATS
    if "u0_m" in m:  # the amplitudes are conditions: every curve states its own
        side["motor"]["U0_m"] = m["u0_m"]
    noise = READING_NOISE * speed
    ldf["speed_sd_rad_s"] = np.sqrt(ldf["speed_sd_rad_s"].fillna(0.0) ** 2 + noise**2)
    ldf["speed_rad_s"] += rng.normal(0.0, noise / math.sqrt(REPEATS), len(ldf))
    write_curve(ldf, path, side)
    return path


def make_data(folder: Path, m: dict, k: int, conditions: tuple) -> tuple[Path, list]:
    """Motor ``k``'s run-up, and a load curve at each of ``conditions`` (``(drive, voltage)``
    factors, :func:`at_condition`; module docstring), written to ``folder``."""
    t_c = m["omega_s"] / (2 * math.pi * m["f_hz"])
    speed = m["r_phi"] * m["phi0"] / t_c  # rad/s per unit of nondimensional speed
    dt = PER_PERIOD / m["f_hz"]
    params = {n: m[n] for n in ("e", "r_phi", "psi", "omega_s")}
    df = synthesize_curve(params, m["f_hz"], m["phi0"], m["span_s"], dt, NOISE * speed,
                          5000 + k, member=0, e_sigma=m["e_sigma"])  # fmt: skip
    run = folder / "run.csv"
    motor = {"drive_frequency_hz": m["f_hz"], "Phi0_rad": m["phi0"]}
    if any(v != 1.0 for _, v in conditions):
        m = dict(m, u0_m=u0(m))
        motor["U0_m"] = m["u0_m"]
    write_curve(df, run, {"source": "benchmark", "synthetic": True,
                          "units": {"time": "s", "omega": "rad/s"}, "motor": motor})  # fmt: skip
    loads = [write_load_curve(folder / f"load{j}.csv", at_condition(m, c), 6000 + k + 1000 * j,
                              [k, j] if j else [k]) for j, c in enumerate(conditions)]  # fmt: skip
    return run, loads


def recover(
    m: dict, k: int, cores: int, conditions: tuple = ((1.0, 1.0),), scan: int = FitSettings.scan
) -> dict:
    """Fit motor ``k`` jointly (the default fit, at ``scan`` scan points) on its run-up and its
    load curves at ``conditions`` (``(drive, voltage)`` factors), and read its intervals against
    the truth."""
    with tempfile.TemporaryDirectory() as tmp:
        run, loads = make_data(Path(tmp), m, k, conditions)
        start = time.perf_counter()
        settings = FitSettings(seed=FIT_SEED, cores=cores, scan=scan)
        fit = fit_curve(read_curve(run), settings,
                        load=[read_load_curve(x) for x in loads])  # fmt: skip
        ds = fit_dataset(fit)
    drives, voltages = ([c[i] for c in conditions] for i in (0, 1))
    row = {"motor": k, "true": m, "drives": drives, "voltages": voltages, "scan": scan, "chi2": round(float(ds.attrs["chi2"]), 3),
           "n": int(ds.attrs["n_statistics"]), "adequate": ds.attrs["identified"] == "yes",
           "wall_s": round(time.perf_counter() - start, 1), "holds": {}, "widths": {},
           "chi2_truth": round(float(ds.attrs.get("chi2_generating_both", math.nan)), 3),
           "loglik_own": {p: round(float(ds.attrs.get(f"loglik_own_{p}", math.nan)), 3)
                          for p in ("generating", "estimate")},
           "estimate": {p: round(float(ds.attrs[p]), 7) for p in ESTIMATE}}  # fmt: skip
    truth = {**_theta(m), "e_sigma": m["e_sigma"]}
    both = [str(s) for s in ds["data_set"].values].index("both")
    for j, name in enumerate(str(n) for n in ds["parameter"].values):
        lo, hi = (float(ds[v].values[both, j]) for v in ("interval_low", "interval_high"))
        row["holds"][name] = bool(lo <= truth[name] <= hi)  # NaN (inadequate): False
        row["widths"][name] = round(hi - lo, 4)
    w = row["widths"]["log10_r_phi"]
    row["r_phi_factor"] = round(10.0**w, 3) if math.isfinite(w) else None
    return row


def rates(rows: list[dict]) -> dict:
    """Success rate, pooled coverage with its interval over motors, and the widths' quartiles
    of the adequate motors."""
    n = len(rows)
    names = list(rows[0]["holds"]) if rows else []
    ok = [r for r in rows if r["adequate"]]

    def quartiles(name):
        v = [r["widths"][name] for r in ok]
        return [round(float(q), 4) for q in np.percentile(v, [25, 50, 75])] if v else None

    return {"motors": n, "adequate": sum(r["adequate"] for r in rows) / n if n else math.nan,
            "coverage": coverage([sum(r["holds"].values()) for r in rows], len(names)),
            "holds_by_parameter": {m: sum(r["holds"][m] for r in rows) for m in names},
            "generating_point_below_held": sum(r["chi2_truth"] < r["chi2"] for r in rows),
            "generating_point_better_own": sum(_own_better(r) for r in _with_own(rows)),
            "rows_with_own": len(_with_own(rows)),
            "r_phi_factor_below_2": sum((r["r_phi_factor"] or math.inf) < 2 for r in rows) / n
            if n else math.nan,
            "width_quartiles": {m: quartiles(m) for m in ("log10_r_phi", "e", "psi", "omega_s")},
            "wall_s_max": max((r["wall_s"] for r in rows), default=math.nan)}  # fmt: skip


def _with_own(rows: list[dict]) -> list[dict]:
    """The rows whose fit file read the generating point's own likelihood."""
    return [
        r
        for r in rows
        if all(math.isfinite(v) for v in r.get("loglik_own", {"": math.nan}).values())
    ]


def _own_better(r: dict) -> bool:
    """Whether the fit file's ``loglik_own_*`` say the generating point is more likely than the
    estimate (:func:`bouncedisk.fitting.joint.generating_point_better`)."""
    return generating_point_better(r["loglik_own"])


def motor_line(r: dict) -> tuple[str, str]:
    """One motor's row of the record: its design, and what the fit found against the truth."""
    t = r["true"]
    design = (f"validation motor {r['motor']}: {t['f_hz'] / 1e3:.3g} kHz, Phi0 {t['phi0']:.3g} rad, "
              f"rotor {1e3 * t['rotor']['m_r_kg']:.3g} g, run-up {t['span_s']:.3g} s, e_sigma "
              f"{t['e_sigma']:g}")  # fmt: skip
    held = [n for n, ok in r["holds"].items() if ok]
    factor = r["r_phi_factor"]
    own = ""
    if "loglik_own" in r:
        own = (f"; -2 log L with its own covariance {r['loglik_own']['generating']:g}, the "
               f"estimate {r['loglik_own']['estimate']:g}")  # fmt: skip
    result = (f"chi2 {r['chi2']:g} on {r['n']} (the generating point {r['chi2_truth']:g}{own}), "
              f"{'adequate' if r['adequate'] else 'inadequate'}; {len(held)} of "
              f"{len(r['holds'])} intervals hold the truth; R_phi to a factor "
              f"{'none' if factor is None else f'{factor:g}'}; {r['wall_s']:g} s")  # fmt: skip
    return design, result


def conditions_from(second_drive: float | None, second_voltage: float | None) -> tuple:
    """The load curves' conditions, ``(drive, voltage)`` factors: the run-up's, then a second
    drive frequency and a second drive voltage where given (``--second-drive``,
    ``--second-voltage``)."""
    conditions = [(1.0, 1.0)]
    if second_drive is not None:
        conditions.append((second_drive, 1.0))
    if second_voltage is not None:
        conditions.append((1.0, second_voltage))
    return tuple(conditions)


def conditions_of(row: dict) -> list[tuple[float, float]]:
    """A row's load-curve conditions, ``(drive, voltage)`` factors (rows without voltages: 1)."""
    drives = row.get("drives", [1.0])
    return list(zip(drives, row.get("voltages", [1.0] * len(drives)), strict=True))


def condition_words(c: tuple[float, float]) -> str:
    """``(drive, voltage)`` factors in words."""
    drive, voltage = c
    if voltage == 1.0:
        return f"{drive:g} x the drive frequency"
    return f"{voltage:g} x the drive voltage"


def write_rates_record(rows: list[dict], name: str = "fit_validation") -> None:
    """The rates and the motors' lines as the performance page's record named ``name``."""
    from record import write_record

    r = rates(rows)
    c, q = r["coverage"], r["width_quartiles"]
    summary = (f"{round(100 * r['adequate'])} % adequate; {c['held']} of {c['intervals']} intervals "
               f"hold the truth ({100 * c.get('rate', math.nan):.0f} %, over motors "
               f"{c.get('ci95_motors')}); R_phi to a factor below 2 on "
               f"{round(100 * r['r_phi_factor_below_2'])} %; the generating point reads below the "
               f"fit on {r['generating_point_below_held']}"
               + (f" (by the own likelihood of each point on {r['generating_point_better_own']} of "
                  f"{r['rows_with_own']})" if r["rows_with_own"] else "")
               + f"; median widths e {q['e'] and q['e'][1]}, "
               f"psi {q['psi'] and q['psi'][1]}, omega_s {q['omega_s'] and q['omega_s'][1]}; "
               f"longest fit {r['wall_s_max']:g} s")  # fmt: skip
    designs = sorted({tuple(conditions_of(x)) for x in rows})
    design = " and ".join(" + ".join(condition_words(c) for c in cs) for cs in designs)
    lines = [(f"the default joint fit on {r['motors']} validation motors, load curves at "
              f"{design}", summary)]  # fmt: skip
    second = [c for cs in designs for c in cs[1:]]
    title = "The fit on validation motors" + (
        ", two drive voltages" if any(v != 1.0 for _, v in second)
        else ", two drive frequencies" if second else ""
    )  # fmt: skip
    write_record(name, title,
                 lines + [motor_line(x) for x in rows])  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    slice_arguments(ap, motors=32)
    ap.add_argument("--rates", metavar="ROWS.jsonl", help="the rates of these rows, no fit")
    ap.add_argument("--record", action="store_true", help="with --rates: write the record")
    ap.add_argument(
        "--second-drive",
        type=float,
        metavar="FACTOR",
        help="a second load curve at FACTOR times the drive frequency (e.g. 0.7)",
    )
    ap.add_argument(
        "--second-voltage",
        type=float,
        metavar="FACTOR",
        help="a second load curve at FACTOR times the drive voltage: U0 and Phi0 (e.g. 0.5)",
    )
    ap.add_argument(
        "--seed",
        type=int,
        default=VALIDATION_SEED,
        help="draw the motors with another seed: a tuning draw of the same design",
    )
    ap.add_argument(
        "--scan",
        type=int,
        default=FitSettings.scan,
        help="scan points of the fit (the fit's default)",
    )
    ap.add_argument(
        "--name",
        default="fit_validation",
        help="with --record: the record's name in benchmarks/out/ (fit_validation)",
    )
    args = ap.parse_args()
    if args.rates:
        rows = read_rows(ap, args.rates)
        try:
            print(json.dumps(rates(rows)))
            if args.record:
                write_rates_record(rows, args.name)
        except (KeyError, TypeError) as ex:
            ap.error(f"--rates {args.rates}: not rows of this benchmark ({ex})")
        return
    conditions = conditions_from(args.second_drive, args.second_voltage)
    sample = draw(args.motors, args.seed)
    run = lambda true, k: recover(true, k, args.cores, conditions, args.scan)  # noqa: E731
    rows = run_slice(args, run, sample)
    print(json.dumps(rates(rows)))


if __name__ == "__main__":
    main()
