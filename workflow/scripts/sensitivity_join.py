"""Adapter: join the sensitivity study's shards in sample order."""

from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import open_checked, write_dataset
from bouncedisk.studies.sensitivity import join_shards

with log_to(snakemake.log[0]) as log:
    shards = [open_checked(p, required=("x", "regime")) for p in snakemake.input.shards]
    ds = join_shards(shards)
    write_dataset(ds, snakemake.output[0])
    log.info("%s: %d points", snakemake.output[0], ds.sizes["point"])
