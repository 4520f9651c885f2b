"""What accuracy costs in time: the exact engine against the comparator solvers."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..analysis.observables import circular_distance
from ..engine import EngineConfig, InitialState, simulate_arrays
from ..io.records import EventKind
from ..run.comparators import ivp_events, moreau_events


@dataclass(frozen=True)
class Case:
    """A test problem of the work–precision study."""

    name: str
    e: float
    omega_s: float
    init: InitialState | None
    n_events: int
    first: int  # impact times compared
    attractor: int  # tail impacts whose phases are compared (0: none)
    t_end: float = math.inf  # end of every run of the case


CASES = (
    Case("periodic (e = 0.3, omega_s = 1.5)", 0.3, 1.5, None, 240, 20, 2),
    Case(
        "chattering (e = 0.5, omega_s = 0.8)",
        0.5,
        0.8,
        InitialState(t=0.0, u=0.5, v=0.0),
        200,
        10,
        0,
        t_end=10.0,
    ),
)
IVP_TOLS = tuple(10.0**-k for k in range(3, 13))
MOREAU_STEPS = (1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5)
EXACT_TOLS = (1e-6, 1e-8, 1e-10, 1e-12, 1e-14)


def _cpu(fn: Callable[[], dict], min_time: float = 0.05) -> tuple[dict, float]:
    """Result and CPU seconds per call (repeated until ``min_time`` is spent)."""
    start = time.process_time()
    out = fn()
    el = time.process_time() - start
    if el >= min_time:
        return out, el
    n = 0
    start = time.process_time()
    while True:
        fn()
        n += 1
        el = time.process_time() - start
        if el >= min_time:
            return out, el / n


def _rest_time(ev: dict) -> float:
    """When the rotor comes to rest: the accumulation point (engine) or the last impact."""
    if len(ev["t"]) == 0:
        return math.nan
    chat = np.nonzero(ev["kind"] == EventKind.CHATTER)[0]
    return float(ev["t"][chat[0]]) if len(chat) else float(ev["t"][-1])


def _errors(case: Case, ev: dict, ref: dict) -> dict[str, float]:
    imp = ev["kind"] == EventKind.IMPACT
    rimp = ref["kind"] == EventKind.IMPACT
    t, rt = ev["t"][imp], ref["t"][rimp]
    n = min(case.first, len(rt))
    if len(t) < n:
        err = math.inf
    else:
        err = float(np.max(np.abs(t[:n] - rt[:n])))
    out = {"error": err, "phase_error": math.nan, "rest_error": math.nan}
    if case.attractor:
        k = case.attractor
        a = np.sort(ev["phase"][imp][-k:])
        b = np.sort(ref["phase"][rimp][-k:])
        if len(a) == k and len(ev["t"]) >= min(case.n_events, len(ref["t"])):
            out["phase_error"] = float(np.max(circular_distance(a, b)))
        else:
            out["phase_error"] = math.inf
    else:
        out["rest_error"] = abs(_rest_time(ev) - _rest_time(ref))
        out["error"] = max(out["error"], out["rest_error"])
    return out


def work_precision(
    cases=CASES,
    ivp_tols=IVP_TOLS,
    moreau_steps=MOREAU_STEPS,
    exact_tols=EXACT_TOLS,
    methods=("rk45", "dop853", "lsoda"),
    progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """The work–precision table (module docstring)."""
    rows = []
    for case in cases:
        init = case.init or InitialState()

        def exact(tol, case=case, init=init):
            return simulate_arrays(
                EngineConfig(
                    e=case.e,
                    omega_s=case.omega_s,
                    tol=tol,
                    max_events=case.n_events,
                    t_end=case.t_end,
                ),
                init,
            ).events

        ref = exact(1e-14)
        u0, v0 = init.u, init.v
        configs = [("exact", "tol", tol, lambda tol=tol: exact(tol)) for tol in exact_tols]
        for m in methods:
            configs += [
                (
                    f"solve_ivp {m.upper()}",
                    "rtol",
                    tol,
                    lambda m=m, tol=tol, case=case, init=init, u0=u0, v0=v0: ivp_events(
                        case.e, case.omega_s, m, tol, init.t, u0, v0, case.n_events, case.t_end
                    )[0],
                )
                for tol in ivp_tols
            ]
        configs += [
            (
                "Moreau-Jean",
                "h",
                h,
                lambda h=h, case=case, init=init, u0=u0, v0=v0: moreau_events(
                    case.e, case.omega_s, h, init.t, u0, v0, case.n_events, case.t_end
                )[0],
            )
            for h in moreau_steps
        ]
        for solver, knob, value, fn in configs:
            ev, cpu = _cpu(fn)
            err = _errors(case, ev, ref)
            rows.append(
                {
                    "case": case.name,
                    "solver": solver,
                    "knob": knob,
                    "value": value,
                    "cpu_s": cpu,
                    "n_impacts": int(np.sum(ev["kind"] == EventKind.IMPACT)),
                    **err,
                }
            )
            if progress:
                progress(
                    f"{case.name}: {solver} {knob}={value:g}: error {err['error']:.2e}, {cpu:.4g} s"
                )
    return pd.DataFrame(rows)


def work_precision_summary(table: pd.DataFrame, target: float = 1e-8) -> dict[str, float | bool]:
    """The study's two findings, as ratios from one run.

    ``speedup``: CPU time of the fastest solve_ivp configuration reaching ``target`` over that of
    the cheapest exact configuration reaching it (periodic case). ``dominates``: for every
    comparator configuration, the exact solver has a smaller error at no more CPU time (or at its
    cheapest setting, when that is cheaper still).
    """
    periodic = table[table["case"] == CASES[0].name]
    ivp = periodic[periodic["solver"].str.startswith("solve_ivp") & (periodic["error"] <= target)]
    ex = periodic[(periodic["solver"] == "exact") & (periodic["error"] <= target)]
    speedup = float(ivp["cpu_s"].min() / ex["cpu_s"].min()) if len(ivp) and len(ex) else math.nan
    dominated = True
    worst = ""
    for case, sub in table.groupby("case"):
        exact = sub[sub["solver"] == "exact"]
        for _, row in sub[sub["solver"] != "exact"].iterrows():
            within = exact[exact["cpu_s"] <= row["cpu_s"]]
            if len(within) == 0:
                within = exact.nsmallest(1, "cpu_s")
            best = float(within["error"].min())
            if not (best < row["error"] or best == 0.0):
                dominated = False
                worst = f"{case}: {row['solver']} {row['knob']}={row['value']:g}"
    return {
        "speedup_vs_fastest_ivp_at_1e-8": speedup,
        "exact_more_accurate_at_every_budget": dominated,
        "counterexample": worst,
    }
