# Stage 5: figures (PDF and PNG), each a pure function of the built netCDF files.

rule fig2_schematic:
    input:
        code=CODE,
    output:
        **fig_out("fig2_schematic", "fig2", FIGCAT),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/fig2_schematic.log",
    benchmark:
        f"{RES}/benchmarks/figures/fig2_schematic.tsv"
    params:
        figure="fig2",
    script:
        "../scripts/figure.py"


rule fig3_trajectory:
    input:
        code=CODE,
        sim=f"{RES}/simulations/fig3.nc",
        band=f"{RES}/bands/fig3.nc",
    output:
        **fig_out("fig3_trajectory_e03", "fig3", FIGCAT),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/fig3_trajectory_e03.log",
    benchmark:
        f"{RES}/benchmarks/figures/fig3_trajectory_e03.tsv"
    params:
        figure="trajectory",
    script:
        "../scripts/figure.py"


rule fig4_trajectory:
    input:
        code=CODE,
        sim=f"{RES}/simulations/fig4.nc",
        band=f"{RES}/bands/fig4.nc",
    output:
        **fig_out("fig4_trajectory_e06", "fig4", FIGCAT),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/fig4_trajectory_e06.log",
    benchmark:
        f"{RES}/benchmarks/figures/fig4_trajectory_e06.tsv"
    params:
        figure="trajectory",
    script:
        "../scripts/figure.py"


rule poincare_maps:
    input:
        code=CODE,
        maps=expand(f"{RES}/poincare/{{s}}.nc", s=list(config["poincare"])),
    output:
        **fig_out("poincare_maps", "poincare", STUDY),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/poincare_maps.log",
    benchmark:
        f"{RES}/benchmarks/figures/poincare_maps.tsv"
    params:
        figure="poincare",
        labels=list(config["poincare"].values()),
    script:
        "../scripts/figure.py"


rule bifurcation_figure:
    input:
        code=CODE,
        up=f"{RES}/continuation/up.nc",
        down=f"{RES}/continuation/down.nc",
    output:
        **fig_out("bifurcation_e", "bifurcation", STUDY),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/bifurcation_e.log",
    benchmark:
        f"{RES}/benchmarks/figures/bifurcation_e.tsv"
    params:
        figure="bifurcation",
    script:
        "../scripts/figure.py"


rule regime_map_figure:
    input:
        code=CODE,
        sweep=f"{RES}/sweeps/regime_map.nc",
    output:
        **fig_out("regime_map", "regime_map", STUDY),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/regime_map.log",
    benchmark:
        f"{RES}/benchmarks/figures/regime_map.tsv"
    params:
        figure="regime_map",
    script:
        "../scripts/figure.py"


rule speed_vs_psi_figure:
    input:
        code=CODE,
        sweep=f"{RES}/sweeps/psi_speed.nc",
    output:
        **fig_out("speed_vs_psi", "speed_vs_psi", STUDY),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/speed_vs_psi.log",
    benchmark:
        f"{RES}/benchmarks/figures/speed_vs_psi.tsv"
    params:
        figure="speed_vs_psi",
    script:
        "../scripts/figure.py"


rule clipped_figure:
    input:
        code=CODE,
        study=f"{RES}/studies/clipped_vs_bouncing.nc",
    output:
        **fig_out("clipped_vs_bouncing", "clipped", STUDY),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/clipped_vs_bouncing.log",
    benchmark:
        f"{RES}/benchmarks/figures/clipped_vs_bouncing.tsv"
    params:
        figure="clipped",
    script:
        "../scripts/figure.py"


rule fig5_prototype:
    input:
        code=CODE,
        curve=config["prototype"]["curve"],
        fit=f"{RES}/fit/prototype.nc",
    output:
        **fig_out("fig5_prototype_fit", "fig5", FIGCAT),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/fig5_prototype_fit.log",
    benchmark:
        f"{RES}/benchmarks/figures/fig5_prototype_fit.tsv"
    params:
        figure="fig5",
    script:
        "../scripts/figure.py"


rule fit_profiles_figure:
    input:
        code=CODE,
        fit=f"{RES}/fit/prototype.nc",
    output:
        **fig_out("fit_profiles", "fit_profiles", STUDY),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/fit_profiles.log",
    benchmark:
        f"{RES}/benchmarks/figures/fit_profiles.tsv"
    params:
        figure="fit_profiles",
    script:
        "../scripts/figure.py"


rule work_precision_figure:
    input:
        code=CODE,
        table=f"{RES}/tables/work_precision.csv",
    output:
        **fig_out("work_precision", "work_precision", "Accuracy and cost"),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/work_precision.log",
    benchmark:
        f"{RES}/benchmarks/figures/work_precision.tsv"
    params:
        figure="work_precision",
    script:
        "../scripts/figure.py"


rule scaling_figure:
    input:
        code=CODE,
        table=f"{RES}/tables/scaling.csv",
    output:
        **fig_out("scaling", "scaling", "Accuracy and cost"),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/scaling.log",
    benchmark:
        f"{RES}/benchmarks/figures/scaling.tsv"
    params:
        figure="scaling",
    script:
        "../scripts/figure.py"


rule stats_cost_figure:
    input:
        code=CODE,
        table=f"{RES}/tables/stats_cost.csv",
        singles=f"{RES}/tables/stats_cost_single_runs.csv",
    output:
        **fig_out("stats_cost", "stats_cost", "Accuracy and cost"),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/figures/stats_cost.log",
    benchmark:
        f"{RES}/benchmarks/figures/stats_cost.tsv"
    params:
        figure="stats_cost",
    script:
        "../scripts/figure.py"
