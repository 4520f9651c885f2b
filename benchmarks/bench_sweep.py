"""A sweep's speed-up on 2 cores: one job against two shards side by side, in one run.

Run:  python benchmarks/bench_sweep.py [--e N] [--omega N] [--repeat R]

Target (docs/user_guide/performance.md): ensembles and sweeps >= 1.85x on 2 cores against 1. A sweep
runs its grid points in turn; its parallelism is its shards (``run_sweep(..., shard, n_shards)``,
the pipeline's ``sweep_shard`` jobs). Measured here on the regime map's base scene
(``workflow/config/scenes/regime_map.yaml``) over a small ``(e, omega_s)`` grid:

- the whole grid in one shard (one core);
- the whole grid in one shard on two threads (``run_sweep(..., cores=2)``: each thread takes the
  next member of the next point as it finishes one, so unequal points balance themselves);
- ``--shards`` shards (default 4, as the pipeline's regime map) handed to two threads of this
  process (the kernel and the members' reduction release the GIL);
- the same shards handed to two processes (as the pipeline's shard jobs run on ``--cores 2``;
  forked, so the numba cache is already loaded).

A shard is a contiguous block of the first axis (the joined file must be ordered), and the cost
of a point varies along it, so two shards of equal size can take unequal times: more shards than
cores balance the load (the two-shard split is printed too).

Wall times are the best of ``--repeat`` rounds, all in this run, so the ratios compare like with
like; the machine's other load makes every ratio smaller, never larger. The joined shards are
checked equal to the one-shard sweep (every statistic, bit for bit) before anything is reported.
"""

from __future__ import annotations

import argparse
import multiprocessing
import platform
import time
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path

import numpy as np

from bouncedisk.analysis.sweeps import combine_shards, run_sweep
from bouncedisk.model.scene import load_scene

SCENE = Path(__file__).resolve().parents[1] / "workflow" / "config" / "scenes" / "regime_map.yaml"


def _axes(n_e: int, n_omega: int) -> list[tuple[str, np.ndarray]]:
    return [("e", np.linspace(0.05, 0.95, n_e)), ("omega_s", np.linspace(1.05, 4.0, n_omega))]


def _shard(args: tuple[int, int, int, int], cores: int = 1):
    """One shard of the benchmark's sweep (a picklable task for the process pool)."""
    shard, n_shards, n_e, n_omega = args
    return run_sweep(load_scene(SCENE), _axes(n_e, n_omega), shard, n_shards, tail=10, cores=cores)


def _timed(run) -> tuple[float, object]:
    start = time.perf_counter()
    out = run()
    return time.perf_counter() - start, out


def _same(a, b) -> bool:
    """Every statistic of two sweeps equal (NaN where NaN); run ids and times may differ."""
    names = [v for v in a.data_vars if a[v].dtype.kind == "f"]
    return all(np.array_equal(a[v].values, b[v].values, equal_nan=True) for v in names)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--e", type=int, default=12, help="values of e (default 12)")
    ap.add_argument("--omega", type=int, default=8, help="values of omega_s (default 8)")
    ap.add_argument("--shards", type=int, default=4, help="shards on 2 workers (default 4)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    _shard((0, 1, 2, 1))  # load the numba cache (not timed)
    one = (0, 1, args.e, args.omega)
    two = [(i, 2, args.e, args.omega) for i in range(2)]
    many = [(i, args.shards, args.e, args.omega) for i in range(args.shards)]
    serial, threads, procs, halves, pointwise = [], [], [], [], []
    ctx = multiprocessing.get_context("fork")
    for _ in range(args.repeat):
        t1, whole = _timed(lambda: _shard(one))
        t5, whole2 = _timed(lambda: _shard(one, cores=2))
        with ThreadPoolExecutor(2) as pool:
            t2, parts = _timed(lambda pool=pool: list(pool.map(_shard, many)))
        with ProcessPoolExecutor(2, mp_context=ctx) as pool:
            pool.submit(sum, [0]).result()  # the workers exist before the clock starts
            t3, parts_p = _timed(lambda pool=pool: list(pool.map(_shard, many)))
            t4, halves_p = _timed(lambda pool=pool: list(pool.map(_shard, two)))
        for joined in (parts, parts_p, halves_p):
            if not _same(whole, combine_shards(joined)):
                raise SystemExit("the joined shards differ from the one-shard sweep")
        if not _same(whole, whole2):
            raise SystemExit("the sweep on two threads differs from the one on one")
        serial.append(t1)
        threads.append(t2)
        procs.append(t3)
        halves.append(t4)
        pointwise.append(t5)
    points = args.e * args.omega
    print(f"machine: {platform.machine()}  python {platform.python_version()}")
    print(f"regime-map sweep, {points} points (6 members each), best of {args.repeat}")
    n = args.shards
    print(f"one shard, one core             {min(serial):7.2f} s")
    print(
        f"one shard, points on two threads {min(pointwise):6.2f} s   "
        f"{min(serial) / min(pointwise):.2f}x"
    )
    print(
        f"{n} shards on two threads        {min(threads):7.2f} s   {min(serial) / min(threads):.2f}x"
    )
    print(f"{n} shards on two processes      {min(procs):7.2f} s   {min(serial) / min(procs):.2f}x")
    print(
        f"2 shards on two processes       {min(halves):7.2f} s   {min(serial) / min(halves):.2f}x"
    )
    print("joined shards and the two-thread sweep equal the one-shard sweep: yes")


if __name__ == "__main__":
    main()
