"""The resolved parameter study: its index table and what it cost, from a finished run's folder.

Run the study first (docs/user_guide/sensitivity.md), then read it:

    snakemake --cores 2 --config sensitivity=full results=results-full -- sensitivity
    python benchmarks/sensitivity_full.py results-full [--record]

Prints the Markdown table of every Sobol' index with its 95 % half-width (the sensitivity guide's
table of the resolved study), the largest half-width, and the cost: the CPU seconds summed over
the study's jobs (Snakemake's benchmark files), in core-hours, the largest job's memory and the
wall time on two dedicated cores that this CPU makes (CPU / 2: the shard jobs are independent and
equal in size). ``--record`` writes its record, ``sensitivity_full.json``, in ``benchmarks/out/``
(the performance page).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path

from bouncedisk.studies.sensitivity_settings import PARAMETERS

#: The half-width every index of the resolved study is to reach (the sensitivity guide).
TARGET = 0.03
LABELS = {
    "e": "$e$",
    "omega_s": r"$\omega_s$",
    "log10_r_phi": r"$\log_{10} R_\varphi$",
    "psi": r"$\psi$",
}


def number(x) -> float:
    """A summary's number (JSON ``null`` for an undefined one) as a float, NaN for null."""
    return math.nan if x is None else float(x)


def half_width(entry: dict) -> float:
    """Half the width of an index's 95 % interval (NaN when undefined)."""
    lo, hi = (number(v) for v in entry["ci95"])
    return (hi - lo) / 2.0


def table(summary: dict) -> list[str]:
    """Markdown rows: one per output, ``S_1 / S_T`` with their half-widths per parameter."""
    head = "| output (noise share) | " + " | ".join(
        f"{LABELS[p]}: $S_1$ / $S_T$" for p in PARAMETERS
    )
    rows = [head + " |", "| --- |" + " --- |" * len(PARAMETERS)]
    for name, out in summary["outputs"].items():
        cells = [
            " / ".join(
                f"{round(number(out[k][p]['index']), 2) + 0.0:.2f} ± {half_width(out[k][p]):.2f}"
                for k in ("S1", "ST")
            )
            for p in PARAMETERS
        ]
        rows.append(
            f"| `{name}` ({100 * number(out['noise_share']):.1f} %) | " + " | ".join(cells) + " |"
        )
    return rows


def job_costs(results: Path) -> dict:
    """CPU seconds and peak memory of the study's jobs (its Snakemake benchmark files)."""
    cpu, rss, shards = 0.0, 0.0, 0
    for tsv in sorted((results / "benchmarks" / "sensitivity").glob("*.tsv")):  # this study's jobs
        with tsv.open(encoding="utf-8") as f:
            row = next(csv.DictReader(f, delimiter="\t"))
        cpu += float(row["cpu_time"])
        rss = max(rss, float(row["max_rss"]))
        shards += tsv.stem.startswith("shard-")
    return {"cpu_s": cpu, "max_rss_mb": rss, "shards": shards}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path, help="the study's results folder (results=...)")
    ap.add_argument("--record", action="store_true", help="write the performance page's record")
    args = ap.parse_args()
    summary_path = args.results / "sensitivity" / "summary.json"
    if not summary_path.is_file():
        ap.error(f"{summary_path}: no summary; run the study first (see this script's docstring)")
    summary = json.loads(summary_path.read_text(encoding="utf-8"))
    named = {
        f"{k}({p}) of {name}": half_width(out[k][p])
        for name, out in summary["outputs"].items()
        for k in ("S1", "ST")
        for p in PARAMETERS
    }
    widths = list(named.values())
    within = f"{sum(w <= TARGET for w in widths)} of {len(widths)}"
    largest = max((w for w in widths if w == w), default=math.nan)  # NaN: undefined indices
    wide = ", ".join(f"{n} ±{w:.3f}" for n, w in named.items() if not w <= TARGET) or "none"
    cost = job_costs(args.results)
    print("\n".join(table(summary)))
    print(
        f"\n{summary['n_points']} points; largest half-width {largest:.3f} "
        f"({within} within ±{TARGET}); "
        f"{cost['shards']} shards; CPU {cost['cpu_s']:.0f} s = {cost['cpu_s'] / 3600:.2f} "
        f"core-hours (two dedicated cores: {cost['cpu_s'] / 2 / 60:.0f} min); "
        f"largest job {cost['max_rss_mb']:.0f} MB\nwider than ±{TARGET}: {wide}"
    )
    if args.record:
        from record import write_record

        write_record(
            "sensitivity_full",
            "The resolved parameter study (config sensitivity: full)",
            [
                ("points of the Saltelli sample", str(summary["n_points"])),
                (
                    f"indices within ±{TARGET} (95 % half-width)",
                    f"{within}; largest half-width {largest:.3f}",
                ),
                (f"indices wider than ±{TARGET}", wide),
                (
                    "CPU summed over the study's jobs",
                    f"{cost['cpu_s']:.0f} s = {cost['cpu_s'] / 3600:.2f} core-hours "
                    f"({cost['shards']} shard jobs)",
                ),
                ("wall time on two dedicated cores (CPU / 2)", f"{cost['cpu_s'] / 120:.0f} min"),
                ("largest job's peak memory", f"{cost['max_rss_mb']:.0f} MB"),
            ],
        )


if __name__ == "__main__":
    main()
