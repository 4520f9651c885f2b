"""Adapter: run one shard of a parameter sweep."""

from bouncedisk.datasets import write_dataset
from bouncedisk.logutil import log_to
from bouncedisk.scene import load_scene
from bouncedisk.sweeps import grid_values, run_sweep

with log_to(snakemake.log[0]) as log:
    spec = snakemake.params.spec
    scene = load_scene(snakemake.input.scene)
    axes = [(name, grid_values(v)) for name, v in spec["axes"].items()]
    shard = int(snakemake.wildcards.shard)

    def progress(done, total):
        if done % 50 == 0 or done == total:
            log.info("%d / %d grid points", done, total)

    ds = run_sweep(
        scene, axes, shard=shard, n_shards=spec["shards"], tail=spec["tail"], progress=progress
    )
    write_dataset(ds, snakemake.output[0])
