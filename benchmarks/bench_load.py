"""What the motor under load costs (issue "The motor under load", docs/model.md).

Run:  python benchmarks/bench_load.py [--events N] [--rounds R] [--skip-curve]

1. Cost per impact with the ``load`` effect against the same scene without it (e = 0.6,
   torsion, restitution noise, the energy audit on as in an ensemble member): CPU time of the
   compiled engine, the two alternated in one process, best of the rounds.
2. Wall time of a 25-load x 32-member torque-speed curve at e = 0.6, 50,000 time units per member
   and load (2,000 of them discarded), both continuation branches, on 2 cores; and one branch.
3. The largest energy-audit residuals over the test suite's regimes (10^6 events each).

Prints one JSON object. Timings on a shared machine are noisy: read the ratio, and the load
average printed beside it.
"""

from __future__ import annotations

import argparse
import json
import os
import time

from bouncedisk.engine import EngineConfig, simulate_arrays
from bouncedisk.engine.driver import audit_balances
from bouncedisk.model.scene import scene_from_mapping
from bouncedisk.studies.torque_speed import torque_speed

BASE = dict(e=0.6, omega_s=1.5, r_phi=0.01, psi=0.0, torsion=True, e_sigma=1e-9, stats_from=0.0)
REGIMES = {
    "periodic e=0.3": dict(e=0.3, max_events=10**6),
    "chaotic with chatter e=0.6": dict(e=0.6, max_events=10**6),
    "e=0 stick-slip (psi 0.7)": dict(e=0.0, psi=0.7, max_events=10**6),
    "w<=1 permanent contact": dict(e=0.5, omega_s=0.9, t_end=2.0e5),
    "e=1": dict(e=1.0, psi=0.7, max_events=10**6),
}


def cost_ratio(events: int, rounds: int) -> dict:
    """CPU ns per impact without and with the load, best of ``rounds`` alternated runs."""
    best = {"no load": float("inf"), "load 0.3": float("inf")}
    for _ in range(rounds):
        for name, load in (("no load", 0.0), ("load 0.3", 0.3)):
            cfg = EngineConfig(**BASE, max_events=events, load_torque=load)
            t0 = time.process_time()
            res = simulate_arrays(cfg)
            dt = time.process_time() - t0
            best[name] = min(best[name], dt / len(res.events["t"]) * 1e9)
    return {
        "ns_per_impact": best,
        "ratio_load_over_none": best["load 0.3"] / best["no load"],
        "events": events,
    }


def curve_time(branches: tuple[str, ...]) -> dict:
    """Wall time of the 25-load x 32-member curve on 2 cores."""
    raw = {
        "name": "bench_load",
        "parameters": {
            "e": 0.6,
            "omega_s": 1.5,
            "r_phi": 0.01,
            "psi": 0.0,
            "e_sigma": 1e-9,
            "load_torque": 0.0,
        },  # fmt: skip
        "effects": ["impacts", "contact", "torsion", "restitution_noise", "load"],
        "stop": {"time": 50000.0},
        "stats": {"discard": 2000.0},
        "ensemble": {"members": 32, "seed": 1},
    }
    scene = scene_from_mapping(raw, "<bench>")
    loads = [0.04 * k for k in range(25)]
    t0 = time.perf_counter()
    c0 = time.process_time()
    curve = torque_speed(scene, loads, cores=2, branches=branches)
    wall = time.perf_counter() - t0
    s = curve.summary()
    return {
        "branches": list(branches),
        "wall_s": wall,
        "cpu_s": time.process_time() - c0,
        "stall_torque": s["stall_torque"],
        "max_power": s["max_power"],
        "loadavg_1min": os.getloadavg()[0],
    }


def residuals() -> dict:
    out = {}
    for name, kw in REGIMES.items():
        for load in (0.0, 0.3):
            cfg = EngineConfig(**{**BASE, "e_sigma": 0.0, **kw}, load_torque=load)
            ax, tor = audit_balances(simulate_arrays(cfg).final["audit"])
            out[f"{name}, load {load}"] = {"axial": ax, "torsion": tor}
    worst = {
        "axial": max(v["axial"] for v in out.values()),
        "torsion": max(v["torsion"] for v in out.values()),
    }
    return {"per_regime": out, "largest": worst}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--events", type=int, default=1_000_000)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--skip-curve", action="store_true")
    args = ap.parse_args()
    simulate_arrays(EngineConfig(**BASE, max_events=1000, load_torque=0.3))  # compile
    out = {"cost": cost_ratio(args.events, args.rounds), "loadavg_1min": os.getloadavg()[0]}
    if not args.skip_curve:
        out["curve_both_branches"] = curve_time(("up", "down"))
        out["curve_one_branch"] = curve_time(("up",))
    out["audit"] = residuals()
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
