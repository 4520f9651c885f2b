"""The design maps read steady speeds: at R_phi = 0.001, the slowest to run up, a map cell's
no-load speed and stall torque are those of a long run and of the torque–speed curve."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from bouncedisk.analysis.statistics import run_stats
from bouncedisk.studies import sensitivity as sens
from bouncedisk.studies.sensitivity_settings import study_settings

CONFIG = Path(__file__).resolve().parents[1] / "workflow" / "config" / "config.yaml"


def test_a_map_cell_at_the_smallest_r_phi_has_run_up():
    """At e = 0.3, psi = 0, R_phi = 0.001 the map's no-load speed was 1.2506 (a window of 5 + 5
    units of 1/R_phi, still in the run-up) against a long run's 1.456, its stall torque 1.07."""
    st = sens.map_settings(study_settings(yaml.safe_load(CONFIG.read_text())))
    point = {"e": 0.3, "omega_s": 1.5, "log10_r_phi": -3.0, "psi": 0.0}
    got = sens.MotorModel(st)(point).values
    long = sens.MotorModel(
        sens.dataclasses.replace(st, discard=60.0, duration=20.0, runup=0.0, loads=())
    )
    ref = 1e-3 * float(np.mean(run_stats(long.scene(point), cores=1).column("mean_omega")))
    assert abs(got["no_load_speed"][0] / ref - 1.0) < 0.03
    value, low, high, _ = got["stall_torque"]
    assert 0.95 <= low <= value <= high <= 1.0
