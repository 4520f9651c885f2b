"""What one small pipeline job costs in CPU: with and without freezing the heap, and with dask.

Run:  python benchmarks/job_overhead.py [--repeats N] [--record]

A pipeline job is one Python process: it imports the package (numpy, numba, xarray, pandas),
loads the compiled engine from numba's cache, runs and exits. For a short simulation that fixed
part is nearly all of its cost. ``bouncedisk.io.job_log.log_to``, which every job script
enters, moves the objects alive at its start and at its end out of the cyclic garbage
collector's view (:func:`gc.freeze`). This benchmark runs the simulate job of one scene
(``workflow/config/scenes/fig3.yaml``, as ``workflow/scripts/simulate.py`` does) in fresh
processes, alternately as it is and with ``gc.freeze`` replaced by a no-op, and reports the
median CPU time (user + system) of each and their ratio. A first run fills numba's cache.

xarray imports dask in every process that makes a variable when dask is installed (its check
for dask arrays), although bouncedisk uses none: when dask is installed here, the ensemble job
of one scene (``workflow/config/scenes/stats_locked.yaml``, as
``workflow/scripts/ensemble_stats.py`` does: its dataset is made in memory) runs alternately as
it is and with dask made unimportable, which is the job of an environment without dask.
"""

from __future__ import annotations

import argparse
import importlib.util
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "workflow" / "config" / "scenes" / "fig3.yaml"
STATS_SCENE = ROOT / "workflow" / "config" / "scenes" / "stats_locked.yaml"

#: The simulate job's body (``workflow/scripts/simulate.py`` without Snakemake's object).
JOB = """
import sys
from bouncedisk.io.job_log import log_to
from bouncedisk.model.scene import load_scene
from bouncedisk.run.runner import run_scene

with log_to(sys.argv[2]):
    run_scene(load_scene(sys.argv[1]), sys.argv[3], progress=False, command="job_overhead")
"""
#: The same job with the freezing disabled.
UNFROZEN = "import gc\ngc.freeze = lambda: None\n" + JOB
#: The ensemble job's body (``workflow/scripts/ensemble_stats.py`` without Snakemake's object).
STATS_JOB = """
import sys
from bouncedisk.analysis.statistics import run_stats, to_dataset
from bouncedisk.io.job_log import log_to
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.scene import load_scene

with log_to(sys.argv[2]):
    scene = load_scene(sys.argv[1])
    write_dataset(to_dataset(scene, run_stats(scene, cores=1), 0.0), sys.argv[3])
"""
#: The same job as it runs where dask is not installed (xarray's import of it fails at once).
STATS_NO_DASK = "import sys\nsys.modules['dask'] = None\n" + STATS_JOB


def cpu_of(source: str, folder: Path, scene: Path = SCENE) -> float:
    """CPU seconds (user + system) of one process running ``source`` on ``scene``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    args = [str(scene), str(folder / "job.log"), str(folder / "out.nc")]
    subprocess.run([sys.executable, "-c", source, *args], check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    """Measure the variants alternately; print (and with ``--record`` write) the medians."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=10, help="processes per variant")
    parser.add_argument("--record", action="store_true", help="write benchmarks/out/")
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error(f"--repeats: {args.repeats}: at least 1 process per variant")
    has_dask = importlib.util.find_spec("dask") is not None
    if args.record and not has_dask:  # the record keeps the dask comparison
        parser.exit(2, 'job_overhead.py: error: --record needs dask (pip install -e ".[test]")\n')
    variants = {"frozen": (JOB, SCENE), "unfrozen": (UNFROZEN, SCENE)}
    if has_dask:
        variants.update(stats=(STATS_JOB, STATS_SCENE), stats_no_dask=(STATS_NO_DASK, STATS_SCENE))
    cpu = {name: [] for name in variants}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for source, scene in variants.values():  # numba's cache filled, files in the page cache
            cpu_of(source, folder, scene)
        for _ in range(args.repeats):
            for name, (source, scene) in variants.items():
                cpu[name].append(cpu_of(source, folder, scene))
    med = {name: statistics.median(values) for name, values in cpu.items()}
    a, b = med["frozen"], med["unfrozen"]
    rows = [
        ("simulate job of fig3, heap frozen (median CPU)", f"{a:.2f} s"),
        ("the same job, gc.freeze disabled (median CPU)", f"{b:.2f} s"),
        ("ratio frozen / not frozen", f"{a / b:.2f}"),
    ]
    if "stats" in med:
        c, d = med["stats"], med["stats_no_dask"]
        rows += [
            ("ensemble job of stats_locked, dask installed (median CPU)", f"{c:.2f} s"),
            ("the same job, dask unimportable (median CPU)", f"{d:.2f} s"),
            ("ratio without dask / with dask installed", f"{d / c:.2f}"),
        ]
    rows.append(("processes per variant, alternating", str(args.repeats)))
    for m, r in rows:
        print(f"{m}: {r}")
    if args.record:
        from record import write_record

        write_record(
            "job_overhead", "One small pipeline job: CPU with the heap frozen, and dask", rows
        )


if __name__ == "__main__":
    main()
