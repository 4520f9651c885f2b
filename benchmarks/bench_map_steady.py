"""The design maps' steady speeds against long runs and the torque–speed curves.

Run:  PYTHONPATH=src python benchmarks/bench_map_steady.py [--out benchmarks/out/map_steady.json]

At psi = 0 and every R_phi of the maps (the pipeline's config), each map cell's no-load speed
R_phi * mean(Omega) and stall torque (:class:`bouncedisk.studies.sensitivity.MotorModel` with
:func:`~bouncedisk.studies.sensitivity.map_settings`) beside a long run's no-load speed (discard
100, window 50, units of 1/R_phi, the same members).
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import platform
import time

import numpy as np
import yaml

from bouncedisk.analysis.statistics import run_stats
from bouncedisk.studies import sensitivity as sens
from bouncedisk.studies.sensitivity_settings import study_settings


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="benchmarks/out/map_steady.json")
    args = ap.parse_args()
    config = yaml.safe_load(open("workflow/config/config.yaml"))
    st = sens.map_settings(study_settings(config))
    model = sens.MotorModel(st)
    long = sens.MotorModel(
        dataclasses.replace(st, discard=100.0, duration=50.0, runup=0.0, loads=())
    )
    rows = []
    lr_values = np.linspace(*st.ranges["log10_r_phi"], st.map_points[1])
    for e in st.map_e:
        for lr in lr_values:
            point = {"e": e, "omega_s": st.map_omega_s, "log10_r_phi": float(lr), "psi": 0.0}
            start = time.process_time()
            v = model(point).values
            cpu = time.process_time() - start
            r = 10.0**lr
            ref = r * float(np.mean(run_stats(long.scene(point), cores=1).column("mean_omega")))
            stall = v["stall_torque"]
            rows.append({
                "measurement": f"e = {e:g}, psi = 0, log10 R_phi = {lr:.3g}: no-load speed "
                "R_phi mean(Omega) (map; long run), stall torque [95% interval] (map)",
                "result": f"{v['no_load_speed'][0]:.4f}; {ref:.4f} "
                f"({100 * (v['no_load_speed'][0] / ref - 1):+.2f} %), {stall[0]:.3f} "
                f"[{stall[1]:.3f}, {stall[2]:.3f}] ({cpu:.2f} s CPU)",
            })  # fmt: skip
            print(rows[-1]["measurement"], rows[-1]["result"], flush=True)
    record = {
        "title": "Steady speeds of the design maps against long runs",
        "command": "PYTHONPATH=src python benchmarks/bench_map_steady.py",
        "date": datetime.date.today().isoformat(),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores (shared), Python "
        f"{platform.python_version()}",
        "rows": rows,
    }
    with open(args.out, "w") as f:
        json.dump(record, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
