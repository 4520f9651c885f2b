"""Adapter: generate the synthetic prototype load curve from the model (docs/formats.md format)."""

import filecmp

import yaml

from bouncedisk.fitting.synthetic import synthetic_load_curve
from bouncedisk.io.job_log import log_to
from bouncedisk.io.runup_curves import write_curve

with log_to(snakemake.log[0]) as log:
    spec = yaml.safe_load(open(snakemake.input.spec))
    df, sidecar = synthetic_load_curve(spec, str(snakemake.input.spec))
    write_curve(df, snakemake.output.csv, sidecar)
    same = filecmp.cmp(snakemake.output.csv, snakemake.params.shipped, shallow=False)
    log.info("%d loads; identical to the shipped %s: %s", len(df), snakemake.params.shipped, same)
    if not same:
        log.warning("the shipped load curve differs from the regenerated one")
