"""Scaling measurements: events per second and peak memory against the run's length."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import pandas as pd

from ..engine import EngineConfig, iterate
from ..model.params import NATURAL_E_SIGMA


# ------------------------------------------------------------------------------------ scaling
def _stream(cfg: EngineConfig) -> int:
    """Run ``cfg`` chunk by chunk, dropping the output; returns the number of events.

    Memory stays at one chunk whatever the run's size, where a run collected in memory holds
    every sample of its trajectory (eight bytes per column and sample) and more while the
    chunks are joined.
    """
    n = 0
    for chunk in iterate(cfg):
        n += len(chunk.t)
    return n


def _rate(cfg: EngineConfig, repeat: int = 2) -> tuple[float, int]:
    """Best wall time of ``repeat`` streamed runs of ``cfg`` (after a warm-up), and its events."""
    _stream(EngineConfig(**{**cfg.__dict__, "max_events": 10, "t_end": math.inf}))
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        n = _stream(cfg)
        best = min(best, time.perf_counter() - t0)
    return best, n


def _rate_row(study: str, cfg: EngineConfig, repeat: int = 2, **labels: str) -> dict:
    """One row of the scaling table: :func:`_rate` of ``cfg``, per run and per impact."""
    sec, n = _rate(cfg, repeat)
    return {
        "study": study,
        **labels,
        "e": cfg.e,
        "omega_s": cfg.omega_s,
        "n_impacts": n,
        "seconds": sec,
        "s_per_impact": sec / n,
    }


def peak_memory_mb(n_events: int, e: float = 0.6, omega_s: float = 1.5) -> float:
    """Peak RSS (MB) of a fresh process streaming an events-only run of ``n_events`` to netCDF.

    The child (``python -m bouncedisk.run.memory_probe``, the same interpreter and the same
    package as this process) runs :func:`bouncedisk.run.memory_probe.stream_events_peak_mb` and
    reports its own ``VmHWM`` (``ru_maxrss`` would include this process's high-water mark, which Linux keeps
    across fork and exec). Its file goes to a temporary folder, removed whatever happens.

    Raises
    ------
    RuntimeError
        The child failed (its last line of error output is in the message) or was killed.
    """
    request = {"n_events": n_events, "e": e, "omega_s": omega_s}
    src = str(Path(__file__).resolve().parents[2])
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join(filter(None, [src, os.environ.get("PYTHONPATH")])),
    }
    with tempfile.TemporaryDirectory(prefix="bouncedisk-memory-") as folder:
        request["out"] = os.path.join(folder, "mem.nc")
        proc = subprocess.run(
            [sys.executable, "-m", "bouncedisk.run.memory_probe"],
            input=json.dumps(request),
            capture_output=True,
            text=True,
            env=env,
        )
    if proc.returncode != 0:
        lines = proc.stderr.strip().splitlines()
        why = lines[-1] if lines else "no error output"
        if proc.returncode < 0:
            why = f"killed by signal {-proc.returncode} (out of memory?); {why}"
        raise RuntimeError(
            f"peak memory of {n_events} impacts (e = {e}, omega_s = {omega_s}): "
            f"the child process failed with status {proc.returncode}: {why}"
        )
    return float(json.loads(proc.stdout.strip().splitlines()[-1])["peak_mb"])


def scaling(
    *,
    omegas: Sequence[float],
    per_omega: int,
    sizes: Sequence[int],
    memory_sizes: Sequence[int],
    effect_events: int,
    progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """The scaling table (module docstring); one row per measurement, ``study`` says which.

    The sizes have no defaults: the pipeline passes its config's ``accuracy.scaling`` (the one
    place they are set) and ``benchmarks/bench_accuracy.py`` starts from the same keys.
    """
    rows = []
    for w in omegas:
        row = _rate_row("omega", EngineConfig(e=0.3, omega_s=w, max_events=per_omega))
        rows.append(row)
        if progress:
            progress(f"omega_s = {w:g}: {1e9 * row['s_per_impact']:.0f} ns per impact")
    for n_ev in sizes:
        row = _rate_row("impacts", EngineConfig(e=0.6, omega_s=1.5, max_events=n_ev), repeat=1)
        rows.append(row)
        if progress:
            progress(f"{n_ev} impacts: {row['seconds']:.4g} s")
    for n_ev in memory_sizes:
        mb = peak_memory_mb(n_ev)
        rows.append({"study": "memory", "e": 0.6, "omega_s": 1.5, "n_impacts": n_ev, "peak_mb": mb})
        if progress:
            progress(f"{n_ev} impacts streamed: peak {mb:.0f} MB")
    effects = {
        "axial only": dict(torsion=False),
        "+ torsion": dict(torsion=True, r_phi=0.01),
        "+ torsion + restitution noise": dict(torsion=True, r_phi=0.01, e_sigma=NATURAL_E_SIGMA),
        "+ torsion + trajectory (dt = 0.01)": dict(torsion=True, r_phi=0.01, traj_dt=0.01),
    }
    for label, kw in effects.items():
        cfg = EngineConfig(e=0.6, omega_s=1.5, max_events=effect_events, **kw)
        row = _rate_row("effects", cfg, effect=label)
        rows.append(row)
        if progress:
            progress(f"{label}: {1e9 * row['s_per_impact']:.0f} ns per impact")
    return pd.DataFrame(rows)
