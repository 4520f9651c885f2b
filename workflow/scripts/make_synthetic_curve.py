"""Adapter: generate the synthetic prototype curve from the model plus stated noise."""

import filecmp

from bouncedisk.curves import write_curve
from bouncedisk.fitting.synthetic import read_spec, synthetic_from_spec
from bouncedisk.logutil import log_to

with log_to(snakemake.log[0]) as log:
    spec = read_spec(snakemake.input.spec)
    df, sidecar = synthetic_from_spec(spec, str(snakemake.input.spec))
    write_curve(df, snakemake.output.csv, sidecar)
    same = filecmp.cmp(snakemake.output.csv, snakemake.params.shipped, shallow=False)
    log.info("%d rows; identical to the shipped %s: %s", len(df), snakemake.params.shipped, same)
    if not same:
        log.warning("the shipped curve differs from the regenerated one")
