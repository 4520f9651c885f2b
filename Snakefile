# bouncedisk pipeline: every figure of the paper, and the studies around it, from raw outputs.
# Run from the project root:  snakemake --cores 2     (see README.md, "Rebuilding the figures")
from pathlib import Path

from snakemake.utils import min_version, validate

min_version("8.0")


configfile: "workflow/config/config.yaml"


validate(config, "workflow/schemas/config.schema.yaml")


include: "workflow/rules/common.smk"
include: "workflow/rules/simulate.smk"
include: "workflow/rules/sweep.smk"
include: "workflow/rules/ensemble.smk"
include: "workflow/rules/load.smk"
include: "workflow/rules/analyse.smk"
include: "workflow/rules/fit.smk"
include: "workflow/rules/accuracy.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/check.smk"
include: "workflow/rules/tracking.smk"


rule all:
    input:
        all_targets(),
    default_target: True


onstart:
    tracking_start()


onsuccess:
    tracking_finish()


onerror:
    tracking_fail()
