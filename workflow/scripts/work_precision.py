"""Adapter: the work-precision study (table and a JSON summary of the targets)."""

import json

from bouncedisk.io.atomic import atomic_path, write_text_atomic
from bouncedisk.io.job_log import log_to
from bouncedisk.studies.work_precision import work_precision, work_precision_summary

with log_to(snakemake.log[0]) as log:
    table = work_precision(progress=log.info)
    with atomic_path(snakemake.output.table, suffix=".csv") as tmp:
        table.to_csv(tmp, index=False)
    summary = work_precision_summary(table)
    write_text_atomic(snakemake.output.summary, json.dumps(summary, indent=2) + "\n")
    log.info("summary: %s", summary)
