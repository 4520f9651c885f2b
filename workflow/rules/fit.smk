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


# the prototype's load curve (optional): fitted jointly with the run-up when the config names it
LOAD_CURVE = config["prototype"].get("load_curve")
LOAD_INPUTS = [LOAD_CURVE, str(Path(LOAD_CURVE).with_suffix(".yaml"))] if LOAD_CURVE else []
# threads of the fit (its result does not depend on them): at least this many, more if a profile
# sets more (--set-threads fit_prototype=N)
FIT_THREADS = 2


rule fit_prototype:
    """Fit the model to the prototype's run-up (and load curve, jointly): results/fit/prototype.nc."""
    input:
        curve=config["prototype"]["curve"],
        load=LOAD_INPUTS,
        compiled=rules.compile_engine.output,
    output:
        f"{RES}/fit/prototype.nc",
    # The fit runs FIT_THREADS threads, but they wait on each other (the search's serial steps)
    # and keep 1.7 cores busy on average: it holds one of the scheduler's slots, so that the job
    # in the other slot fills those gaps instead of a core standing idle for most of a minute
    # (docs/user_guide/performance.md). The Slurm profile gives it FIT_THREADS CPUs (set-threads).
    threads: 1
    # the pipeline's longest job and the head of its longest chain (the fit's figures, the
    # prototype's load curve, the checks): started as soon as the engine is compiled
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
