"""Adapter: evaluate one shard of the sensitivity study's Sobol' sample."""

from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.studies.sensitivity import MotorModel, run_shard
from bouncedisk.studies.sensitivity_settings import StudySettings

with log_to(snakemake.log[0]) as log:
    settings = StudySettings.from_params(snakemake.params.settings)

    def progress(done, total):
        if done % 20 == 0 or done == total:
            log.info("%d / %d points", done, total)

    ds = run_shard(settings, MotorModel(settings), int(snakemake.wildcards.shard), progress)
    write_dataset(ds, snakemake.output[0])
    log.info(
        "%s: %d points, %.1f s CPU", snakemake.output[0], ds.sizes["point"], ds.attrs["cpu_time_s"]
    )
