"""Adapter: the load characteristic of one scene (`bouncedisk torque-speed`)."""

import time

from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.scene import load_scene
from bouncedisk.studies.torque_speed import scene_loads, to_dataset, torque_speed

with log_to(snakemake.log[0]) as log:
    scene = load_scene(snakemake.input.scene)
    # N*m for a physical scene, as `bouncedisk torque-speed --loads` reads them
    loads = scene_loads(
        scene, snakemake.params.spec["loads"], "workflow/config/config.yaml", "loads"
    )
    start = time.perf_counter()
    curve = torque_speed(scene, loads, cores=snakemake.threads)
    s = curve.summary()
    write_dataset(to_dataset(scene, curve, time.perf_counter() - start, s), snakemake.output[0])
    log.info("%s: stall %s, max power %s at %s", scene.name, s["stall_torque"], s["max_power"],
             s["max_power_load"])  # fmt: skip
