# Stage 5: what accuracy costs in time (work-precision) and how cost scales.


rule work_precision:
    """Error against CPU time for every solver and tolerance: results/tables/work_precision.csv."""
    input:
        compiled=rules.compile_engine.output,
    priority: 10  # a long job: started early, so that no long job ends the pipeline alone
    output:
        table=report(f"{RES}/tables/work_precision.csv", caption="../report/work_precision_table.rst",
                     category="Accuracy and cost"),
        summary=f"{RES}/tables/work_precision_summary.json",
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/work_precision.log",
    benchmark:
        f"{RES}/benchmarks/work_precision.tsv"
    script:
        "../scripts/work_precision.py"


rule scaling:
    """Cost per impact against omega_s, time and memory against impacts, cost of each effect."""
    input:
        compiled=rules.compile_engine.output,
    priority: 10  # a long job: started early, so that no long job ends the pipeline alone
    output:
        report(f"{RES}/tables/scaling.csv", caption="../report/scaling_table.rst",
               category="Accuracy and cost"),
    conda:
        "../envs/bouncedisk.yaml"
    log:
        f"{RES}/logs/scaling.log",
    benchmark:
        f"{RES}/benchmarks/scaling.tsv"
    params:
        sizes=config["accuracy"]["scaling"],
    script:
        "../scripts/scaling.py"
