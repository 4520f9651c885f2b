"""Adapter: start-up under load, the fraction of starts from rest reaching the fast branch."""

from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.scene import load_scene
from bouncedisk.studies.basins import parse_values, start_grid, startup
from bouncedisk.studies.torque_speed import parse_loads

with log_to(snakemake.log[0]) as log:
    spec = snakemake.params.spec
    scene = load_scene(snakemake.input.scene)
    grid = start_grid(
        spec["phases"],
        [0.0],
        parse_values(
            spec["heights"], "basins.startup.heights", "height", "workflow/config/config.yaml"
        ),
    )
    loads = parse_loads(spec["loads"], "workflow/config/config.yaml", "basins.startup.loads")
    ds = startup(scene, loads, grid, spec["fast_above"], cores=snakemake.threads)
    write_dataset(ds, snakemake.output[0])
    log.info("%s: fast fractions %s", snakemake.output[0], ds["fast_fraction"].values.round(3))
