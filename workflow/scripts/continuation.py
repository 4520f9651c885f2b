"""Adapter: one direction of the continuation (bifurcation diagram)."""

from bouncedisk.analysis.sweeps import grid_values, run_continuation
from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.scene import load_scene

with log_to(snakemake.log[0]) as log:
    spec = snakemake.params.spec
    scene = load_scene(snakemake.input.scene)

    def progress(done, total):
        if done % 25 == 0 or done == total:
            log.info("%d / %d points", done, total)

    ds = run_continuation(
        scene,
        spec["parameter"],
        grid_values(spec["axis"]),
        direction=snakemake.wildcards.direction,
        tail=spec["tail"],
        progress=progress,
    )
    write_dataset(ds, snakemake.output[0])
