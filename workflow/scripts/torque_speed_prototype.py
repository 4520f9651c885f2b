"""Adapter: the load characteristic of the fitted prototype motor, in SI units."""

import time

import xarray as xr
import yaml

from bouncedisk.io.job_log import log_to
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
    motor = yaml.safe_load(open(snakemake.input.motor))
    with xr.open_dataset(snakemake.input.fit) as fit:
        fitted = {k: float(fit[k]) for k in ("e", "omega_s", "r_phi", "psi")}
        e_sigma = float(fit.attrs["e_sigma"])
    scene = motor_scene(
        Parameters(**fitted, e_sigma=e_sigma), motor["drive_frequency_hz"], motor["Phi0_rad"],
        motor["rotor"], motor["preload_N"], spec["members"], spec["time"], spec["discard"],
    )  # fmt: skip
    loads = parse_loads(spec["loads"], "workflow/config/config.yaml", "prototype_load.loads")
    start = time.perf_counter()
    resolution = spec.get("resolution")  # none: the loads as given
    rounds = REFINE_ROUNDS if resolution is not None else 0
    curve = refined_torque_speed(scene, loads, resolution or 0.0, rounds, cores=snakemake.threads)
    ds = to_dataset(scene, curve, time.perf_counter() - start)
    ds.attrs["fit_file"] = "fit/prototype.nc (in the results folder)"
    ds.attrs["motor_description"] = "the fitted model of the synthetic prototype motor, in SI units"
    write_dataset(ds, snakemake.output[0])
    s = curve.summary()
    log.info("fitted motor %s: stall %s N*m %s (%s), max power %s W (%s), %d loads", fitted,
             s.get("stall_torque_Nm"), s.get("stall_torque_Nm_ci95"), s["stall_torque_state"],
             s.get("max_power_W"), s["max_power_state"], len(curve.loads))  # fmt: skip
