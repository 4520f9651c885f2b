"""Adapter: the scaling measurements (benchmarks/bench_accuracy.py runs the full sizes)."""

from bouncedisk.atomic import atomic_path
from bouncedisk.logutil import log_to
from bouncedisk.studies import scaling

with log_to(snakemake.log[0]) as log:
    if snakemake.params.quick:
        table = scaling(
            omegas=(1.5, 10.0, 100.0),
            per_omega=50_000,
            sizes=(1_000, 10_000, 100_000),
            memory_sizes=(1_000, 100_000),
            effect_events=50_000,
            progress=log.info,
        )
    else:
        table = scaling(progress=log.info)
    with atomic_path(snakemake.output[0], suffix=".csv") as tmp:
        table.to_csv(tmp, index=False)
