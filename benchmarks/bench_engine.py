"""Engine throughput: impacts per second, axial-only and full scenes, at omega_s = 1.5 and 100.

Run:  python benchmarks/bench_engine.py [--events N] [--repeat R]

Targets (docs/user_guide/performance.md): >= 3e6 impacts/s per core axial-only at omega_s = 1.5
and >= 2e6 with torsion and load; cost per impact at omega_s = 100 at most
3x that at 1.5. Rates are per CPU second of this process (``time.process_time``: on a shared
machine wall time measures the neighbours too). All numbers come from this one run, so the
ratios compare like with like. The first call compiles (or loads the numba cache) and is not
timed.
"""

from __future__ import annotations

import argparse
import platform
import time

from bouncedisk.engine import EngineConfig, simulate_arrays

CASES = {
    "axial-only": dict(contact=True, torsion=False),
    "full (contact+torsion)": dict(contact=True, torsion=True, r_phi=0.01, psi=0.0),
    "torsion+load": dict(contact=True, torsion=True, r_phi=0.01, psi=0.0, load_torque=0.3),
}


def rate(w: float, effects: dict, events: int, repeat: int, e: float = 0.3) -> float:
    cfg = EngineConfig(e=e, omega_s=w, max_events=events, **effects)
    simulate_arrays(EngineConfig(e=e, omega_s=w, max_events=10, **effects))  # warm-up
    best = float("inf")
    for _ in range(repeat):
        t0 = time.process_time()
        res = simulate_arrays(cfg)
        best = min(best, time.process_time() - t0)
    assert len(res.events["t"]) == events
    return events / best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--events", type=int, default=2_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(
        f"machine: {platform.machine()} {platform.processor() or ''} python {platform.python_version()}"
    )
    print(f"{args.events:,} events per run, best of {args.repeat}; e = 0.3")
    print(f"{'scene':<24}{'omega_s=1.5':>16}{'omega_s=100':>16}{'cost ratio 100/1.5':>22}")
    results = {}
    for name, eff in CASES.items():
        r15 = rate(1.5, eff, args.events, args.repeat)
        r100 = rate(100.0, eff, args.events, args.repeat)
        results[name] = (r15, r100)
        print(f"{name:<24}{r15:>14,.0f}/s{r100:>14,.0f}/s{r15 / r100:>22.2f}")
    r15, r100 = results["axial-only"]
    ok1 = r15 >= 3e6
    ok2 = r15 / r100 <= 3.0
    print(
        f"target axial-only >= 3e6 impacts/s at 1.5: {'met' if ok1 else 'NOT met'} ({r15:,.0f}/s)"
    )
    rl = results["torsion+load"][0]
    print(
        f"target torsion+load >= 2e6 impacts/s at 1.5: {'met' if rl >= 2e6 else 'NOT met'} "
        f"({rl:,.0f}/s)"
    )
    print(f"target cost(100)/cost(1.5) <= 3: {'met' if ok2 else 'NOT met'} ({r15 / r100:.2f})")


if __name__ == "__main__":
    main()
