# Stage 3: derived datasets (Poincaré maps, model comparison).


rule poincare:
    """Impact map and stroboscopic map of a simulation: results/poincare/<scene>.nc."""
    input:
        compiled=rules.compile_engine.output,
        sim=f"{RES}/simulations/{{scene}}.nc",
    output:
        f"{RES}/poincare/{{scene}}.nc",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/poincare/{{scene}}.log",
    benchmark:
        f"{RES}/benchmarks/poincare/{{scene}}.tsv"
    params:
        transient=1000,
    script:
        "../scripts/poincare.py"


rule clipped_comparison:
    """Rotor speed of the bouncing and the clipped spring-contact models, for several psi."""
    input:
        scene=scene_path(config["clipped_comparison"]["scene"]),
        compiled=rules.compile_engine.output,
    output:
        f"{RES}/studies/clipped_vs_bouncing.nc",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/clipped_comparison.log",
    benchmark:
        f"{RES}/benchmarks/clipped_comparison.tsv"
    params:
        psi=config["clipped_comparison"]["psi"],
        band=BAND_SPEC,
    script:
        "../scripts/clipped_comparison.py"
