"""The run registry: one row per simulation output, gathered from the files' provenance.

``results/runs.csv`` has the run id, scene name and hash, parameters, effects, solver, code
version and git commit, wall time and peak memory (from Snakemake benchmark files when present),
and the output's sha256, so any figure can be traced to the exact run and code behind it.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from .atomic import atomic_path
from .datasets import open_checked
from .errors import InputError
from .provenance import sha256_file

COLUMNS = [
    "run_id",
    "scene_name",
    "file",
    "scene_sha256",
    "e",
    "omega_s",
    "r_phi",
    "psi",
    "effects",
    "solver",
    "tol",
    "n_impacts",
    "n_chatter",
    "status",
    "bouncedisk_version",
    "git_commit",
    "created",
    "wall_time_s",
    "job_s",
    "max_rss_mb",
    "sha256",
]


def _benchmark(path: Path, benchmarks_dir: Path | None) -> tuple[float, float]:
    """Wall time and peak RSS (MB) of the Snakemake job that made ``path``, if recorded."""
    if benchmarks_dir is None:
        return float("nan"), float("nan")
    hits = sorted(benchmarks_dir.rglob(f"{path.stem}.tsv"))
    if not hits:
        return float("nan"), float("nan")
    try:
        b = pd.read_csv(hits[0], sep="\t")
        return float(b["s"].iloc[-1]), float(b["max_rss"].iloc[-1])
    except (KeyError, ValueError, IndexError, pd.errors.ParserError):
        return float("nan"), float("nan")


def build(files: list[str | Path], benchmarks_dir: str | Path | None = None) -> pd.DataFrame:
    """Gather the registry from netCDF files (each validated on reading)."""
    bdir = Path(benchmarks_dir) if benchmarks_dir else None
    rows = []
    for f in files:
        p = Path(f)
        ds = open_checked(p, required_attrs=("run_id", "scene_name"), what="bouncedisk output")
        a = ds.attrs
        job_s, rss = _benchmark(p, bdir)
        rows.append(
            {
                "run_id": a.get("run_id"),
                "scene_name": a.get("scene_name"),
                "file": str(p),
                "scene_sha256": a.get("scene_sha256", ""),
                "e": a.get("e"),
                "omega_s": a.get("omega_s"),
                "r_phi": a.get("r_phi"),
                "psi": a.get("psi"),
                "effects": a.get("effects", ""),
                "solver": a.get("solver", ""),
                "tol": a.get("tol"),
                "n_impacts": a.get("n_impacts"),
                "n_chatter": a.get("n_chatter"),
                "status": a.get("status", ""),
                "bouncedisk_version": a.get("bouncedisk_version", ""),
                "git_commit": a.get("git_commit", ""),
                "created": a.get("created", ""),
                "wall_time_s": a.get("wall_time_s"),
                "job_s": job_s,
                "max_rss_mb": rss,
                "sha256": sha256_file(p),
            }
        )
    return pd.DataFrame(rows, columns=COLUMNS)


def write(table: pd.DataFrame, path: str | Path) -> None:
    """Write the registry CSV atomically."""
    with atomic_path(path, suffix=".csv") as tmp:
        table.to_csv(tmp, index=False)


def read(path: str | Path) -> pd.DataFrame:
    """Read and validate a registry CSV."""
    p = Path(path)
    if not p.exists():
        raise InputError(
            str(path), "", "no run registry here (build it with `snakemake --cores 2`)"
        )
    try:
        table = pd.read_csv(p)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as ex:
        raise InputError(str(path), "", f"not a readable CSV: {str(ex).splitlines()[0]}") from None
    missing = [c for c in ("run_id", "scene_name") if c not in table.columns]
    if missing:
        raise InputError(str(path), missing[0], "missing required column (not a run registry?)")
    return table


def format_table(table: pd.DataFrame) -> str:
    """A compact listing for the terminal."""
    cols = [
        c
        for c in (
            "run_id",
            "scene_name",
            "e",
            "omega_s",
            "effects",
            "solver",
            "n_impacts",
            "status",
            "wall_time_s",
            "git_commit",
        )
        if c in table.columns
    ]
    view = table[cols].copy()
    if "git_commit" in view:
        view["git_commit"] = view["git_commit"].astype(str).str[:12]
    if "status" in view:
        view["status"] = view["status"].astype(str).str[:24]
    return view.to_string(index=False)


def _find(table: pd.DataFrame, key: str) -> pd.Series:
    hits = table[table["run_id"].astype(str).str.startswith(key)]
    if len(hits) == 0:
        hits = table[table["scene_name"].astype(str) == key]
    if len(hits) != 1:
        raise InputError("runs diff", key, f"matches {len(hits)} runs; give a unique run id prefix")
    return hits.iloc[0]


def diff(table: pd.DataFrame, a: str, b: str) -> str:
    """What differs between two runs (every registry column)."""
    ra, rb = _find(table, a), _find(table, b)
    lines = [f"{'field':>20}  {ra['run_id']}  |  {rb['run_id']}"]
    for c in table.columns:
        va, vb = ra[c], rb[c]
        same = (pd.isna(va) and pd.isna(vb)) or va == vb
        if not same:
            lines.append(f"{c:>20}  {va}  |  {vb}")
    if len(lines) == 1:
        lines.append("(no differences)")
    return "\n".join(lines)
