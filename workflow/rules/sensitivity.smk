# Stage 6: global sensitivity of the motor's figures of merit (SALib Sobol';
# docs/user_guide/sensitivity.md). The sample is split into shard jobs (contiguous blocks of points) that join
# bit-identically to a one-job run; the design maps are one job per e. SENSITIVITY: the checked
# settings of the size the config asks for (bouncedisk.studies.sensitivity_settings, checked in the Snakefile).
import dataclasses

SENS_PARAMS = dataclasses.asdict(SENSITIVITY)
SENS = f"{RES}/sensitivity"


rule sensitivity_shard:
    """One block of the Sobol' sample's points: results/sensitivity/shard-<i>.nc."""
    input:
        compiled=rules.compile_engine.output,
    priority: 10  # a long job: started early, so that no long job ends the pipeline alone
    output:
        f"{SENS}/shard-{{shard}}.nc",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/sensitivity/shard-{{shard}}.log",
    benchmark:
        f"{RES}/benchmarks/sensitivity/shard-{{shard}}.tsv"
    params:
        settings=SENS_PARAMS,
    wildcard_constraints:
        shard=r"\d+",
    script:
        "../scripts/sensitivity_shard.py"


rule sensitivity_join:
    """The shards in sample order: results/sensitivity/points.nc."""
    input:
        compiled=rules.compile_engine.output,
        shards=expand(f"{SENS}/shard-{{i}}.nc", i=range(SENSITIVITY.shards)),
    priority: 5  # on the chain to the studies' figures, the last batch: run when ready, so that it starts early
    output:
        f"{SENS}/points.nc",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/sensitivity/join.log",
    benchmark:
        f"{RES}/benchmarks/sensitivity/join.tsv"
    script:
        "../scripts/sensitivity_join.py"


rule sensitivity_map:
    """Design map over (psi, log10_r_phi) at the i-th e of design_map.e: results/sensitivity/map-<i>.nc."""
    input:
        compiled=rules.compile_engine.output,
    priority: 5  # on the chain to the studies' figures, the last batch: run when ready, so that it starts early
    output:
        f"{SENS}/map-{{i}}.nc",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/sensitivity/map-{{i}}.log",
    benchmark:
        f"{RES}/benchmarks/sensitivity/map-{{i}}.tsv"
    params:
        settings=SENS_PARAMS,
    wildcard_constraints:
        i=r"\d+",
    script:
        "../scripts/sensitivity_map.py"


rule sensitivity_analyse:
    """Sobol' indices with bootstrap intervals, noise shares, best operating points."""
    input:
        compiled=rules.compile_engine.output,
        points=f"{SENS}/points.nc",
        maps=expand(f"{SENS}/map-{{i}}.nc", i=range(len(SENSITIVITY.map_e))),
    priority: 5  # on the chain to the studies' figures, the last batch: run when ready, so that it starts early
    output:
        indices=f"{SENS}/indices.nc",
        maps=f"{SENS}/maps.nc",
        summary=f"{SENS}/summary.json",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/sensitivity/analyse.log",
    benchmark:
        f"{RES}/benchmarks/sensitivity/analyse.tsv"
    params:
        settings=SENS_PARAMS,
    script:
        "../scripts/sensitivity_analyse.py"


rule sensitivity:
    """The study alone, as a target: its shards, design maps and indices. The resolved study:
    `snakemake --cores 2 --config sensitivity=full results=results-full -- sensitivity`
    (about 1.8 core-hours, docs/user_guide/sensitivity.md)."""
    input:
        rules.sensitivity_analyse.output,
