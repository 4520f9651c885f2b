"""What one axial run per member saves the fit: the points at one ``(e, omega_s)`` together.

The axial motion depends on neither ``R_φ`` nor ``ψ`` (docs/model.md "Events"), so the fit's
points that share ``(e, omega_s)`` (the scan's ψ grid, its matched points, a least-squares step
with the points its Jacobian reads) take their samples from one axial run per member
(``bouncedisk.engine.loads.row_trajectories``, ``Objective.prefetch``). Measured in one run:

1. The engine: 8 and 3 runs differing in ``(R_φ, ψ)`` (a ψ grid; a step and its two
   differences) one by one against one axial run, in four regimes of the fit's range; each
   row's samples checked equal, bit for bit. Best of 3 wall times.
2. Whole fits with the points evaluated together and one by one (every point its own runs):
   wall and CPU time of each, and the same ``χ²``, estimate and intervals.
   The shipped motor's joint fit at the pipeline's settings (``--scan 64 --zoom 0 --e-sigma 0.03
   --cores 2``: its scan is a small share of it), and the fit of its run-up alone at the default
   search (scan 192, zoom 16: the scan is most of it).

Run:  python benchmarks/bench_fit_rows.py [--record]
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import math
import time

import numpy as np

from bouncedisk.engine import InitialState, simulate_arrays
from bouncedisk.engine.loads import row_trajectories
from bouncedisk.fitting import FitSettings, fit_curve
from bouncedisk.fitting import objective as objective_module
from bouncedisk.fitting.members import member_records
from bouncedisk.fitting.summary_stats import EnsembleStats, records_stats
from bouncedisk.io.load_curves import read_load_curve
from bouncedisk.io.runup_curves import read_curve
from bouncedisk.model.engine_config import motor_config

#: Regimes of the fit's range: (label, e, omega_s), the recovery cases' and a chattering one.
REGIMES = [("period 1", 0.31, 1.37), ("chaotic, reinjection", 0.62, 1.48),
           ("near the period doubling", 0.33, 1.40), ("chattering", 0.8, 2.5)]  # fmt: skip
#: A run-up of 0.06 s at 15 kHz and omega_s ~1.4: about 4,000 time units, a sample every 1.7.
SPAN, DT = 4000.0, 1.7


def _best(fn, repeats: int = 3) -> float:
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def engine_rows() -> list[tuple[str, str]]:
    """Part 1: one axial run for 8 and 3 rows against a run each."""
    rows = []
    init = InitialState(t=0.0, omega=0.0)
    for label, e, w in REGIMES:
        for n in (8, 3):
            cfgs = [motor_config(e, w, 10.0 ** (-2.5 + 0.1 * k), psi, t_end=SPAN, traj_dt=DT,
                                 traj_t0=0.0, traj_t1=SPAN, max_events=50_000_000,
                                 e_sigma=0.03, seed=5, member=3)
                    for k, psi in enumerate(np.linspace(-math.pi, math.pi, n, endpoint=False))]  # fmt: skip
            alone = [simulate_arrays(c, init).traj for c in cfgs]
            together = row_trajectories(cfgs, init)
            assert all(np.array_equal(a, b) for a, b in zip(alone, together, strict=True))
            t_one = _best(lambda cfgs=cfgs: [simulate_arrays(c, init) for c in cfgs])
            t_rows = _best(lambda cfgs=cfgs: row_trajectories(cfgs, init))
            rows.append((f"{label} (e {e}, omega_s {w}), {n} runs of (R_phi, psi)",
                         f"{1e3 * t_one:.1f} ms one by one, {1e3 * t_rows:.1f} ms together: "
                         f"{t_one / t_rows:.2f}x; samples equal bit for bit"))  # fmt: skip
    return rows


@contextlib.contextmanager
def one_by_one():
    """The objective as before: every point its own runs, nothing evaluated ahead."""
    cls = objective_module.Objective
    saved = cls.prefetch, cls.ensemble

    def ensemble(self, x, members=None):
        k = members or self.members
        x = objective_module.snap(x)
        key = (k, *x)
        if key not in self.cache:
            spec = dataclasses.replace(self.spec, cores=1) if self.points_parallel else self.spec
            recs = member_records(self.theta(x), self.curve, range(k), spec)
            self.cache[key] = EnsembleStats.from_values(records_stats(np.array(recs), self.layout))
        self.read.add(key)
        return self.cache[key]

    cls.prefetch, cls.ensemble = (lambda self, xs, members=None: None), ensemble
    try:
        yield
    finally:
        cls.prefetch, cls.ensemble = saved


def timed_fit(joint: bool) -> tuple[float, float, object]:
    """The shipped motor's joint fit at the pipeline's settings (``joint``), or its run-up's
    alone at the default search: wall s, CPU s, result."""
    curve = read_curve("data/prototype/synthetic_motor.csv")
    load = [read_load_curve("data/prototype/synthetic_motor_load.csv")] if joint else None
    search = {"scan": 64, "zoom": 0} if joint else {}
    s = FitSettings(seed=20261121, bootstrap=40, e_sigma=0.03, cores=2, **search)
    wall, cpu = time.perf_counter(), time.process_time()
    fit = fit_curve(curve, s, load=load)
    return time.perf_counter() - wall, time.process_time() - cpu, fit


#: The fits of part 2: (label, joint).
FITS = [("the joint fit of the shipped motor, pipeline settings (`--scan 64 --zoom 0 "
         "--e-sigma 0.03 --cores 2`)", True),
        ("the fit of the shipped run-up alone, default search (scan 192, zoom 16, "
         "`--e-sigma 0.03 --cores 2`)", False)]  # fmt: skip


def fit_rows() -> list[tuple[str, str]]:
    """Part 2: whole fits, points together and one by one."""
    rows = []
    for label, joint in FITS:
        w_new, c_new, new = timed_fit(joint)
        with one_by_one():
            w_old, c_old, old = timed_fit(joint)
        assert new.chi2 == old.chi2 and np.array_equal(new.x, old.x), (new.chi2, old.chi2)
        for a, b in zip(new.profiles, old.profiles, strict=True):
            assert (a.ci_low, a.ci_high) == (b.ci_low, b.ci_high), a.name
        rows.append((f"{label}: points at one (e, omega_s) together / one by one (the version "
                     "before), the same chi2, estimate and intervals",
                     f"{w_new:.1f} / {w_old:.1f} s wall ({w_old / w_new:.2f}x), {c_new:.1f} / "
                     f"{c_old:.1f} s CPU ({c_old / c_new:.2f}x); chi2 {new.chi2:.4g}"))  # fmt: skip
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--record", action="store_true", help="write benchmarks/out/fit_rows.json")
    args = ap.parse_args()
    rows = engine_rows() + fit_rows()
    for m, r in rows:
        print(f"{m}: {r}", flush=True)
    if args.record:
        from record import write_record

        write_record("fit_rows", "The fit: points at one (e, omega_s) from one axial run", rows)


if __name__ == "__main__":
    main()
