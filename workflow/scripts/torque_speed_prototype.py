"""Adapter: the load characteristic of the fitted prototype motor, in SI units."""

import time
from pathlib import Path

import xarray as xr

from bouncedisk.io.job_log import exit_with_error, log_to
from bouncedisk.io.load_curves import read_load_curve
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.params import Parameters
from bouncedisk.studies.load_summary import REFINE_ROUNDS
from bouncedisk.studies.torque_speed import (
    motor_scene,
    parse_loads,
    refined_torque_speed,
    to_dataset,
)

with log_to(snakemake.log[0]) as log:
    spec = snakemake.params.spec
    if not snakemake.input.curve:
        exit_with_error(
            "workflow/config/config.yaml: prototype.load_curve: not set, so the fitted motor's "
            "rotor and preload, which its SI load characteristic needs, are unknown"
        )
    rig = read_load_curve(snakemake.input.curve[0])  # the rotor and preload the motor ran with
    with xr.open_dataset(snakemake.input.fit) as fit:
        fitted = {k: float(fit[k]) for k in ("e", "omega_s", "r_phi", "psi")}
        e_sigma = float(fit.attrs["e_sigma"])
        drive, phi0 = float(fit.attrs["drive_frequency_hz"]), fit.attrs["Phi0_rad"]
    phi0 = rig.phi0_rad if phi0 == "unknown" else float(phi0)  # the run-ups' sidecars gave none
    scene = motor_scene(
        Parameters(**fitted, e_sigma=e_sigma), drive, phi0, rig.rotor, rig.preload_n,
        spec["members"], spec["time"], spec["discard"],
    )  # fmt: skip
    loads = parse_loads(spec["loads"], "workflow/config/config.yaml", "prototype_load.loads")
    start = time.perf_counter()
    resolution = spec.get("resolution")  # none: the loads as given
    rounds = REFINE_ROUNDS if resolution is not None else 0
    curve = refined_torque_speed(scene, loads, resolution or 0.0, rounds, cores=snakemake.threads)
    ds = to_dataset(scene, curve, time.perf_counter() - start)
    ds.attrs["fit_file"] = "fit/prototype.nc (in the results folder)"
    # the figure's title: short (the rotor's source is the caption's and the formats page's)
    run_up = Path(snakemake.config["prototype"]["curve"]).name
    ds.attrs["motor_description"] = f"the fitted model of the motor of {run_up}, in SI units"
    write_dataset(ds, snakemake.output[0])
    s = curve.summary()
    log.info("fitted motor %s: stall %s N*m %s (%s), max power %s W (%s), %d loads", fitted,
             s.get("stall_torque_Nm"), s.get("stall_torque_Nm_ci95"), s["stall_torque_state"],
             s.get("max_power_W"), s["max_power_state"], len(curve.loads))  # fmt: skip
