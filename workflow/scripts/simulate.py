"""Adapter: run one scene and write its netCDF file."""

from bouncedisk.io.job_log import log_to
from bouncedisk.model.scene import load_scene
from bouncedisk.run.runner import run_scene

with log_to(snakemake.log[0]) as log:
    scene = load_scene(snakemake.input.scene, list(snakemake.params.overrides))
    summary = run_scene(
        scene,
        snakemake.output[0],
        progress=True,
        command=f"snakemake rule simulate ({snakemake.input.scene})",
    )
    log.info(
        "%s: %d impacts, %d chattering tails, status %s, %.3f s, run %s",
        summary.path,
        summary.n_impacts,
        summary.n_chatter,
        summary.status,
        summary.wall_time_s,
        summary.run_id,
    )
