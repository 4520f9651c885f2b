"""Ensemble statistics: parallel speed-up, the cost of restitution noise, and a stats run's time.

Run:  python benchmarks/bench_ensemble.py [--members K] [--repeat R]

Targets (issue "Long-run statistics that mean something"): an ensemble on 2 cores runs close to 2x
the one-core rate; scenes without noise pay nothing for it (the per-impact cost with noise is
reported as a ratio); `bouncedisk stats` at e = 0.6, omega_s = 1.5, r_phi = 0.01 with 32 members
over t in [3000, 53000] takes under 10 s on 2 cores with a 95% half-width <= 1.5. All numbers
come from this one run; the first call loads the numba cache and is not timed.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import time

from bouncedisk.analysis.ensembles import run_ensemble
from bouncedisk.analysis.statistics import confidence_interval
from bouncedisk.engine import EngineConfig, InitialState, simulate_arrays

CFG = EngineConfig(
    e=0.6,
    omega_s=1.5,
    torsion=True,
    r_phi=0.01,
    t_end=53000.0,
    max_events=10**9,
    e_sigma=1e-9,
    seed=1,
)


def ensemble_seconds(members: int, cores: int, repeat: int, psi: float = 0.0) -> tuple[float, list]:
    """Best wall time of one ensemble over [3000, 53000], and its members."""
    cfg = EngineConfig(**{**CFG.__dict__, "psi": psi})
    best, res = math.inf, []
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = run_ensemble(cfg, InitialState(), members, 3000.0, cores=cores)
        best = min(best, time.perf_counter() - t0)
    return best, res


def gil_free_share(members: int) -> float:
    """Share of one thread's ensemble time spent in compiled code that releases the GIL (the
    kernel, the members' reduction): the rest runs under the GIL and bounds the speed-up on
    ``n`` cores at ``1 / (1 − share + share / n)``, whatever the machine's load."""
    from bouncedisk.analysis import ensembles
    from bouncedisk.engine import kernel

    inside = [0.0]

    def timed(fn):
        def call(*args):
            t0 = time.perf_counter()
            out = fn(*args)
            inside[0] += time.perf_counter() - t0
            return out

        return call

    saved = kernel.run_chunk, ensembles._reduce_chunk
    kernel.run_chunk, ensembles._reduce_chunk = timed(saved[0]), timed(saved[1])
    try:
        t0 = time.perf_counter()
        run_ensemble(CFG, InitialState(), members, 3000.0, cores=1)
        total = time.perf_counter() - t0
    finally:
        kernel.run_chunk, ensembles._reduce_chunk = saved
    return inside[0] / total


def noise_cost_ratio(events: int, repeat: int) -> float:
    """Per-impact time with restitution noise over without (same scene otherwise)."""
    base = EngineConfig(e=0.6, omega_s=1.5, torsion=True, r_phi=0.01, max_events=events)
    noisy = EngineConfig(**{**base.__dict__, "e_sigma": 1e-9})
    out = {}
    for name, cfg in (("off", base), ("on", noisy)):
        best = math.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            simulate_arrays(cfg)
            best = min(best, time.perf_counter() - t0)
        out[name] = best
    return out["on"] / out["off"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--members", type=int, default=32)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(
        f"machine: {platform.machine()} python {platform.python_version()}, {os.cpu_count()} cpus"
    )
    run_ensemble(CFG, InitialState(), 2, 52000.0, cores=2)  # warm-up (numba cache)
    one, _ = ensemble_seconds(args.members, 1, args.repeat)
    two, res = ensemble_seconds(args.members, 2, args.repeat)
    impacts = sum(m.n_impacts for m in res)
    print(f"{args.members} members x 50,000 time units ({impacts:,} impacts after the transient)")
    print(f"  1 core : {one:.3f} s")
    print(f"  2 cores: {two:.3f} s   speed-up {one / two:.2f}x (target close to 2x)")
    share = max(gil_free_share(args.members) for _ in range(args.repeat))
    print(
        f"  share of a member's time without the GIL: {100 * share:.1f} % "
        f"(bounds the 2-core speed-up at {1 / (1 - share / 2):.2f}x)"
    )
    for psi in (0.0, math.pi / 2):
        sec, res = ensemble_seconds(args.members, 2, 1, psi)
        mean, low, high = confidence_interval([m.mean_omega for m in res])
        print(
            f"  psi = {psi:.4f}: mean Omega {mean:.3f}, 95% CI [{low:.3f}, {high:.3f}], "
            f"half-width {(high - low) / 2:.3f} (target <= 1.5), {sec:.2f} s on 2 cores"
        )
    ratio = noise_cost_ratio(2_000_000, args.repeat)
    print(f"cost per impact with restitution noise / without: {ratio:.3f}")


if __name__ == "__main__":
    main()
