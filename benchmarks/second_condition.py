"""Which second condition separates the basins one run-up and one load curve leave open.

On the shipped synthetic motor (``workflow/config/synthetic_motor.yaml``) the default fit of the
run-up and the load curve ends in a basin other than the generating point's, which reproduces
the data as well (docs/fitting_method.md "What it recovers"). A lab can run the motor a second
way; this benchmark makes, for each candidate second condition, a load curve of the generating
motor run that way (:func:`bouncedisk.fitting.synthetic.synthetic_load_curve`, the same loads
as fractions of the condition's torque scale, 5 repeats) and reads it alone at both points,
stated at the shipped condition (:class:`bouncedisk.fitting.loadpart.LoadPart`, each point's own
members' covariance, 32 members for the covariance and 8 for the mean, as the fit). The second curve's
``χ²`` at the fit's basin against the generating point's says how strongly that condition
rejects the basin: the condition to recommend is the one with the largest gap.

    python benchmarks/second_condition.py results/fit/prototype.nc [--record]

``--record`` writes ``benchmarks/out/fit_conditions.json`` (the performance page's record).
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np
import xarray as xr

from bouncedisk.fitting import loadpart as lp
from bouncedisk.fitting.synthetic import read_spec, synthetic_load_curve
from bouncedisk.io.load_curves import read_load_curve
from bouncedisk.io.runup_curves import write_curve

SPEC = "workflow/config/synthetic_motor.yaml"
SHIPPED_LOAD = "data/prototype/synthetic_motor_load.csv"
#: The candidate second conditions: changes to the shipped motor's drive, rotor, preload or the
#: stator's axial amplitude (factors).
CONDITIONS = {
    "drive frequency x 1.5": {"drive_frequency_hz": 1.5},
    "drive frequency x 0.7": {"drive_frequency_hz": 0.7},
    "added inertia: r_g x 1.5": {"r_g_m": 1.5},
    "preload x 3": {"preload_N": 3.0},
    "axial amplitude x 0.5": {"U0_m": 0.5},
    "axial amplitude x 2": {"U0_m": 2.0},
    "drive voltage x 0.5 (U0 and Phi0 halved)": {"U0_m": 0.5, "Phi0_rad": 0.5},
}
#: The stated axial amplitude of the shipped condition (m): only ratios of amplitudes are read
#: (:func:`bouncedisk.fitting.loadpart.convert`), so any value serves.
U0_NOMINAL = 1.0e-6
#: Members of each point's covariance and of its mean reading (the fit's LOAD_PILOT, LOAD_MEMBERS).
COV_MEMBERS, MEAN_MEMBERS = lp.LOAD_PILOT, lp.LOAD_MEMBERS


def condition_spec(spec: dict, change: dict) -> dict:
    """The shipped motor's spec run as ``change`` says (factors on the drive frequency, the
    rotor's ``r_g_m``, the preload, the axial amplitude ``U0_m`` or ``Φ0``), its parameters converted to
    that condition and its loads the shipped ones as fractions of the torque scale."""
    ref = lp.Setup(
        spec["drive_frequency_hz"], spec["Phi0_rad"], spec["rotor"], spec["preload_N"], U0_NOMINAL
    )
    rotor = {k: v * change.get(k, 1.0) for k, v in spec["rotor"].items()}
    cond = lp.Setup(
        ref.f * change.get("drive_frequency_hz", 1.0),
        ref.phi0 * change.get("Phi0_rad", 1.0),
        rotor,
        ref.preload * change.get("preload_N", 1.0),
        U0_NOMINAL * change.get("U0_m", 1.0),
    )
    p = spec["parameters"]
    theta = {
        "e": p["e"],
        "log10_r_phi": math.log10(p["r_phi"]),
        "psi": p["psi"],
        "omega_s": p["omega_s"],
    }
    at = lp.convert(theta, ref, cond)
    t0 = lp.motor_scales(theta, _data(ref))[2]
    t1 = lp.motor_scales(at, _data(cond))[2]
    out = dict(
        spec, drive_frequency_hz=cond.f, Phi0_rad=cond.phi0, rotor=rotor, preload_N=cond.preload
    )
    out["parameters"] = dict(p, omega_s=at["omega_s"], r_phi=10.0 ** at["log10_r_phi"])
    loads = [x * t1 / t0 for x in spec["load_curve"]["loads_Nm"]]
    out["load_curve"] = dict(
        spec["load_curve"], loads_Nm=loads, seed=spec["load_curve"]["seed"] + 100
    )
    return out


def _data(s: lp.Setup):
    """A load curve of one zero load run as ``s`` states (for its scales only)."""
    from bouncedisk.io.load_curves import LoadCurveData

    return LoadCurveData(np.zeros(1), np.zeros(1), None, s.f, s.phi0, s.rotor, s.preload,
                         (0.0, 1.0), True, "<scales>")  # fmt: skip


def chi2_second(curve, ref: lp.Setup, x: dict, seed: int) -> float:
    """``χ²`` of the second ``curve``'s readings alone at point ``x`` (stated at the shipped
    condition ``ref``, with its ``e_sigma``), under the point's own members' covariance."""
    part = lp.LoadPart([curve], x["e_sigma"], seed, given_reference=ref)
    key = np.array([x[k] for k in ("e", "log10_r_phi", "psi", "omega_s", "e_sigma")])
    part.set_cov(part.values(x, key, COV_MEMBERS))
    r = part.residuals(x, key, MEAN_MEMBERS)
    return float(r @ r)


def points(fit: Path, spec: dict) -> dict[str, dict]:
    """The generating point and the fit's estimate (search coordinates with ``e_sigma``)."""
    with xr.open_dataset(fit) as ds:
        est = {n: float(ds[n]) for n in ("e", "r_phi", "psi", "omega_s")}
        est["e_sigma"] = float(ds["e_sigma"]) if "e_sigma" in ds else float(ds.attrs["e_sigma"])
    p = spec["parameters"]
    out = {}
    for name, v in (("generating", {**p, "e_sigma": spec["e_sigma"]}), ("fit", est)):
        out[name] = {"e": v["e"], "log10_r_phi": math.log10(v["r_phi"]), "psi": v["psi"],
                     "omega_s": v["omega_s"], "e_sigma": v["e_sigma"]}  # fmt: skip
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "fit", type=Path, help="the shipped motor's fit file (results/fit/prototype.nc)"
    )
    ap.add_argument("--record", action="store_true", help="write the performance page's record")
    args = ap.parse_args()
    if not args.fit.is_file():
        ap.error(f"{args.fit}: no fit file; run the pipeline first (snakemake --cores 2)")
    spec = read_spec(SPEC)
    pts = points(args.fit, spec)
    # the shipped condition with its amplitude stated: each second curve states its own
    ref = lp.setup(read_load_curve(SHIPPED_LOAD))._replace(u0=U0_NOMINAL)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, change in CONDITIONS.items():
            df, side = synthetic_load_curve(condition_spec(spec, change))
            side["motor"]["U0_m"] = U0_NOMINAL * change.get("U0_m", 1.0)
            path = Path(tmp) / "second.csv"
            write_curve(df, path, side)
            second = read_load_curve(path)
            chi = {k: chi2_second(second, ref, x, seed=1) for k, x in pts.items()}
            n = len(df)
            line = (f"chi2 of its {n} readings: {chi['generating']:.3g} at the generating point, "
                    f"{chi['fit']:.3g} at the basin the fit found")  # fmt: skip
            print(f"{name}: {line}", flush=True)
            rows.append((f"second load curve, {name}", line))
    if args.record:
        from record import write_record

        write_record("fit_conditions", "A second condition against the basins of one", rows)


if __name__ == "__main__":
    main()
