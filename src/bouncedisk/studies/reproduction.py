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

from ..analysis import observables as ob
from ..engine import EngineConfig, InitialState, simulate_arrays
from ..io.netcdf import open_checked, open_simulation
from ..io.records import TrajColumn
from ..model import stator
from ..model.errors import InputError
from ..run.runner import run_scene_arrays

#: The pipeline's scene files: the checks read the same scenes the pipeline runs.
SCENE_DIR = Path(__file__).resolve().parents[3] / "workflow" / "config" / "scenes"


def workflow_scene(name: str, scene_dir: Path | None = None):
    """The workflow's scene ``name`` (``workflow/config/scenes/<name>.yaml``).

    Raises
    ------
    InputError
        When the scene file is missing (the package runs outside the project's checkout).
    """
    from ..model.scene import load_scene

    return load_scene((scene_dir or SCENE_DIR) / f"{name}.yaml")


#: Members of the rotor-speed band of Fig. 5 when simulated here (the pipeline's ``bands``).
BAND_MEMBERS = 16
#: The built results the checks read (relative to the results folder).
RESULT_FILES = (
    "simulations/fig5.nc",
    "bands/fig5.nc",
    "stats/stats_e03.nc",
    "stats/stats_e06.nc",
    "stats/stats_locked.nc",
    "load/load_fig3.nc",
    "load/load_fig4.nc",
    "fit/prototype.nc",
)
#: The pipeline's load curves the checks read, and what is simulated without a results folder.
LOAD_CURVES = ("load_fig3", "load_fig4")
LOAD_SIMULATED = {
    "loads": "0:1.05:8",
    "resolution": 0.01,
    "overrides": ["ensemble.members=8", "stop.time=8000"],
}
#: The load curves whose stall torque is the momentum bound itself (Fig. 3's period-2 motor
#: holds its speed up to it); the others' must lie at or below it.
AT_BOUND = ("load_fig3",)
#: The refinement's resolution the pipeline asks for (workflow/config/config.yaml, twice).
RESOLUTION_SLACK = 0.01
#: What a check reads from a built file; a file without one is refused, naming it.
STATS_ATTRS = tuple(f"stats_{k}" for k in (
    "mean_omega", "mean_omega_ci95", "members", "regime", "period", "regime_fraction",
    "lyapunov", "lyapunov_ci95", "lyapunov_reset_fraction",
))  # fmt: skip
LOAD_VARIABLES = ("branch", "load_torque", "mean_omega", "mean_omega_ci95_low",
                  "mean_omega_ci95_high", "audit_residual_axial", "audit_residual_torsion")  # fmt: skip
LOAD_ATTRS = ("e",)


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
    missing = [f for f in RESULT_FILES if not (p / f).is_file()]
    if missing:
        raise InputError(
            str(path),
            "--results",
            "holds no built results for "
            + ", ".join(missing)
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
            res = run_scene_arrays(workflow_scene(name))
            traj = res.traj[:, [TrajColumn.T, TrajColumn.OMEGA]] if len(res.traj) else None
            out = (res.events, traj, f"simulated (scene {name}.yaml)")
        self.cache[name] = out
        return out

    def stats(self, name: str) -> tuple[dict, str]:
        """Ensemble statistics (:meth:`EnsembleStats.summary`) of a scene, and where they came from."""
        key = f"stats:{name}"
        if key in self.cache:
            return self.cache[key]
        path = self.results / "stats" / f"{name}.nc" if self.results else None
        if path is not None and path.exists():
            ds = open_checked(path, required=("mean_omega", "regime"),
                              required_attrs=STATS_ATTRS, what="statistics")  # fmt: skip
            out = (_summary_of(ds), str(path))
        else:
            from ..analysis.statistics import run_stats

            out = (run_stats(workflow_scene(name), cores=2).summary(), f"ensemble ({name}.yaml)")
        self.cache[key] = out
        return out

    def band(self, name: str) -> tuple[dict, np.ndarray, str]:
        """Per-member first-order trends of a band, and the mean-trend attributes."""
        key = f"band:{name}"
        if key in self.cache:
            return self.cache[key]
        path = self.results / "bands" / f"{name}.nc" if self.results else None
        if path is not None and path.exists():
            ds = open_checked(path, required=("trend_steady", "omega_mean"),
                              required_attrs=("mean_trend_r2",), what="band")  # fmt: skip
            where = str(path)
        else:
            from ..analysis.bands import omega_band

            ds = omega_band(workflow_scene(name), BAND_MEMBERS, seed=1, cores=2)
            where = f"ensemble band ({name}.yaml, {BAND_MEMBERS} members)"
        out = (dict(ds.attrs), ds["trend_steady"].values, where)
        self.cache[key] = out
        return out


def _load_curve(src: _Source, name: str) -> tuple[dict, str]:
    """The up branch of a load curve (loads, mean speed and its interval, stall torque) and the
    largest audit residuals of both branches."""
    key = f"load:{name}"
    if key in src.cache:
        return src.cache[key]
    path = src.results / "load" / f"{name}.nc" if src.results else None
    if path is not None and path.exists():
        ds = open_checked(path, required=LOAD_VARIABLES, required_attrs=LOAD_ATTRS,
                          what="load curve")  # fmt: skip
        if "up" not in [str(b) for b in ds["branch"].values]:
            raise InputError(str(path), "branch", "has no 'up' branch (not a load curve file?)")
        where = str(path)
    else:
        from ..model.scene import load_scene
        from .torque_speed import parse_loads, refined_torque_speed, to_dataset

        scene = load_scene(SCENE_DIR / f"{name}.yaml", LOAD_SIMULATED["overrides"])
        loads = parse_loads(LOAD_SIMULATED["loads"])
        curve = refined_torque_speed(scene, loads, LOAD_SIMULATED["resolution"], cores=2)
        ds = to_dataset(scene, curve, 0.0)
        where = f"load curve ({name}.yaml, {LOAD_SIMULATED['loads']}, refined, 8 members)"
    up = ds.sel(branch="up")
    out = {
        "loads": ds["load_torque"].values,
        "mean": up["mean_omega"].values,
        "low": up["mean_omega_ci95_low"].values,
        "high": up["mean_omega_ci95_high"].values,
        "residual": max(
            float(ds["audit_residual_axial"].max()), float(ds["audit_residual_torsion"].max())
        ),
        "stall": float(ds.attrs.get("stall_torque", math.nan)),
        "stall_ci95": [float(x) for x in np.ravel(ds.attrs.get("stall_torque_ci95", [np.nan] * 2))],
        "state": str(ds.attrs.get("stall_torque_state", "")),
        "e": float(ds.attrs["e"]),
        "window": _window_resolution(ds),
    }
    src.cache[key] = (out, where)
    return out, where


def _window_resolution(ds) -> float:
    """How far past the momentum bound a finite run's mean speed can stay positive.

    Past the bound the rotor decelerates at ``>= τ_L − 1`` (docs/model.md "The motor under
    load"), so a run started at ``Ω_0`` has a mean speed ``<= 0`` over its window from
    ``τ_L = 1 + Ω_0 / (discard + window/2)``; ``Ω_0`` is at most the up branch's largest mean
    speed (its interval's upper end). 0 when the file does not say its window.
    """
    discard, window = ds.attrs.get("stats_discard"), ds.attrs.get("stats_duration")
    if discard is None or window is None:
        return 0.0
    top = float(np.nanmax(ds.sel(branch="up")["mean_omega_ci95_high"].values))
    top = max(top, float(np.nanmax(ds.sel(branch="up")["mean_omega"].values)))
    return max(0.0, top) / (float(discard) + 0.5 * float(window))


def _stall_check(name: str, c: dict, where: str) -> CheckResult:
    """The stall torque against the momentum bound 1 (docs/model.md "The motor under load"):
    at it, within the window's resolution and the refinement's, for a motor that holds its
    speed up to it (:data:`AT_BOUND`); at or below it for the others. Not reached is a fail:
    the sweep must go past it."""
    e, stall, state = c["e"], c["stall"], c["state"] or "found"
    lo, hi = c["stall_ci95"]
    top = float(c["loads"][-1])
    if state != "found" or not math.isfinite(stall):
        shown = f"not found ({state or 'no root'}, loads up to {top:g})"
    else:
        shown = f"{stall:.4g} (95% interval [{lo:.4g}, {hi:.4g}])"
    res = f"window resolution {c['window']:.2g}"
    found = state == "found" and math.isfinite(stall) and math.isfinite(lo)
    if name in AT_BOUND:
        ok = found and lo <= 1.0 <= hi and hi <= 1.0 + c["window"] + RESOLUTION_SLACK
        expected = (f"1 in the interval, its upper end <= 1 + the {res} + "
                    f"{RESOLUTION_SLACK:g} (units of the friction torque)")  # fmt: skip
        claim = f"e = {e:g}: the motor stalls at the momentum bound (mean N = 1, docs/model.md)"
    else:
        ok = found and lo <= 1.0 + c["window"]
        expected = f"found, <= 1 + the {res} (units of the friction torque)"
        claim = f"e = {e:g}: stall torque within the momentum bound (mean N = 1, docs/model.md)"
    return CheckResult(claim, f"stall torque {shown}", expected, ok, where)


def _rises(c: dict) -> list[float]:
    """Loads up to the momentum bound 1 at which the up branch's mean speed lies above the
    previous load's 95 % interval by more than :data:`~.torque_speed.MATERIAL` of the curve's
    largest speed. Past the bound no speed is stationary (docs/model.md "The
    motor under load"): a run's mean speed there depends on the speed it started from."""
    from .torque_speed import MATERIAL

    loads, low, high = c["loads"], c["low"], c["high"]
    # a periodic orbit's interval has zero width, and a finite window's mean still depends on
    # the state a run started from: a rise counts when it is material, as for two branches
    slack = MATERIAL * max(abs(x) for x in [*low, *high])
    return [
        float(loads[k + 1])
        for k in range(len(loads) - 1)
        if loads[k + 1] <= 1.0 and low[k + 1] > high[k] + slack
    ]


def _load_checks(src: _Source) -> list[CheckResult]:
    """The motor under load (docs/model.md): the energy audit closes, the stall torque respects the
    momentum bound, and the speed falls (or stays, within its interval) as the load grows."""
    out = []
    for name in LOAD_CURVES:
        c, where = _load_curve(src, name)
        e = c["e"]
        out.append(CheckResult(
            f"e = {e:g}: the energy audit closes to round-off on every load (docs/model.md)",
            f"largest relative residual {c['residual']:.2g} over both balances, branches, loads",
            "<= 1e-9", c["residual"] <= 1e-9, where,
        ))  # fmt: skip
        out.append(_stall_check(name, c, where))
        rises = _rises(c)
        out.append(CheckResult(
            f"e = {e:g}: the mean speed does not rise with the load up to the momentum bound "
            "(up branch; past it no speed is stationary, docs/model.md)",
            "rises beyond the 95% intervals at loads " + (", ".join(f"{x:g}" for x in rises) or "none"),
            "none", not rises, where,
        ))  # fmt: skip
    return out


def _summary_of(ds) -> dict:
    """The statistics summary stored as ``stats_*`` attributes of a ``bouncedisk stats`` file."""
    out = {}
    for k, v in ds.attrs.items():
        if k.startswith("stats_"):
            v = v.tolist() if isinstance(v, np.ndarray) else v
            if isinstance(v, list):
                v = [None if (isinstance(x, float) and math.isnan(x)) else x for x in v]
            elif isinstance(v, float) and math.isnan(v):
                v = None
            out[k[len("stats_") :]] = v
    if out.get("period") == "none":
        out["period"] = None
    return out


def _ci(summary: dict, name: str) -> str:
    low, high = summary[f"{name}_ci95"]
    return f"{summary[name]:.4g} (95% CI [{low:.4g}, {high:.4g}], {summary['members']} members)"


def _period_check(src: _Source) -> CheckResult:
    st, where = src.stats("stats_e03")
    low, high = st["mean_omega_ci95"]
    width = high - low
    ok = st["regime"] == "periodic" and st["period"] == [2, 2] and st["regime_fraction"] == 1.0
    ok = ok and width <= 1e-6 * abs(st["mean_omega"])
    return CheckResult(
        "e = 0.3, omega_s = 1.5 settles on a period-2 orbit (paper §3, Fig. 3; "
        "docs/model.md 'Long-run statistics of chaotic motion')",
        f"regime {st['regime']} {st['period']} in {100 * st['regime_fraction']:.0f}% of "
        f"{st['members']} members; mean Omega {_ci(st, 'mean_omega')}",
        "periodic [2 impacts, 2 stator periods] in every member; interval of zero width",
        ok,
        where,
    )


def _chaos_check(src: _Source) -> CheckResult:
    st, where = src.stats("stats_e06")
    ok = st["lyapunov_ci95"][0] is not None and st["lyapunov_ci95"][0] > 0.0
    ok = ok and st["regime"] in ("chaotic", "chaotic-reinjection")
    return CheckResult(
        "e = 0.6, omega_s = 1.5 is chaotic (paper §3, Fig. 4; docs/model.md, Long-run statistics "
        "of chaotic motion)",
        f"regime {st['regime']} ({100 * st['regime_fraction']:.0f}% of members); Lyapunov "
        f"exponent between resets {_ci(st, 'lyapunov')} per impact",
        "chaotic, the 95% interval of the Lyapunov exponent above 0",
        ok,
        where,
    )


def _locked_check(src: _Source) -> CheckResult:
    st, where = src.stats("stats_locked")
    ok = st["regime"] == "chattering-periodic" and st["lyapunov_reset_fraction"] == 1.0
    return CheckResult(
        "e = 0.5, omega_s = 1.126 is a locked chattering cycle, not chaos (docs/model.md, Regimes)",
        f"regime {st['regime']} {st['period']} in {100 * st['regime_fraction']:.0f}% of "
        f"members; {100 * st['lyapunov_reset_fraction']:.0f}% reset every cycle (exponent -inf)",
        "chattering-periodic in the majority, every member's exponent -inf (reset)",
        ok,
        where,
    )


def settles_on_period(e: float, gamma: float, n: int, phase: float, events: int) -> bool:
    """Does a run started at ``phase`` with the period-n orbit's velocity ``T/2`` settle on it?"""
    w = math.sqrt(gamma)
    res = simulate_arrays(
        EngineConfig(e=e, omega_s=w, max_events=events),
        InitialState(t=phase / w, u=stator.position(phase), v=math.pi * n / w),
    )
    ev = res.events
    per = ob.find_period(ev["t"], ev["phase"], ev["v_rel"], ev["kind"], w, max_period=4)
    return per is not None and per.p == 1 and per.q == n


def _bisect(holds, lo: float, hi: float, resolution: float, holds_above: bool) -> float:
    """Midpoint of the bracket where ``holds(Γ)`` switches, narrowed to ``resolution``."""
    while hi - lo > resolution:
        mid = 0.5 * (lo + hi)
        if holds(mid) == holds_above:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def engine_existence_threshold(n: int, e: float, resolution: float = 2e-4) -> float:
    """Γ above which a run started at the period-n orbit's phase settles on it (bisection)."""
    g_n = ob.period_n_threshold(n, e)

    def settles(gamma: float) -> bool:
        return settles_on_period(e, gamma, n, math.acos(min(1.0, g_n / gamma)) + 1e-3, 20_000)

    return _bisect(settles, 0.9 * g_n, 1.1 * g_n, resolution, holds_above=True)


def period_one_is_stable(e: float, gamma: float) -> bool:
    """Does a run started 1e-4 off the period-1 fixed point stay on it (phases within 1e-7)?"""
    w = math.sqrt(gamma)
    phi, vp = ob.period_n_fixed_point(1, e, w)
    phi += 1e-4
    res = simulate_arrays(
        EngineConfig(e=e, omega_s=w, max_events=60_000),
        InitialState(t=phi / w, u=stator.position(phi), v=vp),
    )
    return float(np.ptp(res.events["phase"][-200:])) < 1e-7


def engine_doubling_threshold(e: float, resolution: float = 5e-4) -> float:
    """Γ at which the engine's period-1 orbit loses stability (bisection on long runs)."""
    g_pd = ob.period_doubling_threshold(1, e)

    def stable(gamma: float) -> bool:
        return period_one_is_stable(e, gamma)

    return _bisect(stable, g_pd - 0.05, g_pd + 0.05, resolution, holds_above=False)


def _threshold_checks(_src: _Source) -> list[CheckResult]:
    out = []
    e = 0.3
    for n in (1, 2):
        g = engine_existence_threshold(n, e)
        ref = ob.period_n_threshold(n, e)
        out.append(
            CheckResult(
                f"period-{n} orbit exists from Gamma_{n} = {n}π(1-e)/(1+e), e = {e} "
                "(Holmes 1982; docs/model.md, Classic results)",
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
            "(Luck & Mehta 1993; docs/model.md, Classic results); omega_s = 1.5 (Gamma = 2.25) is "
            "past it",
            f"engine: Gamma = {g:.5f}",
            f"{ref:.5f} (within 1e-3) < 2.25",
            abs(g - ref) < 1e-3 and g < 2.25,
            "engine bisection near the fixed point",
        )
    )
    return out


def _rise_check(src: _Source) -> CheckResult:
    _, traj, where = src.get("fig5")
    claim = (
        "rotor speed after 300 collisions: first-order rise with a high-frequency ripple "
        "(paper §3, Fig. 5; docs/user_guide/fitting.md; e = 0.6, omega_s = 1.5, R_phi = 0.01, "
        "psi = 0)"
    )
    if traj is None or len(traj) < 10:
        return CheckResult(claim, "no trajectory", "trajectory with omega_rotor", False, where)
    t, om = traj[:, 0], traj[:, 1]
    trend = ob.first_order_trend(t, om)
    ripple = trend.ripple_rms / abs(trend.steady)
    attrs, steady, band_where = src.band("fig5")
    from ..analysis.statistics import confidence_interval

    mean, low, high = confidence_interval(steady)
    r2 = float(attrs["mean_trend_r2"])
    long_run, lr_where = src.stats("stats_e06")
    ok = r2 > 0.8 and trend.tau > 0 and 0.005 < ripple < 0.3 and t[-1] > 2 * trend.tau
    ok = ok and low <= long_run["mean_omega_ci95"][1] and high >= long_run["mean_omega_ci95"][0]
    measured = (
        f"steady Omega of the members' first-order trends {mean:.4g} (95% CI [{low:.4g}, "
        f"{high:.4g}], {len(steady)} members), R^2 of the ensemble-mean trend {r2:.3f}; long-run "
        f"mean {_ci(long_run, 'mean_omega')}; one run's ripple RMS {100 * ripple:.2f}% of steady"
    )
    return CheckResult(
        claim,
        measured,
        "R^2 > 0.8, ripple 0.5%-30% of steady, run longer than 2 time constants, steady-speed "
        "interval overlapping the long-run ensemble mean's",
        ok,
        f"{where}; {band_where}; {lr_where}",
    )


#: The pipeline's joint fit of the prototype (run-up and load curve), read by :func:`_fit_checks`.
FIT_FILE = "fit/prototype.nc"
#: Fewest readings of the load curve within the fitted members' 95 % band (13 readings: 11).
FIT_IN_BAND = 0.8
#: What the fit checks read from the fit file; a file without one is refused, naming it.
FIT_VARIABLES = ("load_speed_measured", "load_speed_band_low", "load_speed_band_high",
                 "interval_low", "interval_high", "interval_identified", "search_low",
                 "search_high", "data_set", "parameter")  # fmt: skip
FIT_ATTRS = ("chi2", "n_statistics", "chi2_p_value", "fit_adequate")


def _fit_checks(src: _Source) -> list[CheckResult]:
    """The joint fit (docs/user_guide/fitting.md): the model fitted to the run-up and the load curve together
    reproduces the load curve and pins every parameter. Read from the pipeline's fit file; a run
    without ``--results`` has no fit to read (a fit takes minutes), and a run-up-only fit no load
    curve: both skip it."""
    if src.results is None:
        return []
    path = src.results / FIT_FILE
    if not path.is_file():
        raise InputError(str(path), "", "missing: the results folder lacks the prototype's fit")
    ds = open_checked(path, required=("omega_measured",), what="fit")
    if "load_speed_measured" not in ds:
        return []  # a run-up-only fit (the config names no load curve): no joint fit to check
    ds = open_checked(path, required=FIT_VARIABLES, required_attrs=FIT_ATTRS, what="fit")
    if "both" not in [str(d) for d in ds["data_set"].values]:
        raise InputError(str(path), "data_set", "has no 'both' row (not a joint fit file?)")
    y = ds["load_speed_measured"].values
    inside = (y >= ds["load_speed_band_low"].values) & (y <= ds["load_speed_band_high"].values)
    frac = float(np.mean(inside))
    a = ds.attrs
    both = list(ds["data_set"].values).index("both")
    return [
        CheckResult(
            "the model fitted to the run-up and the load curve together reproduces the load "
            "curve (docs/user_guide/fitting.md)",
            f"{100 * frac:.0f}% of {len(y)} readings within the fitted members' 95% band; joint "
            f"chi2 {a['chi2']:.4g} on {a['n_statistics']} statistics (p = {a['chi2_p_value']:.2g})",
            f">= {100 * FIT_IN_BAND:.0f}% within the band, fit adequate (p > 1e-3)",
            frac >= FIT_IN_BAND and bool(a["fit_adequate"]), str(path),
        ),
        _identifiability_check(ds, both, str(path)),
    ]  # fmt: skip


def _identifiability_check(ds, both: int, where: str) -> CheckResult:
    """Every joint interval two-sided, inside the search range, and, when the data are synthetic
    (the sidecar states the generating values: ``generating_value``), holding the generating
    value. A NaN interval (an inadequate fit writes them) is not identified."""
    names = [str(n) for n in ds["parameter"].values]
    lo, hi = ds["interval_low"].values[both], ds["interval_high"].values[both]
    ids = ds["interval_identified"].values[both]
    s_lo, s_hi = ds["search_low"].values, ds["search_high"].values
    gen = ds["generating_value"].values if "generating_value" in ds else np.full(len(names), np.nan)
    synthetic = bool(np.isfinite(gen).any())
    fails = []
    for j, n in enumerate(names):
        if not (np.isfinite(lo[j]) and np.isfinite(hi[j]) and ids[j]):
            fails.append(f"{n} not identified")
        elif not (s_lo[j] < lo[j] and hi[j] < s_hi[j]):
            fails.append(f"{n} reaches the search range's end")
        elif synthetic and not (np.isfinite(gen[j]) and lo[j] <= gen[j] <= hi[j]):
            fails.append(f"{n} excludes its generating value {gen[j]:.4g}")
    measured = ", ".join(f"{n} [{lo[j]:.4g}, {hi[j]:.4g}]" for j, n in enumerate(names))
    if synthetic:
        measured += "; generating " + ", ".join(f"{n} {gen[j]:.4g}" for j, n in enumerate(names))
    if fails:
        measured += " (" + "; ".join(fails) + ")"
    expected = "identified and strictly inside the search range, each"
    expected += ", holding the generating value (synthetic data)" if synthetic else ""
    return CheckResult(
        "the run-up and the load curve together identify the motor: every parameter has a "
        "two-sided 95% interval inside its search range (docs/user_guide/fitting.md)",
        measured, expected, not fails, where,
    )  # fmt: skip


def _basins_check(src: _Source) -> CheckResult:
    """The closed case of the basins (:func:`bouncedisk.studies.basins.closed_case`)."""
    from .basins import closed_case

    return CheckResult(*closed_case(src.results, lambda: workflow_scene("basins_fig3")))


CHECKS: list[Callable[[_Source], CheckResult | list[CheckResult]]] = [
    _period_check,
    _chaos_check,
    _locked_check,
    _threshold_checks,
    _rise_check,
    _load_checks,
    _basins_check,
    _fit_checks,
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
    from ..io.provenance import git_commit, utc_now

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
