"""Where a pipeline run's CPU goes: Snakemake's own process, and the jobs it ran.

Run:  python benchmarks/pipeline_cpu.py [SNAKEMAKE ARGUMENTS]   (default: --cores 2 --quiet rules)

from the root of a clean clone (``PYTHONPATH=src`` when the package is installed from another
tree). Runs Snakemake's command line in this process and prints, when it exits, the wall time,
the CPU time of this process (Snakemake itself: the DAG, the scheduling, the sampling of the
jobs' benchmark files, the tracking) and the CPU time of every process it started and waited
for (the jobs, the shells that start them, their children, the tracking's ``git`` calls), from
``getrusage``. The jobs' own benchmark files (``pipeline_jobs.py``) sample each job at intervals
and miss what a job spends after its last sample: their sum is below the jobs' CPU here, most of
all for short jobs.
"""

from __future__ import annotations

import atexit
import resource
import sys
import time

DEFAULT = ["--cores", "2", "--quiet", "rules"]


def cpu(who: int) -> float:
    """User + system CPU seconds of ``who`` (``resource.RUSAGE_SELF`` or ``RUSAGE_CHILDREN``)."""
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def main() -> None:
    """Run Snakemake with this process's arguments; report its CPU and its jobs' at exit."""
    start = time.perf_counter()

    def report() -> None:
        print(
            f"pipeline_cpu: wall {time.perf_counter() - start:.1f} s; CPU of Snakemake itself "
            f"{cpu(resource.RUSAGE_SELF):.1f} s, of the processes it started (its jobs) "
            f"{cpu(resource.RUSAGE_CHILDREN):.1f} s",
            file=sys.stderr,
            flush=True,
        )

    atexit.register(report)
    from snakemake.cli import main as snakemake_main

    sys.argv = ["snakemake", *(sys.argv[1:] or DEFAULT)]
    snakemake_main()


if __name__ == "__main__":
    main()
