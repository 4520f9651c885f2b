"""What statistics cost: the 95 % half-width of the mean rotor speed against CPU time.

For chaotic motion the statistic, not the trajectory, is what users need (docs/model.md "Long-run
statistics of chaotic motion"). The half-width of an ensemble mean shrinks like
``1/sqrt(members × duration)``; a single run's time average does not converge to anything
reproducible: it jumps when ``e`` moves by 1e-9. This study measures both.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence

import pandas as pd

from ..analysis.statistics import confidence_interval, run_stats
from ..analysis.sweeps import with_params
from ..model.scene import Ensemble, Scene

#: Step of ``e`` between the single runs (a change no experiment can resolve).
E_STEP = 1e-9


def _window(scene: Scene, duration: float, members: int) -> Scene:
    stop = dataclasses.replace(scene.stop, time=scene.initial.t + scene.stats.discard + duration)
    ens = Ensemble(members=members, seed=scene.ensemble.seed)
    return dataclasses.replace(scene, stop=stop, ensemble=ens)


def half_width_table(
    scene: Scene, members: Sequence[int], durations: Sequence[float]
) -> pd.DataFrame:
    """Half-width of the mean rotor speed's 95 % interval and the CPU time, per (members, duration).

    Each ensemble runs on one core; ``cpu_s`` is its process CPU time.
    """
    run_stats(_window(scene, float(min(durations)), 2), cores=1)  # warm-up: numba cache
    rows = []
    for d in durations:
        for k in members:
            sc = _window(scene, float(d), int(k))
            t0 = time.process_time()
            res = run_stats(sc, cores=1)
            cpu = time.process_time() - t0
            mean, low, high = confidence_interval(res.column("mean_omega"))
            rows.append(
                {
                    "members": int(k),
                    "duration": float(d),
                    "member_time": int(k) * float(d),
                    "cpu_s": cpu,
                    "mean_omega": mean,
                    "ci_low": low,
                    "ci_high": high,
                    "half_width": (high - low) / 2.0,
                }
            )
    return pd.DataFrame(rows)


def single_run_table(scene: Scene, runs: int, duration: float) -> pd.DataFrame:
    """Time-averaged rotor speed of single runs (no noise) at ``e + k·1e-9``, ``k < runs``."""
    base = dataclasses.replace(
        _window(scene, duration, 1),
        effects=scene.effects - {"restitution_noise"},
    )
    rows = []
    for k in range(runs):
        sc = with_params(base, e=scene.params.e + k * E_STEP)
        res = run_stats(sc, cores=1)
        m = res.members[0]
        rows.append(
            {
                "k": k,
                "e": sc.params.e,
                "de": k * E_STEP,
                "mean_omega": m.mean_omega,
                "n_chatter": m.n_chatter,
            }
        )
    return pd.DataFrame(rows)
