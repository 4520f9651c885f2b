"""Adapter: run one shard of a parameter sweep."""

from bouncedisk.analysis.sweeps import grid_values, run_sweep
from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.scene import load_scene

with log_to(snakemake.log[0]) as log:
    spec = snakemake.params.spec
    scene = load_scene(snakemake.input.scene)
    axes = [(name, grid_values(v)) for name, v in spec["axes"].items()]
    shard = int(snakemake.wildcards.shard)

    def progress(done, total):
        if done % 50 == 0 or done == total:
            log.info("%d / %d grid points", done, total)

    ds = run_sweep(
        scene,
        axes,
        shard=shard,
        n_shards=spec["shards"],
        tail=spec["tail"],
        progress=progress,
        cores=snakemake.threads,
    )
    write_dataset(ds, snakemake.output[0])
