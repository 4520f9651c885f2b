# Stage 1: single simulations, one netCDF file per scene.


rule compile_engine:
    """Compile the engine and the compiled functions several jobs call once (numba's cache), so
    that parallel jobs do not all compile them."""
    input:
        code=CODE,
    output:
        touch(f"{RES}/logs/engine_compiled.flag"),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/compile_engine.log",
    benchmark:
        f"{RES}/benchmarks/compile_engine.tsv"
    params:
        events=10,
    script:
        "../scripts/compile_engine.py"


rule simulate:
    """Run one scene: results/simulations/<scene>.nc (docs/formats.md names and provenance)."""
    input:
        scene=scene_path("{scene}"),
        compiled=rules.compile_engine.output,
    output:
        f"{RES}/simulations/{{scene}}.nc",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/simulate/{{scene}}.log",
    benchmark:
        f"{RES}/benchmarks/simulate/{{scene}}.tsv"
    params:
        overrides=[],
    script:
        "../scripts/simulate.py"
