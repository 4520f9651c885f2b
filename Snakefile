# bouncedisk pipeline: every figure of the paper, and the studies around it, from raw outputs.
# Run from the project root:  snakemake --cores 2     (see README.md, "Rebuilding the figures")
from pathlib import Path

from snakemake.utils import min_version, validate

from bouncedisk.io.job_log import exit_with_error
from bouncedisk.io.schema_check import numbers_from_text, schema_error
from bouncedisk.model.errors import InputError
from bouncedisk.studies.sensitivity_settings import study_settings

min_version("8.0")


configfile: "workflow/config/config.yaml"


# beside this file, whatever the working directory (snakemake -d)
CONFIG_SCHEMA = str(Path(workflow.basedir) / "workflow" / "schemas" / "config.schema.yaml")

# the sensitivity study's ranges and sizes, then the schema: one line naming the field, exit 2
numbers_from_text(config, CONFIG_SCHEMA)  # 1e-9 and --config's nested values: numbers
try:
    SENSITIVITY = study_settings(config)
except InputError as _ex:
    exit_with_error(_ex.line())
if (_line := schema_error(config, CONFIG_SCHEMA)) is not None:
    exit_with_error(f"pipeline config: {_line}")
validate(config, CONFIG_SCHEMA)  # Snakemake's own check, which fills in any `default:` of the schema


include: "workflow/rules/common.smk"
include: "workflow/rules/simulate.smk"
include: "workflow/rules/sweep.smk"
include: "workflow/rules/ensemble.smk"
include: "workflow/rules/load.smk"
include: "workflow/rules/basins.smk"
include: "workflow/rules/analyse.smk"
include: "workflow/rules/fit.smk"
include: "workflow/rules/accuracy.smk"
include: "workflow/rules/sensitivity.smk"
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
