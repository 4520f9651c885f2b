"""What one small pipeline job costs in CPU, with and without freezing the heap.

Run:  python benchmarks/job_overhead.py [--repeats N] [--record]

A pipeline job is one Python process: it imports the package (numpy, numba, xarray, pandas),
loads the compiled engine from numba's cache, runs and exits. For a short simulation that fixed
part is nearly all of its cost. ``bouncedisk.io.job_log.log_to``, which every job script
enters, moves the objects alive at its start and at its end out of the cyclic garbage
collector's view (:func:`gc.freeze`). This benchmark runs the simulate job of one scene
(``workflow/config/scenes/fig3.yaml``, as ``workflow/scripts/simulate.py`` does) in fresh
processes, alternately as it is and with ``gc.freeze`` replaced by a no-op, and reports the
median CPU time (user + system) of each and their ratio. A first run fills numba's cache.
"""

from __future__ import annotations

import argparse
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "workflow" / "config" / "scenes" / "fig3.yaml"

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


def cpu_of(source: str, folder: Path) -> float:
    """CPU seconds (user + system) of one process running ``source`` on the scene."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    args = [str(SCENE), str(folder / "job.log"), str(folder / "out.nc")]
    subprocess.run([sys.executable, "-c", source, *args], check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    """Measure both variants alternately; print (and with ``--record`` write) the medians."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=10, help="processes per variant")
    parser.add_argument("--record", action="store_true", help="write benchmarks/out/")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        cpu_of(JOB, folder)  # numba's cache filled, files in the page cache
        frozen, unfrozen = [], []
        for _ in range(args.repeats):
            frozen.append(cpu_of(JOB, folder))
            unfrozen.append(cpu_of(UNFROZEN, folder))
    a, b = statistics.median(frozen), statistics.median(unfrozen)
    rows = [
        ("simulate job of fig3, heap frozen (median CPU)", f"{a:.2f} s"),
        ("the same job, gc.freeze disabled (median CPU)", f"{b:.2f} s"),
        ("ratio frozen / not frozen", f"{a / b:.2f}"),
        ("processes per variant, alternating", str(args.repeats)),
    ]
    for m, r in rows:
        print(f"{m}: {r}")
    if args.record:
        from record import write_record

        write_record("job_overhead", "One small pipeline job: CPU with the heap frozen", rows)


if __name__ == "__main__":
    main()
