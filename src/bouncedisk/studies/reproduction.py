"""Reproduction checks of the paper's claims (``bouncedisk check``).

Each check reports the measured value, the expected one and pass/fail. With a results folder
(the pipeline's ``results/``) the checks read the built files; otherwise they run the needed
simulations in memory from the scenes the package ships (``bouncedisk/scenes``, the pipeline's
``workflow/config/scenes``). Each claim is judged on numbers recomputed from the arrays it is
about (the members of an ensemble, a run's trajectory, a fit's readings and intervals,
:mod:`bouncedisk.studies.check_inputs`); a stored attribute that disagrees with them fails the
claim, named beside it. The physics the checks need is measured elsewhere
(:mod:`bouncedisk.studies.thresholds`): this module only compares.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path

import numpy as np

from ..analysis import observables as ob
from ..io.netcdf import open_checked, open_simulation
from ..io.records import TrajColumn
from ..model.errors import InputError
from ..run.runner import run_scene_arrays
from . import check_inputs as inp
from . import thresholds
from .reproduction_files import (  # noqa: F401  (SCENE_DIR, STATS_SCENES: the checks' API)
    FIT_FILE,
    LOAD_CURVES,
    RESULT_FILES,
    SCENE_DIR,
    STATS_SCENES,
    scene_file,
)


def workflow_scene(name: str, overrides: list[str] | None = None):
    """The shipped scene ``name`` (``bouncedisk/scenes/<name>.yaml``), with ``overrides``.

    Raises
    ------
    InputError
        When the package ships no such scene.
    """
    from ..model.scene import load_scene

    path = scene_file(name)
    if not path.is_file():
        raise InputError(str(path), "", "missing: the package ships no such scene")
    with resources.as_file(path) as real:
        return load_scene(real, overrides)


#: Members of the rotor-speed band of Fig. 5 when simulated here (the pipeline's ``bands``).
BAND_MEMBERS = 16
#: What is simulated for a load curve without a results folder.
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


def check_results_folder(path: str | Path) -> Path:
    """The results folder for ``check --results``, refused unless it holds the built runs.

    A CI that mistypes the folder must fail, not check freshly simulated runs instead.

    Raises
    ------
    InputError
        The folder is missing, is a file, or lacks one of :data:`RESULT_FILES` (named in the
        message).
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


def audited(result: CheckResult, notes: list[str]) -> CheckResult:
    """``result`` failed, with ``notes`` (a file's attributes that disagree with its arrays,
    fields it lacks) beside its measurement; unchanged without notes."""
    if not notes:
        return result
    return replace(result, passed=False, measured=f"{result.measured}; " + "; ".join(notes))


class _Source:
    """The runs the checks read: from ``results/`` if given, else simulated."""

    def __init__(self, results: Path | None, joint_fit: bool | None = None):
        self.results = results
        #: Whether the results hold a joint fit of the prototype (None: unknown)
        self.joint_fit = joint_fit
        self.cache: dict[str, tuple] = {}

    def get(self, name: str) -> tuple[dict, np.ndarray | None, str]:
        """Events and ``(t, Ω)`` trajectory (None without one) of a single run."""
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
                t, om = (inp.array(ds, str(path), v) for v in ("time", "omega_rotor"))
                traj = np.column_stack([t, om])
            out = (ev, traj, str(path))
        else:
            res = run_scene_arrays(workflow_scene(name))
            traj = res.traj[:, [TrajColumn.T, TrajColumn.OMEGA]] if len(res.traj) else None
            out = (res.events, traj, f"simulated (scene {name}.yaml)")
        self.cache[name] = out
        return out

    def stats(self, name: str) -> tuple[dict, str, list[str]]:
        """Ensemble statistics of a scene (:data:`check_inputs.STATS_FIELDS`) recomputed from
        its members, where they came from, and the file's attributes that disagree."""
        key = f"stats:{name}"
        if key in self.cache:
            return self.cache[key]
        path = self.results / "stats" / f"{name}.nc" if self.results else None
        if path is not None and path.exists():
            ds = open_checked(
                path,
                required=inp.STATS_VARIABLES,
                required_attrs=inp.STATS_ATTRS,
                what="statistics",
            )
            summary, notes = inp.stats_from_file(ds, str(path))
            out = (summary, str(path), notes)
        else:
            from ..analysis.statistics import run_stats

            st = inp.stats_summary(run_stats(workflow_scene(name), cores=2))
            out = (st, f"ensemble ({name}.yaml)", [])
        self.cache[key] = out
        return out

    def band(self, name: str) -> tuple[dict, str, list[str]]:
        """A band's per-member trends, its mean's trend ``R²`` recomputed from the mean, the
        central 95 % of its members over time, and its attributes that disagree."""
        key = f"band:{name}"
        if key in self.cache:
            return self.cache[key]
        path = self.results / "bands" / f"{name}.nc" if self.results else None
        if path is not None and path.exists():
            ds = open_checked(
                path, required=BAND_VARIABLES, required_attrs=("mean_trend_r2",), what="band"
            )
            where = str(path)
        else:
            from ..analysis.bands import omega_band

            ds = omega_band(workflow_scene(name), BAND_MEMBERS, seed=1, cores=2)
            where = f"ensemble band ({name}.yaml, {BAND_MEMBERS} members)"
        out, notes = band_from(ds, where)
        self.cache[key] = (out, where, notes)
        return self.cache[key]


#: What the rise check reads from a band file (docs/formats.md "Other files of the pipeline").
BAND_VARIABLES = ("time", "omega_mean", "omega_p025", "omega_p975", "trend_steady")


def band_from(ds, where: str) -> tuple[dict, list[str]]:
    """A band's arrays, its mean's first-order ``R²`` recomputed, and the stored ``R²`` when
    it disagrees."""
    from ..analysis.bands import mean_trend_fit

    t, mean = inp.array(ds, where, "time"), inp.array(ds, where, "omega_mean")
    _, r2 = mean_trend_fit(t, mean)
    out = {
        "time": t,
        "r2": r2,
        "steady": inp.array(ds, where, "trend_steady"),
        "p025": inp.array(ds, where, "omega_p025"),
        "p975": inp.array(ds, where, "omega_p975"),
    }
    stored = {"mean_trend_r2": inp.number(ds.attrs, where, "mean_trend_r2")}
    return out, inp.disagreements(stored, {"mean_trend_r2": r2})


def _load_curve(src: _Source, name: str) -> tuple[dict, str, list[str]]:
    """The up branch of a load curve recomputed from its members (:func:`check_inputs.load_from_file`),
    where it came from, and the file's numbers that disagree."""
    key = f"load:{name}"
    if key in src.cache:
        return src.cache[key]
    path = src.results / "load" / f"{name}.nc" if src.results else None
    if path is not None and path.exists():
        ds = open_checked(
            path, required=inp.LOAD_VARIABLES, required_attrs=inp.LOAD_ATTRS, what="load curve"
        )
        where = str(path)
    else:
        from .torque_speed import parse_loads, refined_torque_speed, to_dataset

        scene = workflow_scene(name, LOAD_SIMULATED["overrides"])
        loads = parse_loads(LOAD_SIMULATED["loads"])
        curve = refined_torque_speed(scene, loads, LOAD_SIMULATED["resolution"], cores=2)
        ds = to_dataset(scene, curve, 0.0)
        where = f"load curve ({name}.yaml, {LOAD_SIMULATED['loads']}, refined, 8 members)"
    c, notes = inp.load_from_file(ds, where)
    c["window"] = window_resolution(c)
    src.cache[key] = (c, where, notes)
    return src.cache[key]


def window_resolution(c: dict) -> float:
    """How far past the momentum bound a finite run's mean speed can stay positive.

    Past the bound the rotor decelerates at ``>= τ_L − 1`` (docs/model.md "The motor under
    load"), so a run started at ``Ω_0`` has a mean speed ``<= 0`` over its window from
    ``τ_L = 1 + Ω_0 / (discard + window/2)``; ``Ω_0`` is at most the up branch's largest mean
    speed (its interval's upper end). 0 when the window is not finite.
    """
    discard, window = c["discard"], c["duration"]
    if not (math.isfinite(discard) and math.isfinite(window)) or discard + window <= 0:
        return 0.0
    top = max(float(np.nanmax(c["high"], initial=0.0)), float(np.nanmax(c["mean"], initial=0.0)))
    return max(0.0, top) / (discard + 0.5 * window)


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
    found = found and lo <= stall <= hi
    if name in AT_BOUND:
        ok = found and lo <= 1.0 <= hi and hi <= 1.0 + c["window"] + RESOLUTION_SLACK
        expected = (
            f"1 in the interval, its upper end <= 1 + the {res} + "
            f"{RESOLUTION_SLACK:g} (units of the friction torque)"
        )
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
    slack = MATERIAL * float(np.nanmax(np.abs([*low, *high]), initial=0.0))
    return [
        float(loads[k + 1])
        for k in range(len(loads) - 1)
        if loads[k + 1] <= 1.0 and low[k + 1] > high[k] + slack
    ]


def _load_checks(src: _Source, names: tuple[str, ...] = LOAD_CURVES) -> list[CheckResult]:
    """The motor under load (docs/model.md): the energy audit closes, the stall torque respects the
    momentum bound, and the speed falls (or stays, within its interval) as the load grows; for
    the load curves ``names``."""
    out = []
    for name in names:
        c, where, notes = _load_curve(src, name)
        e = c["e"]
        out.append(
            CheckResult(
                f"e = {e:g}: the energy audit closes to round-off on every load (docs/model.md)",
                f"largest relative residual {c['residual']:.2g} over both balances, branches, loads",
                "<= 1e-9",
                c["residual"] <= 1e-9,
                where,
            )
        )
        out.append(audited(_stall_check(name, c, where), notes))
        rises = _rises(c)
        out.append(
            audited(
                CheckResult(
                    f"e = {e:g}: the mean speed does not rise with the load up to the momentum bound "
                    "(up branch; past it no speed is stationary, docs/model.md)",
                    "rises beyond the 95% intervals at loads "
                    + (", ".join(f"{x:g}" for x in rises) or "none"),
                    "none",
                    not rises,
                    where,
                ),
                notes,
            )
        )
    return out


def _ci(summary: dict, name: str) -> str:
    low, high = summary[f"{name}_ci95"]
    return f"{summary[name]:.4g} (95% CI [{low:.4g}, {high:.4g}], {summary['members']} members)"


def _period_check(src: _Source) -> CheckResult:
    st, where, notes = src.stats("stats_e03")
    low, high = st["mean_omega_ci95"]
    width = high - low
    ok = st["regime"] == "periodic" and st["period"] == [2, 2] and st["regime_fraction"] == 1.0
    ok = ok and width <= 1e-6 * abs(st["mean_omega"])
    return audited(
        CheckResult(
            "e = 0.3, omega_s = 1.5 settles on a period-2 orbit (paper §3, Fig. 3; "
            "docs/model.md 'Long-run statistics of chaotic motion')",
            f"regime {st['regime']} {st['period']} in {100 * st['regime_fraction']:.0f}% of "
            f"{st['members']} members; mean Omega {_ci(st, 'mean_omega')}",
            "periodic [2 impacts, 2 stator periods] in every member; interval of zero width",
            ok,
            where,
        ),
        notes,
    )


def _chaos_check(src: _Source) -> CheckResult:
    st, where, notes = src.stats("stats_e06")
    ok = st["lyapunov_ci95"][0] > 0.0  # False for nan
    ok = ok and st["regime"] in ("chaotic", "chaotic-reinjection")
    return audited(
        CheckResult(
            "e = 0.6, omega_s = 1.5 is chaotic (paper §3, Fig. 4; docs/model.md, Long-run statistics "
            "of chaotic motion)",
            f"regime {st['regime']} ({100 * st['regime_fraction']:.0f}% of members); Lyapunov "
            f"exponent between resets {_ci(st, 'lyapunov')} per impact",
            "chaotic, the 95% interval of the Lyapunov exponent above 0",
            ok,
            where,
        ),
        notes,
    )


def _locked_check(src: _Source) -> CheckResult:
    st, where, notes = src.stats("stats_locked")
    ok = st["regime"] == "chattering-periodic" and st["lyapunov_reset_fraction"] == 1.0
    return audited(
        CheckResult(
            "e = 0.5, omega_s = 1.126 is a locked chattering cycle, not chaos (docs/model.md, Regimes)",
            f"regime {st['regime']} {st['period']} in {100 * st['regime_fraction']:.0f}% of "
            f"members; {100 * st['lyapunov_reset_fraction']:.0f}% reset every cycle (exponent -inf)",
            "chattering-periodic in the majority, every member's exponent -inf (reset)",
            ok,
            where,
        ),
        notes,
    )


def _threshold_checks(_src: _Source) -> list[CheckResult]:
    """The engine's thresholds (:mod:`bouncedisk.studies.thresholds`) against the closed forms."""
    out = []
    e = 0.3
    for n in (1, 2):
        g = thresholds.engine_existence_threshold(n, e)
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
    g = thresholds.engine_doubling_threshold(e)
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


#: Least share of the single run's samples inside its ensemble's central 95 % band (Fig. 5):
#: the run is one more realization of the band's members.
IN_BAND = 0.5


def in_band(traj: np.ndarray, band: dict) -> float:
    """Share of the run's ``Ω(t)`` samples, within the band's times, inside the band's central
    95 % of members (``omega_p025``, ``omega_p975`` interpolated to the run's times)."""
    t, om = traj[:, 0], traj[:, 1]
    keep = (t >= band["time"][0]) & (t <= band["time"][-1])
    if not keep.any():
        return 0.0
    lo = np.interp(t[keep], band["time"], band["p025"])
    hi = np.interp(t[keep], band["time"], band["p975"])
    return float(np.mean((om[keep] >= lo) & (om[keep] <= hi)))


def _rise_check(src: _Source) -> CheckResult:
    _, traj, where = src.get("fig5")
    claim = (
        "rotor speed after 300 collisions: first-order rise with a high-frequency ripple "
        "(paper §3, Fig. 5; docs/user_guide/fitting.md; e = 0.6, omega_s = 1.5, R_phi = 0.01, "
        "psi = 0)"
    )
    if traj is None or len(traj) < 10:
        return CheckResult(
            claim, "no omega_rotor trajectory", "a trajectory with omega_rotor", False, where
        )
    t, om = traj[:, 0], traj[:, 1]
    trend = ob.first_order_trend(t, om)
    ripple = trend.ripple_rms / abs(trend.steady) if trend.steady else math.inf
    band, band_where, notes = src.band("fig5")
    from ..analysis.statistics import confidence_interval

    mean, low, high = confidence_interval(band["steady"])
    inside = in_band(traj, band)
    long_run, lr_where, lr_notes = src.stats("stats_e06")
    ok = band["r2"] > 0.8 and trend.tau > 0 and 0.005 < ripple < 0.3 and t[-1] > 2 * trend.tau
    ok = ok and low <= long_run["mean_omega_ci95"][1] and high >= long_run["mean_omega_ci95"][0]
    ok = ok and inside >= IN_BAND
    measured = (
        f"steady Omega of the members' first-order trends {mean:.4g} (95% CI [{low:.4g}, "
        f"{high:.4g}], {len(band['steady'])} members), R^2 of the ensemble-mean trend "
        f"{band['r2']:.3f}; long-run mean {_ci(long_run, 'mean_omega')}; one run's ripple RMS "
        f"{100 * ripple:.2f}% of steady, {100 * inside:.0f}% of it inside the members' central 95%"
    )
    return audited(
        CheckResult(
            claim,
            measured,
            "R^2 > 0.8, ripple 0.5%-30% of steady, run longer than 2 time constants, steady-speed "
            f"interval overlapping the long-run ensemble mean's, >= {100 * IN_BAND:.0f}% of the run "
            "inside the band",
            ok,
            f"{where}; {band_where}; {lr_where}",
        ),
        notes + lr_notes,
    )


#: Fewest readings of the load curve within the fitted members' 95 % band (13 readings: 11).
FIT_IN_BAND = 0.8
#: A fit is adequate when its ``χ²``'s p-value (one degree per statistic) exceeds this: the
#: fit's own rule (``bouncedisk.fitting.uncertainty.ADEQUATE_P``, which this layer may not
#: import; tests/test_checks.py holds the two equal).
FIT_P_MIN = 1e-3
#: What the fit checks read from the fit file; a file without one is refused, naming it.
FIT_VARIABLES = (
    "load_speed_measured",
    "load_speed_band_low",
    "load_speed_band_high",
    "interval_low",
    "interval_high",
    "interval_identified",
    "search_low",
    "search_high",
    "generating_value",
    "data_set",
    "parameter",
)
FIT_ATTRS = (
    "chi2",
    "n_statistics",
    "chi2_p_value",
    "fit_adequate",
    "identified",
    "load_curve_synthetic",
)
_FIT_CLAIMS = (
    "the model fitted to the run-up and the load curve together reproduces the load curve "
    "(docs/user_guide/fitting.md)",
    "the run-up and the load curve together identify the motor: every parameter has a "
    "two-sided 95% interval inside its search range (docs/user_guide/fitting.md)",
)


#: What only a joint fit writes: a fit file with one of them is a joint fit, and every field
#: the fit checks read must be in it.
JOINT_MARKERS = tuple(
    v for v in FIT_VARIABLES if v not in ("search_low", "search_high", "parameter")
) + (
    "load_curve_file",
    "load_curve_sha256",
    "load_curve_synthetic",
    "chi2_load",
    "n_load_readings",
)


def _fit_checks(src: _Source) -> list[CheckResult]:
    """The joint fit (docs/user_guide/fitting.md): the model fitted to the run-up and the load
    curve together reproduces the load curve and pins every parameter. Read from the pipeline's
    fit file; a run without ``--results`` has no fit to read (a fit takes minutes) and skips
    it. A joint fit is checked when :attr:`_Source.joint_fit` says one was made (the pipeline
    knows), or, when that is unknown, when the file holds anything only a joint fit writes
    (:data:`JOINT_MARKERS`); a run-up-only fit where a joint fit was made fails both claims."""
    if src.results is None:
        return []
    path = src.results / FIT_FILE
    if not path.is_file():
        raise InputError(str(path), "", "missing: the results folder lacks the prototype's fit")
    ds = open_checked(path, required=("omega_measured",), what="fit")
    joint = any(k in ds.variables or k in ds.attrs for k in JOINT_MARKERS)
    if not (joint or src.joint_fit):
        return []  # a run-up-only fit (the config names no load curve): no joint fit to check
    if not joint:
        why = "a run-up-only fit (no load_speed_measured) where the pipeline made a joint fit"
        return [CheckResult(c, why, "a joint fit (--load)", False, str(path)) for c in _FIT_CLAIMS]
    ds = open_checked(path, required=FIT_VARIABLES, required_attrs=FIT_ATTRS, what="joint fit")
    if "both" not in [str(d) for d in ds["data_set"].values]:
        raise InputError(str(path), "data_set", "has no 'both' row (not a joint fit file?)")
    both = list(ds["data_set"].values).index("both")
    return [_reproduces_check(ds, str(path)), _identifiability_check(ds, both, str(path))]


def fit_verdict(ds, where: str) -> tuple[dict, list[str]]:
    """The fit's ``χ²``, its p-value recomputed from it, and the stored p-value, adequacy and
    ``identified`` that disagree with that p-value."""
    from scipy.special import chdtrc

    a = ds.attrs
    chi2, n = inp.number(a, where, "chi2"), inp.number(a, where, "n_statistics")
    p = float(chdtrc(n, chi2)) if n >= 1 and chi2 >= 0 else math.nan
    adequate = p > FIT_P_MIN
    stored = {
        "chi2_p_value": inp.number(a, where, "chi2_p_value"),
        "fit_adequate": inp.number(a, where, "fit_adequate"),
        "identified": inp.text(a, where, "identified"),
    }
    recomputed = {
        "chi2_p_value": p,
        "fit_adequate": float(adequate),
        "identified": "yes" if adequate else "no",
    }
    verdict = {"chi2": chi2, "n": n, "p": p, "adequate": adequate}
    return verdict, inp.disagreements(stored, recomputed, source="chi2")


def _reproduces_check(ds, where: str) -> CheckResult:
    """The load curve's readings inside the fitted members' band, and an adequate ``χ²``."""
    y = inp.array(ds, where, "load_speed_measured")
    lo, hi = (inp.array(ds, where, f"load_speed_band_{k}") for k in ("low", "high"))
    inside = (y >= lo) & (y <= hi)
    frac = float(np.mean(inside)) if len(y) else 0.0
    v, notes = fit_verdict(ds, where)
    return audited(
        CheckResult(
            _FIT_CLAIMS[0],
            f"{100 * frac:.0f}% of {len(y)} readings within the fitted members' 95% band; joint "
            f"chi2 {v['chi2']:.4g} on {v['n']:g} statistics (p = {v['p']:.2g})",
            f">= {100 * FIT_IN_BAND:.0f}% within the band, fit adequate (p > {FIT_P_MIN:g})",
            frac >= FIT_IN_BAND and v["adequate"],
            where,
        ),
        notes,
    )


def _identifiability_check(ds, both: int, where: str) -> CheckResult:
    """Every joint interval two-sided, inside the search range, and, when the data are synthetic
    (``load_curve_synthetic``; the sidecar states the generating values: ``generating_value``),
    the four motor parameters' holding the generating value. A NaN interval and a fit with
    ``identified = "no"`` (an inadequate fit writes NaN intervals) are not identified. The
    fitted noise's interval is reported against its generating value but not required to hold
    it: it is set by the other acceptable points the search found, the covariance being held at
    the optimum's noise (docs/fitting_method.md "The restitution noise")."""
    names = [str(n) for n in ds["parameter"].values]
    lo, hi = (inp.array(ds, where, f"interval_{k}")[both] for k in ("low", "high"))
    ids = inp.array(ds, where, "interval_identified")[both]
    s_lo, s_hi = inp.array(ds, where, "search_low"), inp.array(ds, where, "search_high")
    gen = inp.array(ds, where, "generating_value")
    synthetic = bool(inp.number(ds.attrs, where, "load_curve_synthetic")) or bool(
        np.isfinite(gen).any()
    )
    fails, notes = [], []
    if inp.text(ds.attrs, where, "identified") != "yes":
        reason = ds.attrs.get("identified_reason", "")
        fails.append(f"identified = {ds.attrs['identified']!r}" + (f": {reason}" if reason else ""))
    for j, n in enumerate(names):
        if not (np.isfinite(lo[j]) and np.isfinite(hi[j]) and ids[j]):
            fails.append(f"{n} not identified")
        elif not (s_lo[j] < lo[j] and hi[j] < s_hi[j]):
            fails.append(f"{n} reaches the search range's end")
        elif synthetic and not np.isfinite(gen[j]):
            fails.append(f"{n}: synthetic data state no generating value")
        elif synthetic and not lo[j] <= gen[j] <= hi[j]:
            (notes if n == "e_sigma" else fails).append(
                f"{n} excludes its generating value {gen[j]:.4g}"
            )
    measured = ", ".join(f"{n} [{lo[j]:.4g}, {hi[j]:.4g}]" for j, n in enumerate(names))
    if synthetic:
        measured += "; generating " + ", ".join(f"{n} {gen[j]:.4g}" for j, n in enumerate(names))
    if fails or notes:
        measured += " (" + "; ".join(fails + [f"{t}: reported, not required" for t in notes]) + ")"
    expected = "identified and strictly inside the search range, each"
    if synthetic:
        expected += ", the motor parameters' holding the generating value (synthetic data)"
    return CheckResult(_FIT_CLAIMS[1], measured, expected, not fails, where)


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


def run_checks(results: Path | None = None, joint_fit: bool | None = None) -> list[CheckResult]:
    """Run every check; ``results`` is the pipeline's results folder (or None to simulate),
    ``joint_fit`` whether the pipeline fitted the prototype's load curve with its run-up
    (None: read it from the fit file, :func:`_fit_checks`)."""
    src = _Source(results, joint_fit)
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
