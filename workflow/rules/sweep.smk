# Stage 2: parameter sweeps, split into independent shard jobs and combined.


rule sweep_shard:
    """One contiguous block of a sweep's first axis: results/sweeps/<sweep>/shard-<i>.nc."""
    input:
        scene=lambda wc: scene_path(config["sweeps"][wc.sweep]["scene"]),
        compiled=rules.compile_engine.output,
    output:
        f"{RES}/sweeps/{{sweep}}/shard-{{shard}}.nc",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/sweep/{{sweep}}-{{shard}}.log",
    benchmark:
        f"{RES}/benchmarks/sweep/{{sweep}}-shard-{{shard}}.tsv"
    params:
        spec=lambda wc: config["sweeps"][wc.sweep],
    priority: 3  # several seconds: before the 1-s jobs, which then fill the cores at the end
    wildcard_constraints:
        shard=r"\d+",
    script:
        "../scripts/sweep_shard.py"


rule sweep_combine:
    """Join a sweep's shards along its swept dimensions: results/sweeps/<sweep>.nc."""
    input:
        compiled=rules.compile_engine.output,
        shards=sweep_shards,
    output:
        f"{RES}/sweeps/{{sweep}}.nc",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/sweep/{{sweep}}-combine.log",
    benchmark:
        f"{RES}/benchmarks/sweep/{{sweep}}-combine.tsv"
    params:
        sweep=lambda wc: wc.sweep,
    script:
        "../scripts/sweep_combine.py"
