"""Adapter: bouncing model against the clipped spring-contact model, for several psi."""

from bouncedisk.analysis import clipped_comparison
from bouncedisk.datasets import write_dataset
from bouncedisk.logutil import log_to
from bouncedisk.scene import load_scene

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
