# Stage 2b: ensemble statistics, bands behind single trajectories, continuation, and what
# statistics cost (docs/model.md "Long-run statistics of chaotic motion").


rule ensemble_stats:
    """Ensemble statistics of a scene (`bouncedisk stats`): results/stats/<scene>.nc."""
    input:
        scene=scene_path("{scene}"),
        compiled=rules.compile_engine.output,
    output:
        f"{RES}/stats/{{scene}}.nc",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/stats/{{scene}}.log",
    benchmark:
        f"{RES}/benchmarks/stats/{{scene}}.tsv"
    threads: 1
    script:
        "../scripts/ensemble_stats.py"


rule omega_band:
    """Ensemble band of the rotor speed behind a single trajectory: results/bands/<scene>.nc."""
    input:
        scene=scene_path("{scene}"),
        compiled=rules.compile_engine.output,
    output:
        f"{RES}/bands/{{scene}}.nc",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/bands/{{scene}}.log",
    benchmark:
        f"{RES}/benchmarks/bands/{{scene}}.tsv"
    params:
        spec=BAND_SPEC,
    threads: 1
    script:
        "../scripts/omega_band.py"


rule continuation:
    """Bifurcation diagram by continuation, one direction: results/continuation/<dir>.nc."""
    input:
        scene=scene_path(config["continuation"]["scene"]),
        compiled=rules.compile_engine.output,
    output:
        f"{RES}/continuation/{{direction}}.nc",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/continuation/{{direction}}.log",
    benchmark:
        f"{RES}/benchmarks/continuation/{{direction}}.tsv"
    params:
        spec=config["continuation"],
    priority: 3  # several seconds: before the 1-s jobs, which then fill the cores at the end
    wildcard_constraints:
        direction="up|down",
    script:
        "../scripts/continuation.py"


rule stats_cost:
    """CI half-width of the mean rotor speed against CPU time: results/tables/stats_cost.csv."""
    input:
        scene=scene_path(config["stats_cost"]["scene"]),
        compiled=rules.compile_engine.output,
    output:
        table=report(f"{RES}/tables/stats_cost.csv", caption="../report/stats_cost_table.rst",
                     category="Studies beyond the paper"),
        singles=f"{RES}/tables/stats_cost_single_runs.csv",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/stats_cost.log",
    benchmark:
        f"{RES}/benchmarks/stats_cost.tsv"
    params:
        spec=config["stats_cost"],
    script:
        "../scripts/stats_cost.py"
