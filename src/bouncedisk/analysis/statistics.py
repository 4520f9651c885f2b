"""Ensemble statistics with confidence intervals (``bouncedisk stats``, docs/formats.md
"Statistics").

A long-run number of a chaotic scene is an ensemble average (docs/model.md "Long-run statistics of
chaotic motion"): every member's time average over ``[t0 + discard, t_end]`` is one sample, and
the 95 % interval is Student's ``t`` across members, ``mean ± t_{0.975, K−1} s / sqrt(K)``.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields

import numpy as np
import xarray as xr
from scipy.special import stdtrit

from ..io.provenance import base_attrs, new_run_id
from ..model.engine_config import engine_config
from ..model.errors import InputError
from ..model.params import Scales
from ..model.scene import Scene, require_scene, time_unit_note
from ..run.cores import checked_cores, map_on_threads
from ..run.runner import scene_attrs
from . import observables as ob
from .ensembles import CappedRun, MemberStats
from .settling import drifting, run_settled

#: Ensemble statistics: field -> (long name, units) in nondimensional units (docs/formats.md).
QUANTITIES: dict[str, tuple[str, str]] = {
    "mean_omega": ("time-averaged rotor angular velocity", "1"),
    "mean_slip": ("time-averaged slip s = r_phi * omega - omega_stator", "1"),
    "impact_rate": ("impacts per unit time (chattering tails not counted)", "1"),
    "chatter_rate": ("complete chattering sequences per unit time", "1"),
    "chatter_interval": (
        "mean time between complete chattering sequences (members with two or more)",
        "1",
    ),
    "lyapunov": ("largest Lyapunov exponent of the impact map per impact, between resets", "1"),
    "power_torsion_in": ("mean power the stator puts in through friction", "1"),
    "power_axial_in": ("mean power the stator puts in through the normal force", "1"),
    "power_chatter_axial": ("mean axial power left to summed chattering tails", "1"),
    "power_out": ("mean output power tau_L * mean omega", "1"),
    "efficiency_torsion": ("efficiency of the friction drive, power_out / power_torsion_in", "1"),
}
#: Quantities reported only for scenes with the ``load`` effect (zero by definition without it).
LOAD_ONLY = ("power_out", "efficiency_torsion")
#: Largest relative residuals of the energy balances over the members (docs/model.md).
AUDIT = {
    "audit_residual_axial": "largest relative residual of the axial energy balance",
    "audit_residual_torsion": "largest relative residual of the torsional energy balance",
}
#: Powers converted to W for physical scenes: field -> attribute of Scales giving its unit.
POWER_UNITS = {
    "power_out": "torsion_power",
    "power_torsion_in": "torsion_power",
    "power_axial_in": "axial_power",
}
LEVEL = 0.95
#: Quantities that cannot be negative: their intervals are cut at 0 (the parameter space).
NONNEGATIVE = ("impact_rate", "chatter_rate", "chatter_interval")


def confidence_interval(
    values: Sequence[float], level: float = LEVEL
) -> tuple[float, float, float]:
    """Mean and Student-t interval ``mean ± t_{(1+level)/2, K−1} s/√K`` of the finite values.

    Returns ``(mean, low, high)``; the interval is ``nan`` with fewer than two finite values and
    has zero width when all values are equal (a periodic attractor).
    """
    x = np.asarray(values, float)
    x = x[np.isfinite(x)]
    if len(x) == 0:
        return math.nan, math.nan, math.nan
    mean = float(np.mean(x))
    if len(x) < 2:
        return mean, math.nan, math.nan
    half = float(t_half_width(x, level))
    return mean, mean - half, mean + half


#: Standard normal quantile of the 95 % Wilson interval.
Z95 = 1.959963984540054


def wilson(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson's score interval of a proportion ``k / n`` (95 % with the default ``z``):
    ``(k + z²/2)/(n + z²) ± z/(n + z²) sqrt(k (n − k)/n + z²/4)``, inside ``[0, 1]``."""
    if n <= 0:
        return math.nan, math.nan
    centre = (k + 0.5 * z * z) / (n + z * z)
    half = z / (n + z * z) * math.sqrt(k * (n - k) / n + 0.25 * z * z)
    low = 0.0 if k == 0 else max(0.0, centre - half)
    high = 1.0 if k == n else min(1.0, centre + half)
    return low, high


def t_quantile(dof: int, level: float = LEVEL) -> float:
    """Student's quantile ``t_{(1+level)/2, dof}`` of a two-sided ``level`` interval.

    docs/model.md "Long-run statistics of chaotic motion". This is ``scipy.stats.t.ppf``'s own
    formula, bit for bit, without the import of ``scipy.stats``, which would weigh on every
    pipeline job that reads an ensemble.

    Raises
    ------
    InputError
        ``level`` not a fraction in (0, 1): ``95`` meant as 95 % is refused, not read as NaN.
    """
    if not 0.0 < level < 1.0:
        raise InputError("<arguments>", "level", f"must be a fraction in (0, 1), got {level!r}")
    return float(stdtrit(dof, 0.5 + level / 2.0))


def t_half_width(values: np.ndarray, level: float = LEVEL, axis: int = 0) -> float | np.ndarray:
    """Half-width ``t_{(1+level)/2, K−1} s/√K`` of the Student interval of the mean along ``axis``.

    ``K`` is the length of ``values`` along ``axis`` (at least 2) and ``s`` the sample standard
    deviation (docs/model.md "Long-run statistics of chaotic motion").
    """
    k = np.shape(values)[axis]
    return t_quantile(k - 1, level) * np.std(values, axis=axis, ddof=1) / math.sqrt(k)


@dataclass(frozen=True)
class EnsembleStats:
    """An ensemble's members and their summary (docs/formats.md fields)."""

    members: list[MemberStats]
    discard: float
    duration: float
    load: bool = False
    scales: Scales | None = None
    #: Each member's drift: its window's second half's mean speed less the first half's
    #: (:func:`~bouncedisk.analysis.settling.run_settled`); ``None``: not measured.
    drift: np.ndarray | None = None

    def column(self, name: str) -> np.ndarray:
        """One per-member quantity as an array in member order."""
        return np.array([getattr(m, name) for m in self.members], dtype=float)

    @property
    def regime(self) -> tuple[str, float, list[int] | None]:
        """Most common member regime, the fraction of members in it, and its ``[p, q]``.

        For a regime with a period the fraction counts the members of that regime *and* period:
        members of the same regime on another period are not "in" it.
        """
        counts = Counter((m.regime, m.period_p, m.period_q) for m in self.members)
        by_regime = Counter(m.regime for m in self.members)
        code, n = by_regime.most_common(1)[0]
        (_, p, q), n_period = next((k, c) for k, c in counts.most_common() if k[0] == code)
        period = [p, q] if p > 0 else None
        if period is not None:
            n = n_period
        return ob.REGIMES[code], n / len(self.members), period

    @property
    def regime_tie(self) -> list[str]:
        """The regimes that share the largest number of members, when several do (else ``[]``).

        :attr:`regime` then names the first of them met in member order.
        """
        by_regime = Counter(m.regime for m in self.members)
        top = max(by_regime.values())
        tied = [ob.REGIMES[code] for code, n in by_regime.items() if n == top]
        return tied if len(tied) > 1 else []

    def summary(self) -> dict:
        """The JSON object of ``bouncedisk stats --json`` (non-finite numbers as ``null``).

        Each quantity's mean and Student interval are over the members that have a (finite)
        value of it; ``members_with_value`` names the quantities some members lack, with the
        number that have one (docs/formats.md "Statistics").
        """
        out: dict = {
            "members": len(self.members),
            "discard": self.discard,
            "duration": self.duration,
            "members_with_value": {},
        }
        for name in QUANTITIES:
            if name in LOAD_ONLY and not self.load:
                continue
            _put_interval(out, name, self.column(name), nonnegative=name in NONNEGATIVE)
        for name in AUDIT:
            out[name] = _finite_or_none(float(np.nanmax(self.column(name), initial=-np.inf)))
        if self.drift is not None:
            self._settling(out)
        if self.scales is not None:
            self._physical_values(out)
        lam = self.column("lyapunov")
        reset = float(np.mean(np.isneginf(lam)))
        out["lyapunov_reset_fraction"] = reset
        name, frac, period = self.regime
        out["regime"] = name
        out["regime_fraction"] = frac
        n = len(self.members)  # a proportion of the members: Wilson's interval, as basins'
        out["regime_fraction_ci95"] = list(wilson(round(frac * n), n))
        out["regime_tie"] = self.regime_tie
        out["period"] = period
        return out

    def _settling(self, out: dict) -> None:
        """Into ``out``: the members' drift with its interval and whether the ensemble has
        settled (1) or its window still drifts (0): :func:`~.settling.drifting` with the mean
        speed's magnitude as the scale."""
        _put_interval(out, "drift", self.drift)
        scale = abs(float(np.nanmean(self.column("mean_omega"))))
        out["settled"] = int(not drifting(self.drift[:, None], scale)[0])  # members x 1

    def _physical_values(self, out: dict) -> None:
        """Into ``out``: the mean speed in rad/s, the powers in W and the motor's mechanical
        efficiency ``η = P_out / (P_ax + P_t)`` (docs/model.md "The motor under load"), each with
        its interval across members."""
        sc = self.scales
        _put_interval(out, "mean_omega_rad_s", self.column("mean_omega") * sc.omega_scale)
        watts = {}
        for name, unit in POWER_UNITS.items():
            if name in LOAD_ONLY and not self.load:
                continue
            watts[name] = self.column(name) * getattr(sc, unit)
            _put_interval(out, f"{name}_W", watts[name])
        if self.load:
            with np.errstate(invalid="ignore", divide="ignore"):
                eta = watts["power_out"] / (watts["power_axial_in"] + watts["power_torsion_in"])
            _put_interval(out, "efficiency", eta)


def _put_interval(out: dict, name: str, values: np.ndarray, nonnegative: bool = False) -> None:
    """``out[name]``, ``out[name + "_ci95"]``: the mean and Student interval of the finite
    ``values`` (the low end raised to 0 for a ``nonnegative`` quantity), and their count in
    ``out["members_with_value"]`` when some values are not finite."""
    mean, low, high = confidence_interval(values)
    if nonnegative and low < 0.0:
        low = 0.0
    out[name] = _finite_or_none(mean)
    out[f"{name}_ci95"] = [_finite_or_none(low), _finite_or_none(high)]
    finite = int(np.isfinite(values).sum())
    if finite < len(values):
        out["members_with_value"][name] = finite


def _finite_or_none(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def ensemble_window(scene: Scene) -> tuple[float, float]:
    """``(t_from, t_end)`` of a scene's averages: after ``stats.discard``, to ``stop.time``.

    Raises
    ------
    InputError
        No time stop, or an averaging window shorter than one stator period ``2 pi / omega_s``.
    """
    if scene.stop.time is None:
        raise InputError(
            scene.source,
            "stop",
            "statistics are time averages: give stop.time or stop.periods, not stop.impacts",
        )
    t_from, t_end = scene.initial.t + scene.stats.discard, scene.stop.time
    period = 2.0 * math.pi / scene.params.omega_s
    if t_end - t_from < period:
        # the field at fault: the discard that eats the run, else the run itself
        field = "stats.discard" if scene.stats.discard > 0 else "stop.time"
        raise InputError(
            scene.source,
            field,
            f"leaves {t_end - t_from:.3g} time units to average over, less than one stator "
            f"period ({period:.4g}): too short to hold an impact or a cycle, so no regime or rate "
            f"can be measured; lower stats.discard or raise stop.time{time_unit_note(scene.physical)}",
        )
    return t_from, t_end


def capped_error(
    scene: Scene, ex: CappedRun, where: str = "", who: str | None = None
) -> InputError:
    """The one-line error for a member that stopped at ``stop.max_events`` before the end of its
    averaging window: a statistic over a window the run did not reach is no number. ``who``
    names the run (:meth:`CappedRun.said`)."""
    return InputError(
        scene.source,
        "stop.max_events",
        f"{ex.said(who)}{where}: no average over a window the run did not reach; raise "
        "stop.max_events or shorten stop.time",
    )


def run_stats(
    scene: Scene,
    cores: int = 1,
    on_member: Callable[[int, int], None] | None = None,
    should_stop: Callable[[], bool] | None = None,
) -> EnsembleStats:
    """Run a scene's ensemble (``ensemble.members`` members) and reduce it.

    Raises
    ------
    InputError
        When the scene does not stop on time, is not the exact bouncing model, or a member
        stops at ``stop.max_events`` before ``stop.time`` (:func:`capped_error`).
    """
    scene = require_scene(scene)
    cores = checked_cores(cores)
    t_from, t_end = ensemble_window(scene)
    if scene.solver.method != "exact" or scene.model != "bouncing":
        raise InputError(
            scene.source, "solver.method", "statistics run the exact bouncing model only"
        )
    cfg = engine_config(scene)

    def one(m: int) -> tuple[MemberStats, float]:
        stats, _final, drift = run_settled(cfg, scene.initial, m, t_from, should_stop)
        return stats, drift

    try:
        got = map_on_threads(one, range(scene.ensemble.members), cores, on_member)
    except CappedRun as ex:
        raise capped_error(scene, ex) from None
    members = [stats for stats, _ in got]
    drift = np.array([d for _, d in got], dtype=float)
    return EnsembleStats(
        members, scene.stats.discard, t_end - t_from, "load" in scene.effects, scene.scales, drift
    )


def to_dataset(scene: Scene, result: EnsembleStats, wall_time_s: float) -> xr.Dataset:
    """Per-member values (dimension ``member``) with the summary and provenance as attributes."""
    data = {}
    for f in fields(MemberStats):
        if f.name == "member":
            continue
        values = result.column(f.name)
        long_name, units = QUANTITIES.get(
            f.name, (AUDIT.get(f.name, f.name.replace("_", " ")), "1")
        )
        if f.name in ("regime", "period_p", "period_q", "n_impacts", "n_chatter"):
            values = values.astype(np.int64)
        data[f.name] = ("member", values, {"long_name": long_name, "units": units})
    data["regime"][2].update(
        {
            "long_name": "dynamical regime of the member",
            **ob.regime_flags(np.int64),
        }
    )
    data["period_p"][2]["long_name"] = "impacts per cycle (periodic regimes; 0 otherwise)"
    data["period_q"][2]["long_name"] = "stator periods per cycle (periodic regimes; 0 otherwise)"
    data["duration"][2]["long_name"] = "averaging time of the member"
    members = np.array([m.member for m in result.members], dtype=np.int64)
    ds = xr.Dataset(data, coords={"member": ("member", members, {"long_name": "ensemble member"})})
    ds.attrs.update(base_attrs(f"bouncedisk ensemble statistics of scene '{scene.name}'"))
    ds.attrs.update(scene_attrs(scene))
    summary = result.summary()
    counted = summary.pop("members_with_value")
    ds.attrs["stats_members_with_value"] = (
        ",".join(f"{k}:{n}" for k, n in counted.items()) or "all"
    )  # "chatter_interval:24": its mean is over 24 members
    for k, v in summary.items():
        if isinstance(v, list) and v and isinstance(v[0], str):
            v = ",".join(v)  # regime_tie: names of the tied regimes
        elif isinstance(v, list):
            v = [math.nan if x is None else x for x in v] if v else "none"
        ds.attrs[f"stats_{k}"] = math.nan if v is None else v
    ds.attrs.update(
        {
            "ensemble_members": len(result.members),
            "ensemble_seed": scene.ensemble.seed,
            "confidence_level": LEVEL,
            "run_id": new_run_id(f"{scene.name}-stats", scene.sha256),
            "wall_time_s": round(wall_time_s, 6),
            "n_impacts": int(sum(m.n_impacts for m in result.members)),
            "status": "completed",
        }
    )
    return ds
