# Stage 5: figures (PDF and PNG), each a pure function of the built files, drawn in batches: the
# figure table workflow/config/figures.yaml (figure_table.smk) puts each figure in a batch, and
# one rule per batch, figure_<batch>, draws all of the batch's figures in one job (one Python
# start and one import of matplotlib and xarray for the batch, not one per figure).
# `snakemake results/figures/<name>.pdf` runs the job of the figure's batch.


include: "figure_table.smk"


for _batch in FIGURE_BATCHES:

    rule:
        """The figures of one batch of the table workflow/config/figures.yaml:
        results/figures/<name>.pdf and .png of each."""
        name:
            f"figure_{_batch}"
        input:
            **figure_batch_inputs(_batch),
        output:
            **figure_batch_outputs(_batch),
        conda:
            "../envs/bouncedisk.yaml"
        log:
            f"{RES}/logs/figures/{_batch}.log",
        benchmark:
            f"{RES}/benchmarks/figures/{_batch}.tsv"
        params:
            batch=_batch,
            figures=figure_batch_params(_batch),
        script:
            "../scripts/figure.py"
