"""Adapter: run one shard of the basin map's starts."""

from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.scene import load_scene
from bouncedisk.studies.basins import parse_values, run_starts, start_grid

with log_to(snakemake.log[0]) as log:
    spec = snakemake.params.spec
    scene = load_scene(snakemake.input.scene)
    grid = start_grid(
        spec["phases"],
        parse_values(spec["speeds"], "basins.map.speeds", "speed", "workflow/config/config.yaml"),
        parse_values(
            spec["heights"], "basins.map.heights", "height", "workflow/config/config.yaml"
        ),
    )
    shard = int(snakemake.wildcards.shard)
    ds = run_starts(scene, grid, shard=shard, n_shards=spec["shards"], cores=snakemake.threads)
    write_dataset(ds, snakemake.output[0])
    log.info("%s: %d of %d starts", snakemake.output[0], ds.sizes["start"], grid.size)
