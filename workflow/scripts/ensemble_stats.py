"""Adapter: ensemble statistics of one scene (`bouncedisk stats`)."""

import time

from bouncedisk.analysis.statistics import run_stats, to_dataset
from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.scene import load_scene

with log_to(snakemake.log[0]) as log:
    scene = load_scene(snakemake.input.scene)
    start = time.perf_counter()
    result = run_stats(scene, cores=snakemake.threads)
    write_dataset(to_dataset(scene, result, time.perf_counter() - start), snakemake.output[0])
    log.info("%s: %s", snakemake.output[0], result.summary())
