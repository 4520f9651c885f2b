"""Compile (or load from the numba cache), with tiny runs, the engine kernel (axial and with
torsion), the ensemble reduction (``analysis.ensembles``) and the regime tests
(``analysis.observables``), which most jobs call: compiled here once, the later jobs load them
from the cache rather than several compiling the same function side by side. A function only one
job calls compiles in that job: the work-precision comparator, and the load rows
(``engine.loads``), which only the fit calls, so that the jobs waiting for this one start sooner."""

from pathlib import Path

from bouncedisk.analysis.observables import chatter_cycle, find_period
from bouncedisk.analysis.statistics import run_stats
from bouncedisk.engine import EngineConfig, simulate_arrays
from bouncedisk.io.job_log import log_to
from bouncedisk.model.scene import scene_from_mapping

#: A tiny loaded ensemble with restitution noise: its run reaches every compiled reduction.
WARM_SCENE = {
    "name": "compile",
    "parameters": {
        "e": 0.3,
        "omega_s": 1.5,
        "r_phi": 0.1,
        "psi": 0.0,
        "e_sigma": 1e-3,
        "load_torque": 0.1,
    },
    "effects": ["impacts", "contact", "torsion", "restitution_noise", "load"],
    "stop": {"time": 20.0},
    "ensemble": {"members": 1, "seed": 1},
    "stats": {"discard": 5.0},
    "outputs": {"events": False},
}

with log_to(snakemake.log[0]) as log:
    events = snakemake.params.events
    for torsion in (False, True):
        cfg = EngineConfig(e=0.3, omega_s=1.5, torsion=torsion, max_events=events, traj_dt=0.1)
        res = simulate_arrays(cfg)
        log.info("engine ready (torsion=%s): %s", torsion, res.status)
    ev = res.events
    tail = (ev["t"], ev["phase"], ev["v_rel"], ev["kind"], cfg.omega_s)
    cycle, period = chatter_cycle(*tail), find_period(*tail)
    log.info("regime tests ready: chatter cycle %s, period %s", cycle, period)
    stats = run_stats(scene_from_mapping(WARM_SCENE, source="compile_engine"))
    log.info("ensemble reduction ready: regime %s", stats.regime[0])
    Path(snakemake.output[0]).touch()
