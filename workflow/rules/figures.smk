# Stage 5: figures (PDF and PNG), each a pure function of the built files: ONE rule over a {fig}
# wildcard, driven by the figure table workflow/config/figures.yaml (figure_table.smk).


include: "figure_table.smk"


rule figure:
    """One figure of the table workflow/config/figures.yaml: results/figures/{fig}.pdf and .png."""
    input:
        unpack(figure_inputs),
    output:
        **fig_out("{fig}", "figure", lambda wildcards: FIGURE_TABLE[wildcards.fig]["category"]),
    wildcard_constraints:
        fig="|".join(re.escape(name) for name in FIGURES),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/{{fig}}.log",
    benchmark:
        f"{RES}/benchmarks/figures/{{fig}}.tsv"
    params:
        plot=lambda wildcards: FIGURE_TABLE[wildcards.fig]["plot"],
        options=figure_params,
        caption=figure_caption,
    script:
        "../scripts/figure.py"
