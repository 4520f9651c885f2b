"""What the reproduction checks read from a built file: each field type-checked, each summary
recomputed from the arrays it summarises, each stored attribute compared with its recomputation.

A check judges a claim on the numbers recomputed here (:mod:`bouncedisk.studies.reproduction`);
an attribute that disagrees with them is reported beside the claim (:func:`disagreements`), and
the claim fails. A field of the wrong type is an :class:`~bouncedisk.model.errors.InputError`
naming the file and the field.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ..analysis import observables as ob
from ..analysis.ensembles import MemberStats
from ..analysis.statistics import EnsembleStats, confidence_interval
from ..model.errors import InputError
from .load_summary import MOMENTUM_BOUND, derived

#: Relative (and absolute, near 0) difference below which a stored number equals its recomputation.
SAME = 1e-9
#: Per-member variables of a statistics file the summary is recomputed from (docs/formats.md
#: "Statistics file").
STATS_VARIABLES = ("mean_omega", "lyapunov", "regime", "period_p", "period_q")
#: The summary fields the checks use, each stored as the attribute ``stats_<field>``.
STATS_FIELDS = (
    "members",
    "mean_omega",
    "mean_omega_ci95",
    "regime",
    "regime_fraction",
    "period",
    "lyapunov",
    "lyapunov_ci95",
    "lyapunov_reset_fraction",
)
STATS_ATTRS = tuple(f"stats_{k}" for k in STATS_FIELDS)
#: Variables of a load curve the checks recompute from (per member) and compare (per load).
LOAD_VARIABLES = (
    "branch",
    "load_torque",
    "mean_omega_member",
    "power_out_member",
    "mean_omega",
    "mean_omega_ci95_low",
    "mean_omega_ci95_high",
    "audit_residual_axial",
    "audit_residual_torsion",
)
LOAD_ATTRS = (
    "e",
    "stall_torque",
    "stall_torque_ci95",
    "stall_torque_state",
    "stats_discard",
    "stats_duration",
)


def _short(v) -> str:
    """A value as a user wrote it (``0.5``, ``'abc'``, ``[1, 2]``: no numpy type names)."""
    text = repr(v.tolist() if isinstance(v, np.ndarray | np.generic) else v)
    return text if len(text) <= 40 else text[:37] + "..."


def number(attrs: Mapping, where: str, name: str) -> float:
    """The attribute ``name`` as a float (``nan`` allowed).

    Raises
    ------
    InputError
        When it is not one number (a string, a list, a boolean).
    """
    v = attrs[name]
    if isinstance(v, np.ndarray) and v.size == 1:
        v = v.reshape(()).item()
    if isinstance(v, bool | np.bool_) or not isinstance(v, int | float | np.integer | np.floating):
        raise InputError(where, name, f"is {_short(v)}, not a number")
    return float(v)


def pair(attrs: Mapping, where: str, name: str) -> list[float]:
    """The attribute ``name`` as ``[low, high]`` (``nan`` allowed).

    Raises
    ------
    InputError
        When it is not two numbers.
    """
    v = attrs[name]
    arr = np.asarray(v)
    if arr.dtype.kind not in "fiu" or arr.shape != (2,):
        raise InputError(where, name, f"is {_short(v)}, not a pair of numbers [low, high]")
    return [float(x) for x in arr]


def text(attrs: Mapping, where: str, name: str) -> str:
    """The attribute ``name`` as a string.

    Raises
    ------
    InputError
        When it is not a string.
    """
    v = attrs[name]
    if not isinstance(v, str):
        raise InputError(where, name, f"is {_short(v)}, not text")
    return v


def array(ds, where: str, name: str) -> np.ndarray:
    """The variable ``name`` as a float array.

    Raises
    ------
    InputError
        When it holds something other than numbers.
    """
    values = ds[name].values
    if values.dtype.kind not in "fiub":
        raise InputError(where, name, f"holds {values.dtype} values, not numbers")
    return np.asarray(values, float)


def _same(stored, recomputed) -> bool:
    if isinstance(recomputed, str) or recomputed is None or isinstance(stored, str):
        return stored == recomputed
    a, b = np.asarray(stored, float), np.asarray(recomputed, float)
    if a.shape != b.shape:
        return False
    both_nan = np.isnan(a) & np.isnan(b)
    close = np.isclose(a, b, rtol=SAME, atol=SAME) | (a == b)
    return bool(np.all(both_nan | close))


def disagreements(
    stored: Mapping, recomputed: Mapping, prefix: str = "", source: str = "the arrays"
) -> list[str]:
    """``"<prefix><key> <stored> vs <recomputed> from <source>"`` for each key of ``stored``
    whose value differs from ``recomputed[key]`` (numbers within :data:`SAME`)."""
    out = []
    for key, value in stored.items():
        other = recomputed[key]
        if _same(value, other):
            continue
        if np.ndim(value) == 1 and len(value) > 2 and np.shape(value) == np.shape(other):
            k = next(i for i in range(len(value)) if not _same(value[i], other[i]))
            key, value, other = f"{key}[{k}]", value[k], other[k]
        out.append(f"{prefix}{key} {_shown(value)} vs {_shown(other)} from {source}")
    return out


def _shown(v) -> str:
    if isinstance(v, list | tuple | np.ndarray):
        return "[" + ", ".join(_shown(x) for x in v) + "]"
    if isinstance(v, float | np.floating):
        return f"{float(v):.6g}"
    return str(v)


# ----------------------------------------------------------------------------- statistics
def member_stats(ds, where: str) -> EnsembleStats:
    """The ensemble of a statistics file rebuilt from its per-member variables
    (:data:`STATS_VARIABLES`; the others the checks do not use are left ``nan``).

    Raises
    ------
    InputError
        A variable that holds no numbers, or a regime code that is not one of the file's flags.
    """
    cols = {name: array(ds, where, name) for name in STATS_VARIABLES}
    codes = cols["regime"]
    bad = [c for c in codes if not (np.isfinite(c) and int(c) == c and int(c) in ob.REGIMES)]
    if bad:
        raise InputError(
            where, "regime", f"holds {bad[0]:g}, not a regime code {sorted(ob.REGIMES)}"
        )
    nan = math.nan
    members = [
        MemberStats(
            member=k,
            mean_omega=cols["mean_omega"][k],
            mean_slip=nan,
            impact_rate=nan,
            chatter_rate=nan,
            chatter_interval=nan,
            lyapunov=cols["lyapunov"][k],
            regime=int(codes[k]),
            period_p=int(cols["period_p"][k]),
            period_q=int(cols["period_q"][k]),
            n_impacts=0,
            n_chatter=0,
            duration=nan,
        )
        for k in range(len(codes))
    ]
    if not members:
        raise InputError(where, "member", "has no members")
    return EnsembleStats(members, nan, nan)


def stats_summary(stats: EnsembleStats) -> dict:
    """The summary fields the checks use (:data:`STATS_FIELDS`) of an ensemble, ``nan`` for a
    missing number."""
    s = stats.summary()
    nan = math.nan
    out = {k: s[k] for k in STATS_FIELDS}
    for k in ("mean_omega", "lyapunov"):
        out[k] = nan if out[k] is None else out[k]
        out[f"{k}_ci95"] = [nan if x is None else x for x in out[f"{k}_ci95"]]
    return out


def stored_stats(ds, where: str) -> dict:
    """The ``stats_<field>`` attributes of :data:`STATS_FIELDS`, type-checked."""
    a = ds.attrs
    out: dict = {}
    for k in STATS_FIELDS:
        name = f"stats_{k}"
        if k == "regime":
            out[k] = text(a, where, name)
        elif k == "period":
            out[k] = _period(a, where, name)
        elif k.endswith("_ci95"):
            out[k] = pair(a, where, name)
        else:
            out[k] = number(a, where, name)
    return out


def _period(attrs: Mapping, where: str, name: str) -> list[int] | None:
    """A stored period: ``[p, q]``, or none (``nan``, as the statistics file writes it, or
    ``"none"``)."""
    v = attrs[name]
    if (isinstance(v, str) and v == "none") or (
        np.ndim(v) == 0 and not isinstance(v, str) and math.isnan(number(attrs, where, name))
    ):
        return None
    return [int(x) for x in pair(attrs, where, name)]


def stats_from_file(ds, where: str) -> tuple[dict, list[str]]:
    """The summary recomputed from a statistics file's members, and how its attributes
    disagree with it."""
    summary = stats_summary(member_stats(ds, where))
    return summary, disagreements(stored_stats(ds, where), summary, "stats_")


# ----------------------------------------------------------------------------- load curves


def _largest(values: np.ndarray) -> float:
    """The largest of ``values``, infinite where one is not finite (a residual that is NaN did not
    close: it must fail the audit's claim, not be skipped)."""
    v = np.asarray(values, float)
    return float(np.max(np.where(np.isfinite(v), v, np.inf))) if v.size else math.inf


def load_from_file(ds, where: str) -> tuple[dict, list[str]]:
    """A load curve's up branch recomputed from its members: per load the mean speed and its
    95 % interval, the stall torque with its interval and state (:func:`derived`), with the
    largest audit residual; and how the file's per-load means and attributes disagree."""
    branches = [str(b) for b in ds["branch"].values]
    if "up" not in branches:
        raise InputError(where, "branch", "has no 'up' branch (not a load curve file?)")
    loads = array(ds, where, "load_torque")
    up = branches.index("up")
    speed = array(ds, where, "mean_omega_member")[up].T  # (member, load)
    power = array(ds, where, "power_out_member")[up].T
    per_load = np.array([confidence_interval(speed[:, k]) for k in range(len(loads))])
    got = derived(loads, speed, power, MOMENTUM_BOUND)
    nan = math.nan
    stall_ci = [nan if x is None else x for x in got["stall_torque_ci95"]]
    out = {
        "loads": loads,
        "mean": per_load[:, 0],
        "low": per_load[:, 1],
        "high": per_load[:, 2],
        "residual": max(
            _largest(array(ds, where, f"audit_residual_{k}")) for k in ("axial", "torsion")
        ),
        "stall": nan if got["stall_torque"] is None else got["stall_torque"],
        "stall_ci95": stall_ci,
        "state": got["stall_torque_state"],
        "e": number(ds.attrs, where, "e"),
        "discard": number(ds.attrs, where, "stats_discard"),
        "duration": number(ds.attrs, where, "stats_duration"),
    }
    stored = {
        "mean_omega": array(ds, where, "mean_omega")[up],
        "mean_omega_ci95_low": array(ds, where, "mean_omega_ci95_low")[up],
        "mean_omega_ci95_high": array(ds, where, "mean_omega_ci95_high")[up],
        "stall_torque": number(ds.attrs, where, "stall_torque"),
        "stall_torque_ci95": pair(ds.attrs, where, "stall_torque_ci95"),
        "stall_torque_state": text(ds.attrs, where, "stall_torque_state"),
    }
    recomputed = dict(
        zip(
            stored,
            (out["mean"], out["low"], out["high"], out["stall"], out["stall_ci95"], out["state"]),
            strict=True,
        )
    )
    return out, disagreements(stored, recomputed)
