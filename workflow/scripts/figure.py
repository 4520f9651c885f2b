"""Adapter: draw one figure of the figure table (workflow/config/figures.yaml), PDF and PNG."""

from bouncedisk.figures import common, drawing
from bouncedisk.io.job_log import log_to

with log_to(snakemake.log[0]) as log:
    paths = {name: path for name, path in snakemake.input.items() if name != "code"}
    fig = drawing.draw_figure(snakemake.params.plot, paths, snakemake.params.options)
    common.save_figure(fig, snakemake.output.pdf, snakemake.output.png)
    log.info("wrote %s and %s", snakemake.output.pdf, snakemake.output.png)
