"""Adapter: run the reproduction checks on the built results and write the Markdown report."""

from pathlib import Path

from bouncedisk.io.atomic import write_text_atomic
from bouncedisk.io.job_log import log_to
from bouncedisk.studies import reproduction as checks

with log_to(snakemake.log[0]) as log:
    results = checks.run_checks(Path(snakemake.params.results), snakemake.params.joint_fit)
    write_text_atomic(snakemake.output[0], checks.to_markdown(results))
    log.info("\n%s", checks.to_text(results))
    # a failed claim is reported in the file, not hidden by a failed job: `bouncedisk check`
    # exits non-zero, and CI runs it
