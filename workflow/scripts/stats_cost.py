"""Adapter: the cost of ensemble statistics, beside the scatter of single runs."""

from bouncedisk.io.atomic import write_text_atomic
from bouncedisk.io.job_log import log_to
from bouncedisk.model.scene import load_scene
from bouncedisk.studies.statistics_cost import half_width_table, single_run_table

with log_to(snakemake.log[0]) as log:
    spec = snakemake.params.spec
    scene = load_scene(snakemake.input.scene)
    table = half_width_table(scene, spec["members"], spec["durations"])
    singles = single_run_table(scene, spec["single_runs"], max(spec["durations"]))
    write_text_atomic(snakemake.output.table, table.to_csv(index=False))
    write_text_atomic(snakemake.output.singles, singles.to_csv(index=False))
    log.info("\n%s\n%s", table.to_string(), singles.to_string())
