"""The joint fit's share of the fit file: measured and fitted load curves, identifiability.

Added to the fit file (docs/formats.md) when load curves were fitted (``bouncedisk fit … --load``):
on the dimension ``reading`` (every reading of every load curve, curve by curve) the load torque
``load_torque`` (N·m), ``load_speed_measured`` with its spread ``load_speed_sd`` and the standard
deviation the likelihood gave it ``load_speed_sigma`` (:mod:`.loadpart`), the fitted model's
``load_speed_fitted`` (ensemble mean) with the 95 % interval of that mean
(``load_speed_fitted_low/high``) and its members' 2.5–97.5 % band (``load_speed_band_low/high``);
and on ``(data_set, parameter)`` the 95 % interval of every search coordinate from the run-ups
alone, the load curves alone and both (``interval_low``, ``interval_high``,
``interval_identified``): which data pins which parameter.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ..io.provenance import sha256_file
from .core import FitResult
from .joint import generating_point_better, stated_truth, truth_coordinate
from .loadpart import LOAD_BAND, LOAD_MEMBERS, setup
from .members import BOUNDS
from .uncertainty import THRESHOLD, identified

#: Data sets of the identifiability table, in order: (key of ``LoadFit.intervals``, label).
DATA_SETS = (("runup", "run-ups"), ("load", "load curve"), ("both", "both"))


def _readings(fit: FitResult) -> dict:
    """Per-reading variables (module docstring)."""
    lf = fit.load
    torque = np.concatenate([d.torque for d in lf.curves])
    sd = np.concatenate(
        [
            d.speed_sd if d.speed_sd is not None else np.full(len(d.torque), np.nan)
            for d in lf.curves
        ]
    )
    which = np.concatenate([np.full(len(d.torque), k) for k, d in enumerate(lf.curves)])
    b = lf.band

    def var(v, long_name):
        return ("reading", np.asarray(v, float), {"units": "rad/s", "long_name": long_name})

    return {
        "load_torque": ("reading", torque, {"units": "N m", "long_name": "load torque"}),
        "load_curve_index": (
            "reading",
            which.astype(np.int32),
            {"units": "1", "long_name": "which load curve the reading is from (order of --load)"},
        ),
        "load_drive_frequency_hz": (
            "reading",
            np.concatenate([np.full(len(d.torque), d.drive_frequency_hz) for d in lf.curves]),
            {"units": "Hz", "long_name": "drive frequency of the reading's curve (its condition)"},
        ),
        "load_speed_measured": var(
            np.concatenate([d.speed for d in lf.curves]),
            "measured mean rotor speed over the window after a start from rest",
        ),
        "load_speed_sd": var(sd, "spread of repeated readings (the data's; nan: not given)"),
        "load_speed_sigma": var(
            np.sqrt(lf.data_var),
            "standard deviation of the reading in the "
            "likelihood: max(spread, model members' sd) / sqrt(repeats)",
        ),
        "load_speed_fitted": var(b["mean"], "fitted model's ensemble mean of the reading"),
        "load_speed_fitted_low": var(b["low"], "lower end of the 95% interval of that mean"),
        "load_speed_fitted_high": var(b["high"], "upper end of the 95% interval of that mean"),
        "load_speed_band_low": var(b["p025"], "2.5th percentile of the fitted model's members"),
        "load_speed_band_high": var(b["p975"], "97.5th percentile of the fitted model's members"),
    }


def _intervals(fit: FitResult) -> dict:
    """The identifiability table on ``(data_set, parameter)`` (search coordinates)."""
    iv = fit.load.intervals
    names = fit.names

    def table(field):
        rows = []
        for key, _ in DATA_SETS:
            prof = {p.name: p for p in iv[key]}
            rows.append([getattr(prof[n], field) if n in prof else np.nan for n in names])
        return np.array(rows, dtype=float)

    dims = ("data_set", "parameter")
    low, high, ident = table("ci_low"), table("ci_high"), table("identified")
    if not identified(fit.chi2, fit.n_statistics)[0]:  # an inadequate fit reports no interval
        low[:], high[:], ident[:] = np.nan, np.nan, 0
    gen = truth(fit)
    truth_x = [truth_coordinate({f"generating_{k}": v for k, v in gen.items()}, n) for n in names]
    return {
        "search_low": (
            "parameter",
            np.array([BOUNDS[n][0] for n in names]),
            {"units": "1", "long_name": "lower end of the search range of each search coordinate"},
        ),
        "search_high": (
            "parameter",
            np.array([BOUNDS[n][1] for n in names]),
            {"units": "1", "long_name": "upper end of the search range of each search coordinate"},
        ),
        "generating_value": (
            "parameter",
            np.array([np.nan if v is None else v for v in truth_x]),
            {
                "units": "1",
                "long_name": "generating value of each search "
                "coordinate stated by synthetic data (nan: not stated)",
            },
        ),
        "interval_low": (
            dims,
            low,
            {
                "units": "1",
                "long_name": "lower end of the "
                "95% interval of each search coordinate from each data set",
            },
        ),
        "interval_high": (
            dims,
            high,
            {
                "units": "1",
                "long_name": "upper end of the "
                "95% interval of each search coordinate from each data set",
            },
        ),
        "interval_identified": (
            dims,
            ident.astype(np.int8),
            {"units": "1", "long_name": "1: the profile is not flat over the search range"},
        ),
    }


def truth(fit: FitResult) -> dict[str, float]:
    """Generating parameters stated by a synthetic load curve's sidecar (empty otherwise), at
    the reference condition (:func:`.loadpart.reference_setup`)."""
    return stated_truth(fit.load.curves, _reference(fit))


def _reference(fit: FitResult):
    """The condition the fit's parameters are stated at (the load part's,
    :func:`.loadpart.reference_setup`)."""
    return fit.load.reference


def _condition_attrs(fit: FitResult) -> dict:
    """The reference condition and every curve's, as global attributes (docs/formats.md)."""
    ref = _reference(fit)

    def words(s) -> str:
        r = s.rotor
        amplitude = "" if s.u0 is None else f", U0 {s.u0:g} m"
        return (
            f"{s.f:g} Hz, Phi0 {s.phi0:g} rad, rotor m_r {r['m_r_kg']:g} kg, r_g "
            f"{r['r_g_m']:g} m, r_c {r['r_c_m']:g} m, preload {s.preload:g} N{amplitude}"
        )

    conditions = (setup(d, ref.u0 is not None) for d in fit.load.curves)
    return {
        "reference_condition": words(ref),
        "load_curve_conditions": "; ".join(words(c) for c in conditions),
    }


def load_dataset(fit: FitResult) -> xr.Dataset:
    """The variables and attributes the joint fit adds to the fit file (module docstring)."""
    lf = fit.load
    n = len(lf.band["mean"])
    ds = xr.Dataset(
        {**_readings(fit), **_intervals(fit)},
        coords={
            "reading": ("reading", np.arange(n)),
            "data_set": ("data_set", [label for _, label in DATA_SETS]),
        },
    )
    ds.attrs.update(
        load_curve_file=", ".join(d.path for d in lf.curves),
        load_curve_sha256=", ".join(sha256_file(d.path) for d in lf.curves),
        load_curve_synthetic=int(all(d.synthetic for d in lf.curves)),
        chi2_load=lf.chi2,
        n_load_readings=lf.n,
        load_window_s=", ".join(f"[{d.window_s[0]:g}, {d.window_s[1]:g}]" for d in lf.curves),
        **_condition_attrs(fit),
        load_members=LOAD_MEMBERS,
        load_band_members=LOAD_BAND,
        identifiability="interval_*: 95% profile intervals of every search coordinate from the "
        "run-ups alone, the load curves alone and both, on the same evaluations; the run-ups' "
        "alone are widened to the scan's acceptable points, as a run-up fit's are",
    )
    for k, v in truth(fit).items():
        ds.attrs[f"generating_{k}"] = v
    for part, v in (lf.chi2_generating or {}).items():
        ds.attrs[f"chi2_generating_{part}"] = v
    for point, v in (lf.loglik_own or {}).items():
        ds.attrs[f"loglik_own_{point}"] = v
    return ds


def identifiability_lines(ds: xr.Dataset) -> list[str]:
    """The summary's lines for a joint fit: the load part's ``χ²`` and the identifiability
    table (search coordinates; ``*``: the profile is flat, not identified)."""
    a = ds.attrs
    lines = [
        f"  load curve: chi2 {a['chi2_load']:.4g} on {a['n_load_readings']} readings "
        f"({a['load_curve_file']})"
    ]
    if a.get("identified", "yes") == "no":
        return [*lines, "  95% intervals by data set: none (inadequate fit)", *_truth_lines(a)]
    lines.append("  95% intervals by data set (search coordinates; * not identified):")
    names = [str(n) for n in ds["parameter"].values]
    for j, name in enumerate(names):
        cells = []
        for k, label in enumerate(str(s) for s in ds["data_set"].values):
            lo, hi = (float(ds[v].values[k, j]) for v in ("interval_low", "interval_high"))
            flag = "" if ds["interval_identified"].values[k, j] else "*"
            cells.append(f"{label} [{lo:.4g}, {hi:.4g}]{flag}")
        truth = float(ds["generating_value"].values[j]) if "generating_value" in ds else math.nan
        lines.append(
            f"    {name:>12}: "
            + "; ".join(cells)
            + (f"  (generating {truth:.4g})" if math.isfinite(truth) else "")
        )
    return lines + _truth_lines(a)


def _truth_lines(attrs: dict) -> list[str]:
    """The summary's lines on the generating point (synthetic data only): its ``χ²`` under the
    fit's final metric, and whether it is more likely than the estimate, judged by ``−2 log L``
    with each point's own covariance (``loglik_own_*``, :func:`.joint.loglik_at_truth`)."""
    if "chi2_generating_both" not in attrs:
        return []
    lines = [
        f"  at the generating point: chi2 {attrs['chi2_generating_both']:.4g} (run-ups "
        f"{attrs['chi2_generating_runup']:.4g}, load curve {attrs['chi2_generating_load']:.4g}) "
        f"under the fit's metric, the fit's {attrs['chi2']:.4g}"
    ]
    if "loglik_own_generating" in attrs:
        own = {k: attrs[f"loglik_own_{k}"] for k in ("generating", "estimate")}
        at, fit = own["generating"], own["estimate"]
        verdict = (
            f"more than {THRESHOLD:.3g} below: the estimate is not the likelihood's maximum"
            if generating_point_better(own)
            else f"not more than {THRESHOLD:.3g} below"
        )
        lines.append(
            f"  with each point's own covariance: -2 log L {at:.4g} at the generating point, "
            f"{fit:.4g} at the estimate; {verdict}"
        )
    return lines
