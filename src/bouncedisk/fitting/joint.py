"""The joint fit's own steps (:mod:`.loadpart` holds its likelihood): the load curves checked
against the run-ups, the scan's acceptable points judged against the load curves, the
identifiability intervals (each data set alone, on the same evaluations) and the fitted load
curve's band.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import stats as _sps

from ..io.load_curves import LoadCurveData, check_same_setup
from ..io.runup_curves import MotorCurve
from ..model.errors import InputError
from .loadpart import LoadPart
from .loadpart import band as load_band
from .model import EnsembleSpec
from .objective import Objective, snap
from .uncertainty import Profile, all_profiles, birge


@dataclass
class LoadFit:
    """The load curves of a joint fit: the data, the fitted model's band at every measured load,
    the load part's ``χ²``, and the intervals from each data set alone (identifiability)."""

    curves: list[LoadCurveData]
    band: dict[str, np.ndarray]
    chi2: float
    n: int
    intervals: dict[str, list[Profile]]  # "runup", "load", "both" -> one profile per coordinate
    data_var: np.ndarray


def load_part(
    curves: list[LoadCurveData], fitted: MotorCurve, spec: EnsembleSpec
) -> LoadPart | None:
    """The load curves' part of the likelihood (``None`` without load curves), after checking
    that they share the run-ups' drive and state ``Φ0`` (the torque scale needs it)."""
    if not curves:
        return None
    for d in curves:
        check_same_setup(d, fitted.drive_frequency_hz, fitted.phi0_rad)
        if fitted.phi0_rad is None:
            raise InputError(d.path, "motor.Phi0_rad", "the run-ups' sidecar must state Phi0_rad "
                             "for a joint fit with a load curve (its torque scale needs it)")  # fmt: skip
    return LoadPart(curves, spec.e_sigma, spec.seed, cores=spec.cores)


def joint_consistent(obj: Objective, members: int, best_chi2: float) -> np.ndarray:
    """The joint candidates (:func:`.search.joint_candidates`: scan points that reproduce the
    run-ups, as they are, with ``R_φ`` moved to the load curve's torque scale, and the joint
    zoom around the best) that reproduce both data sets on ``members`` members: ``χ²`` below the
    95 % point of ``χ²(n)``, scaled by the best fit's ``χ²/n`` when that exceeds 1 (Birge). The
    residuals are already whitened for ``members`` members (the run-ups' by
    ``sqrt(1/M + 1/k)``, the load curves' by ``D + C_L/k``), so no further factor for the few
    members is due. Every basin among them widens the joint intervals."""
    scale = max(1.0, best_chi2 / obj.n_stats)
    limit = scale * float(_sps.chi2.ppf(0.95, obj.n_stats))
    pts = {tuple(ev.x): ev.x for ev in obj.log
           if ev.members == members and ev.parts == "both" and ev.chi2 <= limit}  # fmt: skip
    return np.array(list(pts.values())).reshape(-1, len(obj.names))


def identifiability(
    obj: Objective, x: np.ndarray, members: int, which: list[str] | None, extra_runup: np.ndarray
) -> dict[str, list[Profile]]:
    """The 95 % interval of every coordinate from the run-ups alone and from the load curves
    alone: profiles of each part's ``χ²`` about the joint estimate ``x``, on the same cached
    evaluations, widened to that part's acceptable points (the scan's for the run-ups: it fitted
    them). A flat profile is "not identified", as in the joint fit."""
    out = {}
    saved = obj.parts
    try:
        for part, extra in (("runup", extra_runup), ("load", None)):
            obj.parts = part
            thr = birge(obj.best(members).chi2, obj.n_stats, len(obj.names))
            out[part] = all_profiles(obj, x, members, which, None, thr, extra)[0]
    finally:
        obj.parts = saved
    return out


def load_result(
    obj: Objective, x: np.ndarray, members: int, which: list[str] | None,
    profiles: list[Profile], extra_runup: np.ndarray, progress: Callable[[str], None] | None,
) -> LoadFit:  # fmt: skip
    """The joint fit's load part: identifiability intervals, the fitted load curve's band and
    the load part's ``χ²`` at the estimate."""
    part = obj.load
    intervals = identifiability(obj, x, members, which, extra_runup)
    intervals["both"] = profiles
    if progress is not None:
        for j, name in enumerate(p.name for p in profiles):
            cells = [f"{k} [{intervals[k][j].ci_low:.4g}, {intervals[k][j].ci_high:.4g}]"
                     for k in ("runup", "load", "both")]  # fmt: skip
            progress(f"identifiability {name}: " + "; ".join(cells))
    xs = snap(x)
    theta = obj.theta(xs)
    saved, obj.parts = obj.parts, "load"
    try:
        chi2_load = obj.chi2_now(xs, members)
    finally:
        obj.parts = saved
    return LoadFit(curves=part.curves, band=load_band(part, theta, xs), chi2=chi2_load, n=part.n,
                   intervals=intervals, data_var=part.data_var())  # fmt: skip
