"""Reproduction checks of the paper's claims (``bouncedisk check``).

Each check reports the measured value, the expected one and pass/fail. With a results folder
(the pipeline's ``results/``) the checks read the built files; otherwise they run the needed
simulations in memory from the scenes below, which are the same as the pipeline's.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import observables as ob
from .datasets import open_simulation
from .engine import EngineConfig, InitialState, simulate_arrays
from .errors import InputError
from .runner import run_scene_arrays
from .scene import scene_from_mapping

SCENES = {
    "poincare_e03": {
        "name": "poincare_e03",
        "parameters": {"e": 0.3, "omega_s": 1.5},
        "effects": ["impacts", "contact"],
        "stop": {"impacts": 20000},
    },
    "poincare_e06": {
        "name": "poincare_e06",
        "parameters": {"e": 0.6, "omega_s": 1.5},
        "effects": ["impacts", "contact"],
        "stop": {"impacts": 20000},
    },
    "fig5": {
        "name": "fig5",
        "parameters": {"e": 0.6, "omega_s": 1.5, "r_phi": 0.01, "psi": 0.0},
        "effects": ["impacts", "contact", "torsion"],
        "stop": {"impacts": 300},
        "outputs": {"events": True, "trajectory": {"dt": 0.05}},
    },
}


def check_results_folder(path: str | Path) -> Path:
    """The results folder for ``check --results``, refused unless it holds the built runs.

    A CI that mistypes the folder must fail, not check freshly simulated runs instead.

    Raises
    ------
    InputError
        The folder is missing, is a file, or lacks one of ``simulations/<name>.nc`` the checks
        read (named in the message).
    """
    p = Path(path)
    if str(path).strip() == "":
        raise InputError("<arguments>", "--results", "is empty; give the pipeline's results folder")
    if not p.exists():
        raise InputError(str(path), "--results", "folder not found (build it with snakemake)")
    if not p.is_dir():
        raise InputError(str(path), "--results", "is a file, not the pipeline's results folder")
    missing = [n for n in SCENES if not (p / "simulations" / f"{n}.nc").is_file()]
    if missing:
        raise InputError(
            str(path),
            "--results",
            "holds no built results for "
            + ", ".join(f"simulations/{n}.nc" for n in missing)
            + " (build them with snakemake, or drop --results to simulate)",
        )
    return p


@dataclass(frozen=True)
class CheckResult:
    """One claim of the paper: what was measured, what was expected, and whether it holds."""

    claim: str
    measured: str
    expected: str
    passed: bool
    source: str


class _Source:
    """Events of a named run: from ``results/simulations/<name>.nc`` if present, else simulated."""

    def __init__(self, results: Path | None):
        self.results = results
        self.cache: dict[str, tuple[dict, np.ndarray | None, str]] = {}

    def get(self, name: str) -> tuple[dict, np.ndarray | None, str]:
        if name in self.cache:
            return self.cache[name]
        path = self.results / "simulations" / f"{name}.nc" if self.results else None
        if path is not None:
            if not path.is_file():
                raise InputError(str(path), "", "missing: the results folder lacks this run")
            ds = open_simulation(path)
            ev = {
                "t": ds["t_impact"].values,
                "phase": ds["phase"].values,
                "v_rel": ds["v_rel"].values,
                "kind": ds["kind"].values,
            }
            traj = None
            if "omega_rotor" in ds:
                traj = np.column_stack([ds["time"].values, ds["omega_rotor"].values])
            out = (ev, traj, str(path))
        else:
            res = run_scene_arrays(scene_from_mapping(SCENES[name], f"<built-in scene {name}>"))
            traj = res.traj[:, [0, 4]] if len(res.traj) else None
            out = (res.events, traj, f"simulated ({name} scene)")
        self.cache[name] = out
        return out


def _period_check(src: _Source) -> CheckResult:
    ev, _, where = src.get("poincare_e03")
    per = ob.find_period(
        ev["t"], ev["phase"], ev["v_rel"], ev["kind"], 1.5, max_period=16, tail=2000
    )
    measured = (
        "no period <= 16"
        if per is None
        else (
            f"{per.label}: {per.p} impacts per {per.q} stator periods, phases "
            + ", ".join(f"{x:.6f}" for x in per.phases)
        )
    )
    ok = per is not None and per.p == 2 and per.q == 2
    return CheckResult(
        "e = 0.3, omega_s = 1.5 settles on a period-2 orbit (paper §3, Fig. 3)",
        measured,
        "period-2: 2 impacts per 2 stator periods",
        ok,
        where,
    )


def _chaos_check(src: _Source) -> CheckResult:
    ev, _, where = src.get("poincare_e06")
    per = ob.find_period(
        ev["t"], ev["phase"], ev["v_rel"], ev["kind"], 1.5, max_period=16, tail=2000
    )
    lam, lam_t = ob.lyapunov_exponent(ev["t"], ev["phase"], ev["v_rel"], ev["kind"], 0.6, 1.5)
    ok = per is None and lam > 0.0
    measured = (
        f"{'no period <= 16' if per is None else per.label}; largest Lyapunov exponent "
        f"{lam:.4f} per impact ({lam_t:.4f} per unit time)"
    )
    return CheckResult(
        "e = 0.6, omega_s = 1.5 is chaotic (paper §3, Fig. 4)",
        measured,
        "no period <= 16 and Lyapunov exponent > 0",
        ok,
        where,
    )


def _settles(e: float, gamma: float, n: int, phase: float, events: int) -> bool:
    w = math.sqrt(gamma)
    res = simulate_arrays(
        EngineConfig(e=e, omega_s=w, max_events=events),
        InitialState(t=phase / w, u=math.sin(phase), v=math.pi * n / w),
    )
    ev = res.events
    per = ob.find_period(ev["t"], ev["phase"], ev["v_rel"], ev["kind"], w, max_period=4)
    return per is not None and per.p == 1 and per.q == n


def engine_existence_threshold(n: int, e: float, resolution: float = 2e-4) -> float:
    """Γ above which a run started at the period-n orbit's phase settles on it (bisection)."""
    g_n = ob.period_n_threshold(n, e)
    lo, hi = 0.9 * g_n, 1.1 * g_n
    while hi - lo > resolution:
        mid = 0.5 * (lo + hi)
        if _settles(e, mid, n, math.acos(min(1.0, g_n / mid)) + 1e-3, 20_000):
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def engine_doubling_threshold(e: float, resolution: float = 5e-4) -> float:
    """Γ at which the engine's period-1 orbit loses stability (bisection on long runs)."""
    g_pd = ob.period_doubling_threshold(1, e)

    def stable(gamma: float) -> bool:
        w = math.sqrt(gamma)
        phi, vp = ob.period_n_fixed_point(1, e, w)
        phi += 1e-4
        res = simulate_arrays(
            EngineConfig(e=e, omega_s=w, max_events=60_000),
            InitialState(t=phi / w, u=math.sin(phi), v=vp),
        )
        return float(np.ptp(res.events["phase"][-200:])) < 1e-7

    lo, hi = g_pd - 0.05, g_pd + 0.05
    while hi - lo > resolution:
        mid = 0.5 * (lo + hi)
        if stable(mid):
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _threshold_checks(_src: _Source) -> list[CheckResult]:
    out = []
    e = 0.3
    for n in (1, 2):
        g = engine_existence_threshold(n, e)
        ref = ob.period_n_threshold(n, e)
        out.append(
            CheckResult(
                f"period-{n} orbit exists from Gamma_{n} = {n}π(1-e)/(1+e), e = {e} (Holmes 1982)",
                f"engine: Gamma = {g:.5f}",
                f"{ref:.5f} (within 1e-3)",
                abs(g - ref) < 1e-3,
                "engine bisection from the orbit's phase",
            )
        )
    g = engine_doubling_threshold(e)
    ref = ob.period_doubling_threshold(1, e)
    out.append(
        CheckResult(
            "period-1 orbit doubles at sqrt(Gamma_1^2 + (2(1+e^2)/(1+e)^2)^2), e = 0.3 "
            "(Luck & Mehta 1993); omega_s = 1.5 (Gamma = 2.25) is past it",
            f"engine: Gamma = {g:.5f}",
            f"{ref:.5f} (within 1e-3) < 2.25",
            abs(g - ref) < 1e-3 and g < 2.25,
            "engine bisection near the fixed point",
        )
    )
    return out


def _rise_check(src: _Source) -> CheckResult:
    _, traj, where = src.get("fig5")
    if traj is None or len(traj) < 10:
        return CheckResult(
            "rotor speed rises as a first-order system with a ripple (Fig. 5)",
            "no trajectory",
            "trajectory with omega_rotor",
            False,
            where,
        )
    t, om = traj[:, 0], traj[:, 1]
    trend = ob.first_order_trend(t, om)
    resid = om - trend(t)
    r2 = 1.0 - float(np.var(resid) / np.var(om))
    ripple = trend.ripple_rms / abs(trend.steady)
    ok = r2 > 0.8 and trend.tau > 0 and 0.005 < ripple < 0.3 and t[-1] > 2 * trend.tau
    measured = (
        f"steady Omega = {trend.steady:.4g}, time constant {trend.tau:.4g}, "
        f"R^2 of the first-order trend {r2:.3f}, ripple RMS {100 * ripple:.2f}% of steady"
    )
    return CheckResult(
        "rotor speed after 300 collisions: first-order rise with a high-frequency ripple "
        "(paper §3, Fig. 5; e = 0.6, omega_s = 1.5, R_phi = 0.01, psi = 0)",
        measured,
        "R^2 > 0.8, ripple 0.5%-30% of steady, run longer than 2 time constants",
        ok,
        where,
    )


CHECKS: list[Callable[[_Source], CheckResult | list[CheckResult]]] = [
    _period_check,
    _chaos_check,
    _threshold_checks,
    _rise_check,
]


def run_checks(results: Path | None = None) -> list[CheckResult]:
    """Run every check; ``results`` is the pipeline's results folder (or None to simulate)."""
    src = _Source(results)
    out: list[CheckResult] = []
    for check in CHECKS:
        r = check(src)
        out.extend(r if isinstance(r, list) else [r])
    return out


def to_text(results: list[CheckResult]) -> str:
    """The checks for a terminal, ending with the plain 'N passed, N failed' line."""
    lines = []
    for r in results:
        lines.append(f"[{'PASS' if r.passed else 'FAIL'}] {r.claim}")
        lines.append(f"       measured: {r.measured}")
        lines.append(f"       expected: {r.expected}   ({r.source})")
    n = sum(r.passed for r in results)
    lines.append(f"{n} passed, {len(results) - n} failed")
    return "\n".join(lines)


def to_markdown(results: list[CheckResult]) -> str:
    """The checks as the Markdown table of ``results/reproduction.md``."""
    from .provenance import git_commit, utc_now

    rows = [
        "# Reproduction of the paper's claims",
        "",
        f"Generated {utc_now()} by `bouncedisk check` (git {git_commit()[:12]}).",
        "",
        "| claim | measured | expected | result | from |",
        "| --- | --- | --- | --- | --- |",
    ]
    for r in results:
        rows.append(
            f"| {r.claim} | {r.measured} | {r.expected} | "
            f"{'**pass**' if r.passed else '**FAIL**'} | {r.source} |"
        )
    n = sum(r.passed for r in results)
    rows += ["", f"{n} of {len(results)} checks pass."]
    return "\n".join(rows) + "\n"
