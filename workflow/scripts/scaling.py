"""Adapter: the scaling measurements at the config's sizes (`accuracy.scaling`)."""

from bouncedisk.io.atomic import atomic_path
from bouncedisk.io.job_log import log_to
from bouncedisk.studies.scaling import scaling

with log_to(snakemake.log[0]) as log:
    table = scaling(**snakemake.params.sizes, progress=log.info)
    with atomic_path(snakemake.output[0], suffix=".csv") as tmp:
        table.to_csv(tmp, index=False)
