"""Adapter: ensemble band of the rotor speed of one scene."""

from bouncedisk.analysis.bands import omega_band
from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.scene import load_scene

with log_to(snakemake.log[0]) as log:
    spec = snakemake.params.spec
    scene = load_scene(snakemake.input.scene)
    ds = omega_band(
        scene, spec["members"], seed=spec["seed"], e_sigma=spec["e_sigma"], cores=snakemake.threads
    )
    write_dataset(ds, snakemake.output[0])
    log.info(
        "%s: %s members, %s samples", snakemake.output[0], ds.sizes["member"], ds.sizes["time"]
    )
