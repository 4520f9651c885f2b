"""Adapter: join the shards of a sweep into one netCDF file."""

from bouncedisk.analysis.sweeps import combine_shards
from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import open_checked, write_dataset

with log_to(snakemake.log[0]) as log:
    shards = [open_checked(p, required=("regime",)) for p in snakemake.input.shards]
    ds = combine_shards(shards)
    ds.attrs["history"] = f"combined from {len(shards)} shards"
    write_dataset(ds, snakemake.output[0])
    log.info("%s: %s", snakemake.output[0], dict(ds.sizes))
