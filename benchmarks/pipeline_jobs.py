"""Where a pipeline run's seconds and memory went: every job's wall time, CPU time and peak RSS.

Run:  python benchmarks/pipeline_jobs.py [RESULTS] [--order start|rss|wall] [--markdown]

Reads the benchmark files Snakemake writes for every job (``RESULTS/benchmarks/**/*.tsv``:
wall seconds, peak RSS with the job's children, CPU seconds) and their modification times (a
job's end), so that it can also show when each job ran: the start is the end less the wall
time. Prints one row per job and the totals: the span from the first job's start to the last
job's end, the sum of the jobs' CPU and wall times, the largest peak and whether every job
stayed under 1 GB (the pipeline's memory budget). Reads what the last run of each job wrote:
run it after a complete ``snakemake --cores 2`` in a clean clone.
"""

from __future__ import annotations

import argparse
import csv
from dataclasses import dataclass
from pathlib import Path

#: Every pipeline job's peak memory stays below this (MB).
BUDGET_MB = 1000.0


@dataclass(frozen=True)
class Job:
    name: str
    start: float
    wall: float
    cpu: float
    rss_mb: float


def read_jobs(results: Path) -> list[Job]:
    """The jobs of ``results/benchmarks``, from Snakemake's ``benchmark:`` files."""
    jobs = []
    root = results / "benchmarks"
    for path in sorted(root.rglob("*.tsv")):
        with path.open() as stream:
            rows = list(csv.DictReader(stream, delimiter="\t"))
        if not rows:
            continue
        last = rows[-1]
        wall = float(last["s"])
        end = path.stat().st_mtime
        jobs.append(
            Job(
                name=str(path.relative_to(root).with_suffix("")),
                start=end - wall,
                wall=wall,
                cpu=float(last.get("cpu_time") or "nan"),
                rss_mb=float(last.get("max_rss") or "nan"),
            )
        )
    if not jobs:
        raise SystemExit(f"no benchmark files under {root}: run the pipeline first")
    return jobs


def report(jobs: list[Job], order: str, markdown: bool) -> str:
    """The table (one row per job) and the totals, as text or a Markdown table."""
    t0 = min(j.start for j in jobs)
    key = {"start": lambda j: j.start, "rss": lambda j: -j.rss_mb, "wall": lambda j: -j.wall}
    rows = sorted(jobs, key=key[order])
    lines = []
    if markdown:
        lines += ["| job (`results/benchmarks/…`) | start | wall time | CPU time | peak RSS |",
                  "| --- | ---: | ---: | ---: | ---: |"]  # fmt: skip
        lines += [f"| `{j.name}` | {j.start - t0:.0f} s | {j.wall:.1f} s | {j.cpu:.1f} s | "
                  f"{j.rss_mb:.0f} MB |" for j in rows]  # fmt: skip
    else:
        lines += [f"{'start':>6} {'wall':>6} {'cpu':>6} {'rss MB':>7}  job"]
        lines += [f"{j.start - t0:6.1f} {j.wall:6.1f} {j.cpu:6.1f} {j.rss_mb:7.0f}  {j.name}"
                  for j in rows]  # fmt: skip
    span = max(j.start + j.wall for j in jobs) - t0
    peak = max(jobs, key=lambda j: j.rss_mb)
    lines += [
        "",
        f"{len(jobs)} jobs; first start to last end {span:.1f} s; CPU {sum(j.cpu for j in jobs):.1f} s, "
        f"wall {sum(j.wall for j in jobs):.1f} s summed over the jobs",
        f"largest peak RSS {peak.rss_mb:.0f} MB ({peak.name}); every job under "
        f"{BUDGET_MB:.0f} MB: {'yes' if peak.rss_mb < BUDGET_MB else 'NO'}",
    ]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", nargs="?", default="results", type=Path)
    ap.add_argument("--order", choices=("start", "rss", "wall"), default="start")
    ap.add_argument("--markdown", action="store_true", help="a Markdown table (for the docs)")
    ap.add_argument(
        "--record",
        action="store_true",
        help="write the totals to benchmarks/out/pipeline_jobs.json",
    )
    args = ap.parse_args()
    jobs = read_jobs(args.results)
    print(report(jobs, args.order, args.markdown))
    if args.record:
        print(write_totals(jobs))


def write_totals(jobs: list[Job]):
    """The run's totals and its five longest jobs as the performance page's record."""
    from record import write_record

    t0 = min(j.start for j in jobs)
    peak = max(jobs, key=lambda j: j.rss_mb)
    rows = [
        (
            f"{len(jobs)} jobs, first start to last end",
            f"{max(j.start + j.wall for j in jobs) - t0:.1f} s",
        ),
        ("CPU time summed over the jobs", f"{sum(j.cpu for j in jobs):.1f} s"),
        (f"largest peak RSS ({peak.name})", f"{peak.rss_mb:.0f} MB"),
    ]
    for j in sorted(jobs, key=lambda j: -j.wall)[:5]:
        rows.append((f"job {j.name}: wall, CPU", f"{j.wall:.1f} s, {j.cpu:.1f} s"))
    return write_record("pipeline_jobs", "Pipeline jobs (from the Snakemake benchmark files)", rows)


if __name__ == "__main__":
    main()
