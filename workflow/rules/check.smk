# Stage 6: reproduction checks (the runs themselves are recorded by workflow/rules/tracking.smk).


rule reproduction_checks:
    """Verify the paper's claims from the built results: results/reproduction.md."""
    input:
        compiled=rules.compile_engine.output,
        sims=[f"{RES}/simulations/fig5.nc"],
        stats=expand(f"{RES}/stats/{{s}}.nc", s=CHECKED_STATS),
        band=f"{RES}/bands/fig5.nc",
        load=expand(f"{RES}/load/{{c}}.nc", c=CHECKED_LOAD_CURVES),
        fit=f"{RES}/fit/prototype.nc",
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
        results=lambda wildcards, input: str(Path(input.sims[0]).parents[1]),
    script:
        "../scripts/reproduction_checks.py"

