"""Adapter: ensemble statistics of one scene (`bouncedisk stats`)."""

import time

from bouncedisk.datasets import write_dataset
from bouncedisk.logutil import log_to
from bouncedisk.scene import load_scene
from bouncedisk.stats import run_stats, to_dataset

with log_to(snakemake.log[0]) as log:
    scene = load_scene(snakemake.input.scene)
    start = time.perf_counter()
    result = run_stats(scene, cores=snakemake.threads)
    write_dataset(to_dataset(scene, result, time.perf_counter() - start), snakemake.output[0])
    log.info("%s: %s", snakemake.output[0], result.summary())
