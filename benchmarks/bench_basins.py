"""A basin computation's time: 192 starts of the Fig. 3 motor under load on 1 and 2 cores.

Run:  python benchmarks/bench_basins.py [--phases 48] [--speeds 0,50,100,150] [--load 0.075]
      [--repeat 3] [--set stop.time=12000 ...]

Target: 48 phases x 4 speeds (192 starts), a window of 8,000 time units, e = 0.3 with
a load, in <= 10 s on 2 cores. The scene is the pipeline's ``basins_fig3``
(``workflow/config/scenes/basins_fig3.yaml``: stop 8000, discard 4000, restitution noise 1e-9),
at the load asked for. Every start is two runs of the engine (the window's halves, each from the
start), so the engine's work is 1.5 windows' worth per start.

The first call loads the compiled kernel from numba's cache (not timed: a warm-up of one start).
Wall times are the best of ``--repeat`` rounds; the 2-core labels are checked equal, bit for bit,
to the 1-core ones before anything is reported. The machine's other load makes the times longer,
never shorter.
"""

from __future__ import annotations

import argparse
import platform
import time
from pathlib import Path

from bouncedisk.model.scene import load_scene
from bouncedisk.studies.basins import basins, start_grid, summary

SCENE = Path(__file__).resolve().parents[1] / "workflow" / "config" / "scenes" / "basins_fig3.yaml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--phases", type=int, default=48)
    ap.add_argument("--speeds", default="0,50,100,150")
    ap.add_argument("--load", type=float, default=0.075)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument(
        "--record",
        action="store_true",
        help="write its record of the performance page (benchmarks/record.py)",
    )
    ap.add_argument(
        "--set", action="append", default=[], help="scene override, e.g. stop.time=12000"
    )
    args = ap.parse_args()
    scene = load_scene(SCENE, [f"parameters.load_torque={args.load}", *args.set])
    grid = start_grid(args.phases, [float(x) for x in args.speeds.split(",")])
    basins(scene, start_grid(1, [0.0]))  # warm-up: the kernel from numba's cache
    best: dict[int, float] = {}
    result = {}
    for cores in (1, 2):
        for _ in range(args.repeat):
            start = time.perf_counter()
            ds = basins(scene, grid, cores=cores)
            wall = time.perf_counter() - start
            best[cores] = min(best.get(cores, wall), wall)
        result[cores] = ds
    a, b = result[1]["label"].values, result[2]["label"].values
    assert a.tobytes() == b.tobytes(), "labels differ between 1 and 2 cores"
    out = summary(result[2])
    window = scene.stop.time - scene.initial.t
    print(f"{platform.processor() or platform.machine()}, python {platform.python_version()}")
    print(
        f"{grid.size} starts ({args.phases} phases x {len(grid.speeds)} speeds), window "
        f"{window:g} (averaged after {scene.stats.discard:g}), e = {scene.params.e}, load {args.load}"
    )
    for cores, wall in best.items():
        print(f"{cores} core(s): {wall:.2f} s (best of {args.repeat})")
    print(f"speed-up on 2 cores: {best[1] / best[2]:.2f}x; target <= 10 s on 2 cores")
    for att in out["attractors"]:
        lo, hi = att["fraction_ci95"]
        print(
            f"  attractor {att['label']}: speed {att['mean_speed']:.5g} {att['regime']} "
            f"{att['period']}, fraction {att['fraction']:.3f} [{lo:.3f}, {hi:.3f}]"
        )
    u = out["unsettled"]
    print(f"  not settled: {u['fraction']:.3f} {u['fraction_ci95']}")
    if args.record:
        from record import write_record

        what = f"{grid.size} starts, window {window:g}, e = {scene.params.e}, load {args.load}"
        rows = [
            (f"{what}, {c} core(s), best of {args.repeat}", f"{w:.2f} s") for c, w in best.items()
        ]
        rows += [(f"attractor {a['label']}: speed {a['mean_speed']:.6g}, {a['regime']}",
                  f"fraction {a['fraction']:.3f} [{a['fraction_ci95'][0]:.3f}, "
                  f"{a['fraction_ci95'][1]:.3f}]") for a in out["attractors"]]  # fmt: skip
        rows.append(("not settled", f"fraction {u['fraction']:.3f} "
                     f"[{u['fraction_ci95'][0]:.3f}, {u['fraction_ci95'][1]:.3f}]"))  # fmt: skip
        print(write_record("basins", "Basins of the Fig. 3 motor under load", rows))


if __name__ == "__main__":
    main()
