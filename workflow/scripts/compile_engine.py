"""Compile (or load from the numba cache) the engine kernel with a tiny run."""

from pathlib import Path

from bouncedisk.engine import EngineConfig, simulate_arrays
from bouncedisk.io.job_log import log_to

with log_to(snakemake.log[0]) as log:
    for torsion in (False, True):
        res = simulate_arrays(
            EngineConfig(
                e=0.3, omega_s=1.5, torsion=torsion, max_events=snakemake.params.events, traj_dt=0.1
            )
        )
        log.info("engine ready (torsion=%s): %s", torsion, res.status)
    Path(snakemake.output[0]).touch()
