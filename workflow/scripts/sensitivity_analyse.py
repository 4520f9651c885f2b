"""Adapter: Sobol' indices (SALib) of the joined study, the design maps and the summary."""

import json

from bouncedisk.io.atomic import write_text_atomic
from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import open_checked, write_dataset
from bouncedisk.studies.sensitivity import analyse, join_maps, summary
from bouncedisk.studies.sensitivity_settings import StudySettings

with log_to(snakemake.log[0]) as log:
    settings = StudySettings.from_params(snakemake.params.settings)
    points = open_checked(snakemake.input.points, required=("x", "regime"))
    indices = analyse(points, settings.ranges, settings.resamples, settings.seed)
    maps = [open_checked(p, required=("x", "regime")).load() for p in snakemake.input.maps]
    result = summary(indices, maps)
    write_dataset(indices, snakemake.output.indices)
    write_dataset(join_maps(maps), snakemake.output.maps)
    write_text_atomic(snakemake.output.summary, json.dumps(result, indent=2))
    log.info("%s", json.dumps(result, indent=2))
