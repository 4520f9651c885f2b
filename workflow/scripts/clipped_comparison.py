"""Adapter: bouncing model against the clipped spring-contact model, for several psi."""

from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.scene import load_scene
from bouncedisk.studies.clipped import clipped_comparison

with log_to(snakemake.log[0]) as log:
    scene = load_scene(snakemake.input.scene)
    band = snakemake.params.band
    ds = clipped_comparison(
        scene,
        [float(p) for p in snakemake.params.psi],
        members=band["members"],
        seed=band["seed"],
        e_sigma=band["e_sigma"],
    )
    write_dataset(ds, snakemake.output[0])
    log.info("%s written", snakemake.output[0])
