"""Adapter: impact map and stroboscopic map of a simulation file."""

from bouncedisk.analysis.poincare import poincare_dataset
from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import open_simulation, write_dataset

with log_to(snakemake.log[0]) as log:
    sim = open_simulation(snakemake.input.sim)
    ds = poincare_dataset(sim, transient=snakemake.params.transient)
    write_dataset(ds, snakemake.output[0])
    log.info(
        "%s: %d impacts, %d stroboscopic points",
        snakemake.output[0],
        ds.sizes.get("impact", 0),
        ds.sizes.get("period", 0),
    )
