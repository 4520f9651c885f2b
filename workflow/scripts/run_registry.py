"""Adapter: gather the run registry from every output's provenance."""

from bouncedisk import registry
from bouncedisk.logutil import log_to

with log_to(snakemake.log[0]) as log:
    table = registry.build(list(snakemake.input.files), benchmarks_dir=snakemake.params.benchmarks)
    registry.write(table, snakemake.output[0])
    log.info("%d runs in %s", len(table), snakemake.output[0])
