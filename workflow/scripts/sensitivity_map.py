"""Adapter: one design map of the sensitivity study (a grid over psi and log10_r_phi)."""

from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.studies.sensitivity import MotorModel, design_map, map_settings
from bouncedisk.studies.sensitivity_settings import StudySettings

with log_to(snakemake.log[0]) as log:
    settings = map_settings(StudySettings.from_params(snakemake.params.settings))
    ds = design_map(settings, MotorModel(settings), int(snakemake.wildcards.i))
    write_dataset(ds, snakemake.output[0])
    log.info(
        "%s: %d points, %.1f s CPU", snakemake.output[0], ds.sizes["point"], ds.attrs["cpu_time_s"]
    )
