"""Adapter: the load characteristic of one scene (`bouncedisk torque-speed`)."""

import time

from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.scene import load_scene
from bouncedisk.studies.load_summary import REFINE_ROUNDS
from bouncedisk.studies.torque_speed import refined_torque_speed, scene_loads, to_dataset

with log_to(snakemake.log[0]) as log:
    scene = load_scene(snakemake.input.scene)
    # N*m for a physical scene, as `bouncedisk torque-speed --loads` reads them
    field = f"load_curves.{snakemake.wildcards.curve}.loads"  # the config's key, named whole
    loads = scene_loads(scene, snakemake.params.spec["loads"], "workflow/config/config.yaml", field)
    start = time.perf_counter()
    resolution = snakemake.params.spec.get("resolution")  # none: the loads as given
    rounds = REFINE_ROUNDS if resolution is not None else 0
    curve = refined_torque_speed(scene, loads, resolution or 0.0, rounds, cores=snakemake.threads)
    s = curve.summary()
    write_dataset(to_dataset(scene, curve, time.perf_counter() - start, s), snakemake.output[0])
    log.info("%s: stall %s %s (%s), max power %s at %s (%s), %d loads", scene.name,
             s["stall_torque"], s["stall_torque_ci95"], s["stall_torque_state"], s["max_power"],
             s["max_power_load"], s["max_power_state"], len(curve.loads))  # fmt: skip
