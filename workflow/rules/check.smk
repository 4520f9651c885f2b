# Stage 6: reproduction checks (the runs themselves are recorded by workflow/rules/tracking.smk).


rule reproduction_checks:
    """Verify the paper's claims from the built results: results/reproduction.md."""
    input:
        compiled=rules.compile_engine.output,
        # every built file the checks read (bouncedisk.studies.reproduction_files.RESULT_FILES)
        read=[f"{RES}/{name}" for name in _checked.RESULT_FILES],
        basins=[f"{RES}/basins/startup.nc"] if "basins" in config else [],
    output:
        report(f"{RES}/reproduction.md", caption="../report/reproduction.rst",
               category="Reproduction"),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/reproduction_checks.log",
    benchmark:
        f"{RES}/benchmarks/reproduction_checks.tsv"
    params:
        # the results folder: each file read is <results>/<kind>/<name>.nc
        results=lambda wildcards, input: str(Path(input.read[0]).parents[1]),
        # the checks fail a run-up-only fit file when the config asked for a joint fit
        joint_fit=bool(config["prototype"].get("load_curve")),
    script:
        "../scripts/reproduction_checks.py"

