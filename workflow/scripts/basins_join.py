"""Adapter: join the basin map's shards (every start once) and group the starts into attractors."""

from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import open_checked, write_dataset
from bouncedisk.studies.basins import group, join_shards

with log_to(snakemake.log[0]) as log:
    shards = [open_checked(p, required=("mean_omega", "regime")) for p in snakemake.input.shards]
    ds = group(join_shards(shards))
    ds.attrs["history"] = f"joined from {len(shards)} shards"
    write_dataset(ds, snakemake.output[0])
    log.info("%s: %d starts, %d attractors", snakemake.output[0], ds.sizes["start"],
             ds.sizes["attractor"])  # fmt: skip
