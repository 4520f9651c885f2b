"""Adapter: generate the synthetic prototype curve from the model plus stated noise."""

import filecmp

from bouncedisk.fitting.synthetic import read_spec, synthetic_from_spec
from bouncedisk.io.job_log import log_to
from bouncedisk.io.runup_curves import write_curve

with log_to(snakemake.log[0]) as log:
    spec = read_spec(snakemake.input.spec)
    df, sidecar = synthetic_from_spec(spec, str(snakemake.input.spec))
    write_curve(df, snakemake.output.csv, sidecar)
    same = filecmp.cmp(snakemake.output.csv, snakemake.params.shipped, shallow=False)
    log.info("%d rows; identical to the shipped %s: %s", len(df), snakemake.params.shipped, same)
    if not same:
        log.warning("the shipped curve differs from the regenerated one")
