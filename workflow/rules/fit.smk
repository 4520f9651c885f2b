# Stage 4: the prototype motor curve (synthetic stand-in) and the fit of the model to it.


rule synthetic_curve:
    """Regenerate the shipped synthetic curve (and log whether it is byte-identical)."""
    input:
        spec="workflow/config/synthetic_motor.yaml",
        compiled=rules.compile_engine.output,
    output:
        csv=f"{RES}/prototype/synthetic_motor.csv",
        yaml=f"{RES}/prototype/synthetic_motor.yaml",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/synthetic_curve.log",
    benchmark:
        f"{RES}/benchmarks/synthetic_curve.tsv"
    params:
        shipped=config["prototype"]["curve"],
    script:
        "../scripts/make_synthetic_curve.py"


# threads of the fit (its result does not depend on them): at least this many, more if a profile
# sets more (--set-threads fit_prototype=N, as the Slurm profile does). One by default: a second
# thread shortens the fit's own wall time by a fifth but costs a quarter more CPU (its threads
# wait on each other), which the other jobs want on two cores; with four or more, the fit, at the
# head of the longest chain, gains from two (docs/user_guide/performance.md)
FIT_THREADS = 1


rule fit_prototype:
    """Fit the model to the prototype's run-up (and load curve, jointly): results/fit/prototype.nc."""
    input:
        curve=config["prototype"]["curve"],
        load=LOAD_INPUTS,
        code=CODE,  # instead of compile_engine's flag: an edited package reruns the fit
    output:
        f"{RES}/fit/prototype.nc",
    threads: FIT_THREADS
    # the pipeline's longest job and the head of its longest chain (the fit's figures, the
    # prototype's load curve, the checks): started first, beside compile_engine, not after it. It
    # compiles the engine kernel itself on the core that would otherwise wait for compile_engine.
    # numba writes each cache file whole and then renames it; both jobs compile the same
    # functions, so whichever index is written last names files that exist.
    priority: 100
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/fit_prototype.log",
    benchmark:
        f"{RES}/benchmarks/fit_prototype.tsv"
    params:
        seed=config["prototype"]["seed"],
        bootstrap=config["prototype"]["bootstrap"],
        e_sigma=config["prototype"].get("e_sigma"),  # None: the fit's default
        search={k: config["prototype"][k] for k in ("scan", "zoom") if k in config["prototype"]},
        threads=FIT_THREADS,
    script:
        "../scripts/fit_prototype.py"
