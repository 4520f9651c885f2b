"""Compare two pipeline results folders built from the same config (.ci/cluster-test, .ci/two-kernels).

    python .ci/compare_results.py [--subset] RESULTS_A RESULTS_B

Every netCDF file must exist in both folders and hold bit-identical data: the same variables and
coordinates with the same dimensions, dtype and bytes (read raw, without CF decoding), the same
variable attributes, and the same global attributes except those that differ from run to run by
design (PER_RUN_ATTRS). Every figure must exist, non-empty, in both. Exit 0 only if all of it holds.

--subset: A is a run of part of the pipeline (some targets) and B a run of all of it: every netCDF
file and figure of A must be in B and hold the same data; B's other files are not looked at.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import xarray as xr

# Global attributes that record when and how fast a file was made, or a random run id: they differ
# between any two runs, local or not, so they are left out of the comparison. A run id quoted inside
# another attribute (e.g. a Poincaré file's title names its simulation's run) is masked the same way.
# Everything else must match exactly.
PER_RUN_ATTRS = frozenset(
    {
        "created",  # UTC timestamp of writing
        "date_created",  # ACDD copy of `created`
        "date_modified",  # ACDD: also the time of writing
        "date_issued",
        "date_metadata_modified",
        "history",  # command line and timestamp
        "run_id",  # <scene>-<scene hash>-<random>
        "source_run_id",  # run_id of the simulation a derived file was made from
        "shard_run_ids",  # run_ids of the shards a combined sweep was joined from
        "wall_time_s",  # measured wall time
        "cpu_time_s",  # measured CPU time (sensitivity shards and maps)
        "cpu_s_per_point",  # the sensitivity study's measured cost
        "id",  # ACDD id: the run id, or a random one for a file made without a run
    }
)
RUN_ID_ATTRS = ("run_id", "source_run_id", "shard_run_ids")
FIGURE_SUFFIXES = (".pdf", ".png")


def _files(root: Path, suffixes: tuple[str, ...]) -> set[Path]:
    return {p.relative_to(root) for p in root.rglob("*") if p.is_file() and p.suffix in suffixes}


def _bytes(values: np.ndarray) -> bytes:
    values = np.ascontiguousarray(values)
    if values.dtype == object:  # variable-length strings
        return repr(values.tolist()).encode()
    return values.tobytes()


def _run_ids(attrs: dict) -> list[str]:
    """The random run ids a file's attributes name (longest first, so none masks part of another)."""
    ids = {i.strip() for k in RUN_ID_ATTRS for i in str(attrs.get(k, "")).split(",") if i.strip()}
    return sorted(ids, key=len, reverse=True)


def _mask(value, run_ids: list[str]):
    if isinstance(value, str):
        for run_id in run_ids:
            value = value.replace(run_id, "<run_id>")
    return value


def _same_attr(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.dtype == b.dtype and a.shape == b.shape and _bytes(a) == _bytes(b)
    if isinstance(a, float) and isinstance(b, float) and np.isnan(a) and np.isnan(b):
        return True
    return type(a) is type(b) and a == b


def compare_netcdf(a: Path, b: Path) -> list[str]:
    """What differs between two netCDF files (empty when their data are bit-identical)."""
    problems = []
    with (
        xr.open_dataset(a, decode_cf=False, mask_and_scale=False, decode_times=False) as da,
        xr.open_dataset(b, decode_cf=False, mask_and_scale=False, decode_times=False) as db,
    ):
        names_a, names_b = set(da.variables), set(db.variables)
        if names_a != names_b:
            problems.append(
                f"variables differ: only in A {sorted(names_a - names_b)}, "
                f"only in B {sorted(names_b - names_a)}"
            )
        for name in sorted(names_a & names_b):
            va, vb = da.variables[name], db.variables[name]
            if va.dims != vb.dims or va.dtype != vb.dtype or va.shape != vb.shape:
                problems.append(
                    f"{name}: {va.dims} {va.dtype} {va.shape} != {vb.dims} {vb.dtype} {vb.shape}"
                )
                continue
            if _bytes(va.values) != _bytes(vb.values):
                problems.append(f"{name}: values differ")
            problems += _compare_attrs(va.attrs, vb.attrs, f"{name}.")
        ids_a, ids_b = _run_ids(da.attrs), _run_ids(db.attrs)
        masked_a = {k: _mask(v, ids_a) for k, v in da.attrs.items()}
        masked_b = {k: _mask(v, ids_b) for k, v in db.attrs.items()}
        problems += _compare_attrs(masked_a, masked_b, "global ")
    return problems


def _compare_attrs(a: dict, b: dict, where: str) -> list[str]:
    problems = []
    for key in sorted((set(a) | set(b)) - PER_RUN_ATTRS):
        if key not in a or key not in b:
            problems.append(f"{where}attribute {key!r} only in {'A' if key in a else 'B'}")
        elif not _same_attr(a[key], b[key]):
            problems.append(f"{where}attribute {key!r}: {a[key]!r} != {b[key]!r}")
    return problems


def main(argv: list[str]) -> int:
    subset = "--subset" in argv[1:2]
    if subset:
        argv = [argv[0], *argv[2:]]
    if len(argv) != 3:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    root_a, root_b = Path(argv[1]), Path(argv[2])
    failures = 0

    nc_a = _files(root_a, (".nc",))
    # --subset: only A's files are looked up in B (B, a whole run, may hold CI's other folders too)
    nc_b = {r for r in nc_a if (root_b / r).is_file()} if subset else _files(root_b, (".nc",))
    if not nc_a:
        print(f"FAIL no netCDF files in {root_a}")
        failures += 1
    for rel in sorted(nc_a ^ nc_b):
        print(f"FAIL {rel}: only in {root_a if rel in nc_a else root_b}")
        failures += 1
    for rel in sorted(nc_a & nc_b):
        problems = compare_netcdf(root_a / rel, root_b / rel)
        print(f"{'FAIL' if problems else 'ok  '} {rel}")
        for p in problems:
            print(f"       {p}")
        failures += bool(problems)

    figs_a = _files(root_a / "figures", FIGURE_SUFFIXES)
    if subset:
        figs_b = {r for r in figs_a if (root_b / "figures" / r).is_file()}
    else:
        figs_b = _files(root_b / "figures", FIGURE_SUFFIXES)
    if not figs_a:
        print(f"FAIL no figures in {root_a / 'figures'}")
        failures += 1
    for rel in sorted(figs_a | figs_b):
        sizes = [
            (r / "figures" / rel).stat().st_size if rel in f else 0
            for r, f in ((root_a, figs_a), (root_b, figs_b))
        ]
        ok = all(sizes)
        print(f"{'ok  ' if ok else 'FAIL'} figures/{rel} ({sizes[0]} / {sizes[1]} bytes)")
        failures += not ok

    print(
        f"{len(nc_a & nc_b)} netCDF files and {len(figs_a & figs_b)} figures compared; "
        f"ignored per-run attributes: {', '.join(sorted(PER_RUN_ATTRS))}; {failures} failure(s)"
    )
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
