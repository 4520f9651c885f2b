"""A load curve's readings: one axial trajectory for all loads against one run per load.

Run:  python benchmarks/bench_load_readings.py [--members K] [--rounds R]

The joint fit reads a load curve at every parameter point it evaluates (``fitting.loadpart``):
each member starts from rest under each load and reads ``∫Ω dt`` over the window. The shipped
synthetic motor's load curve (16 loads, window 0.06–0.12 s) at its generating parameters, K
members: :func:`bouncedisk.engine.loads.omega_integrals` (one axial trajectory, every load's
rotation) against :func:`bouncedisk.engine.iterate` once per load. Both give the same bits
(checked here again); CPU time of the two alternated in one process, best of the rounds. Prints
one JSON object with the load average beside it.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time
from pathlib import Path

import numpy as np

from bouncedisk.engine import EngineConfig, InitialState, iterate
from bouncedisk.engine.loads import omega_integrals
from bouncedisk.fitting.loadpart import LOAD_STREAM, MAX_EVENTS, motor_scales
from bouncedisk.io.load_curves import read_load_curve

ROOT = Path(__file__).resolve().parents[1]
THETA = {"e": 0.55, "omega_s": 1.7, "log10_r_phi": float(np.log10(0.002)), "psi": 0.4}


def _config(member: int) -> tuple[EngineConfig, np.ndarray]:
    data = read_load_curve(ROOT / "data" / "prototype" / "synthetic_motor_load.csv")
    t_c, _speed, torque = motor_scales(THETA, data)
    t0, t1 = (w / t_c for w in data.window_s)
    cfg = EngineConfig(e=0.55, omega_s=1.7, r_phi=0.002, psi=0.4, torsion=True, t_end=t1,
                       max_events=MAX_EVENTS, e_sigma=0.03, seed=2, member=LOAD_STREAM + member,
                       stats_from=t0)  # fmt: skip
    return cfg, data.torque / torque


def _per_load(cfg: EngineConfig, loads: np.ndarray, init: InitialState) -> np.ndarray:
    out = []
    for x in loads:
        gen = iterate(dataclasses.replace(cfg, load_torque=float(x)), init)
        while True:
            try:
                next(gen)
            except StopIteration as stop:
                out.append(stop.value[1]["omega_integral"])
                break
    return np.array(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--members", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    init = InitialState(t=0.0, omega=0.0)
    runs = [_config(m) for m in range(args.members)]
    for f in (omega_integrals, _per_load):  # load the numba cache, not timed
        f(*runs[0], init)
    best = {"one_trajectory": np.inf, "one_run_per_load": np.inf}
    for _ in range(args.rounds):
        for name, f in (("one_trajectory", omega_integrals), ("one_run_per_load", _per_load)):
            t = time.process_time()
            got = [f(cfg, loads, init) for cfg, loads in runs]
            best[name] = min(best[name], time.process_time() - t)
            if name == "one_trajectory":
                ref = got
            elif not all(np.array_equal(a, b) for a, b in zip(ref, got, strict=True)):
                raise SystemExit("the two routes differ")
    print(json.dumps({
        "loads": int(len(runs[0][1])), "members": args.members, "rounds": args.rounds,
        "cpu_s": {k: round(v, 4) for k, v in best.items()},
        "speedup": round(best["one_run_per_load"] / best["one_trajectory"], 2),
        "identical": True, "load_average": os.getloadavg()[0],
    }))  # fmt: skip


if __name__ == "__main__":
    main()
