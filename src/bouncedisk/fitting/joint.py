"""The joint fit's own steps (:mod:`.loadpart` holds its likelihood): the load curves checked
against the run-ups, the scan's acceptable points judged against the load curves, the
identifiability intervals (each data set alone, on the same evaluations) and the fitted load
curve's band.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ..io.curve_files import stated_u0
from ..io.load_curves import LoadCurveData
from ..io.runup_curves import MotorCurve
from ..model.errors import InputError
from .loadpart import LOAD_PILOT, LoadPart, Setup, amplitudes, check_window, convert, setup
from .loadpart import band as load_band
from .members import EnsembleSpec
from .objective import Objective, snap
from .uncertainty import (
    THRESHOLD,
    Profile,
    all_profiles,
    birge,
    chi2_level,
    consistent_points,
    fit_limit,
)


class FitSizes(Protocol):
    """The fit's settings :func:`load_result` reads (:class:`.core.FitSettings` has them)."""

    members: int
    pilot_members: int
    profile: tuple[str, ...] | None


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
    chi2_generating: dict[str, float] | None = None  # "runup", "load", "both" at the truth
    #: ``−2 log L`` with each point's own covariance (:meth:`.objective.Objective.own_loglik`)
    #: at the truth and at the estimate: "generating", "estimate"
    loglik_own: dict[str, float] | None = None
    reference: Setup | None = None  # the condition the parameters are stated at (the load part's)


#: The generating parameters a synthetic load curve's sidecar must state to be compared with.
TRUTH_KEYS = ("e", "r_phi", "psi", "omega_s")


def stated_truth(curves: list[LoadCurveData], reference: Setup | None = None) -> dict[str, float]:
    """Generating parameters stated by a synthetic load curve's sidecar (empty otherwise), at
    the ``reference`` condition (the load part's, :attr:`.loadpart.LoadPart.reference`): a curve
    of another condition states its own ``ω_s`` and ``R_φ`` (:func:`.loadpart.convert`)."""
    for d in curves:
        gen = d.sidecar.get("generating_parameters") if d.synthetic else None
        if isinstance(gen, dict) and all(k in gen for k in TRUTH_KEYS):
            # the restitution noise too, when stated (a fitted coordinate)
            out = {k: float(gen[k]) for k in (*TRUTH_KEYS, "e_sigma") if k in gen}
            if reference is not None:
                theta = {**out, "log10_r_phi": math.log10(out["r_phi"])}
                theta = convert(theta, setup(d, reference.u0 is not None), reference)
                out["omega_s"], out["r_phi"] = theta["omega_s"], 10.0 ** theta["log10_r_phi"]
            return out
    return {}


def truth_coordinate(attrs: dict, name: str) -> float | None:
    """The generating value of search coordinate ``name`` from ``generating_*`` attributes
    (``log10_r_phi`` from ``generating_r_phi``); ``None`` when not stated."""
    if name.startswith("log10_"):
        v = attrs.get(f"generating_{name[6:]}")
        return math.log10(v) if v is not None and v > 0 else None
    v = attrs.get(f"generating_{name}")
    return float(v) if v is not None else None


def generating_x(obj: Objective) -> np.ndarray | None:
    """The generating point a synthetic load curve states, in the objective's coordinates
    (``None`` when none is stated)."""
    truth = stated_truth(obj.load.curves, obj.load.reference)
    gen = {f"generating_{k}": v for k, v in truth.items()}
    x = [truth_coordinate(gen, n) for n in obj.names]
    return None if any(v is None for v in x) else snap(np.array(x, float))


def unlogged(obj: Objective, read: Callable[[], dict[str, float]]) -> dict[str, float]:
    """``read()``, its evaluations neither logged, kept in the cache nor counted, so it changes
    no estimate and no count of evaluations."""
    cached, seen, logged = set(obj.cache), set(obj.read), len(obj.log)
    try:
        return read()
    finally:
        for key in set(obj.cache) - cached:
            del obj.cache[key]
        obj.read.intersection_update(seen)
        del obj.log[logged:]


def chi2_at_truth(obj: Objective, members: int) -> dict[str, float] | None:
    """``χ²`` of the run-ups, the load curves and both at the generating point a synthetic
    load curve states, under the fit's final metric (``None`` when none is stated), not logged
    (:func:`unlogged`).

    Far above the fit's own ``χ²`` with the generating point's own covariance low too
    (:func:`loglik_at_truth`), the held metric, measured in another regime, misreads it; far
    above it on both, the model or its likelihood does not describe the data.
    """
    x = generating_x(obj)
    if x is None:
        return None
    return unlogged(
        obj, lambda: {p: obj.seeing(p).chi2_now(x, members) for p in ("runup", "load", "both")}
    )


def loglik_at_truth(
    obj: Objective, estimate: np.ndarray, members: int, load_members: int
) -> dict[str, float] | None:
    """``−2 log L`` with each point's own covariance (:meth:`.objective.Objective.own_loglik`,
    both data sets, the run-ups' on ``members`` members and the load curves' on
    ``load_members``: as many as measure the held metrics) at the generating point a synthetic
    load curve states and at the estimate (``None`` when none is stated), not logged
    (:func:`unlogged`). :func:`generating_point_better` reads them."""
    x = generating_x(obj)
    if x is None:
        return None
    both = obj.seeing("both")
    return unlogged(
        obj,
        lambda: {
            "generating": both.own_loglik(x, members, load_members),
            "estimate": both.own_loglik(snap(estimate), members, load_members),
        },
    )


def generating_point_better(loglik_own: dict[str, float]) -> bool:
    """Whether the generating point is more likely than the estimate: its ``−2 log L`` with its
    own covariance (:func:`loglik_at_truth`) below the estimate's by more than the 95 % point of
    ``χ²(1)`` (:data:`.uncertainty.THRESHOLD`), a margin for the members' noise in both readings.

    Then the estimate is not the likelihood's maximum: the search missed a better basin, or the
    ``χ²`` it minimizes under the held metric peaks away from the likelihood
    (docs/fitting_method.md "Generating point"). Unlike ``χ²`` under the held metric, this
    reading does not favour the regime the metric was measured in. The estimate's members are those the
    search chose it on, which reads it low: "better" is the safe side of the verdict.
    """
    return loglik_own["generating"] < loglik_own["estimate"] - THRESHOLD


def load_part(
    curves: list[LoadCurveData],
    fitted: MotorCurve,
    spec: EnsembleSpec,
    progress: Callable[[str], None] | None = None,
) -> LoadPart | None:
    """The load curves' part of the likelihood (``None`` without load curves), after checking
    that the run-ups state ``Φ0`` (the torque scale needs it). Each curve is read at its own
    condition (:meth:`.loadpart.LoadPart.condition`); the reference is the run-ups' drive and
    ``Φ0`` with the rotor and preload of the curves run at them (:func:`.loadpart.reference_setup`),
    and their amplitude where the curves state different ones (:func:`.loadpart.amplitudes`)."""
    if not curves:
        return None
    for d in curves:
        check_window(d)
        if fitted.phi0_rad is None:
            raise InputError(
                d.path,
                "motor.Phi0_rad",
                "the run-ups' sidecar must state Phi0_rad "
                "for a joint fit with a load curve (its torque scale needs it)",
            )
    return LoadPart(
        curves,
        spec.e_sigma,
        spec.seed,
        cores=spec.cores,
        progress=progress,
        drive_hz=fitted.drive_frequency_hz,
        phi0_rad=fitted.phi0_rad,
        u0=reference_u0(curves, fitted),
    )


def reference_u0(curves: list[LoadCurveData], fitted: MotorCurve) -> float | None:
    """The run-ups' stated axial amplitude where the curves' amplitudes are conditions, else
    ``None`` (:func:`.loadpart.amplitudes`; one line naming a curve that states none, when some
    differ)."""
    u0 = stated_u0(fitted.sidecar)
    return u0 if amplitudes(curves, u0, fitted.sidecar_path or fitted.path) else None


def joint_consistent(obj: Objective, members: int, best_chi2: float) -> np.ndarray:
    """The joint candidates (:func:`.search.joint_candidates`: scan points that reproduce the
    run-ups, as they are, with ``R_φ`` moved to the load curve's torque scale, and the joint
    zoom around the best) that reproduce both data sets on ``members`` members: ``χ²`` below the
    95 % point of ``χ²(n)``, scaled as the intervals are (:func:`.uncertainty.birge_scale`). The
    residuals are already whitened for ``members`` members (the run-ups' by
    ``sqrt(1/M + 1/k)``, the load curves' by ``D + C_L/k``), so no further factor for the few
    members is due. Every basin among them widens the joint intervals."""
    limit = fit_limit(best_chi2, obj.n_stats, len(obj.names))
    pts = {
        tuple(ev.x): ev.x
        for ev in obj.log
        if ev.members == members and ev.parts == "both" and ev.chi2 <= limit
    }
    return np.array(list(pts.values())).reshape(-1, len(obj.names))


def identifiability(
    obj: Objective, x: np.ndarray, members: int, which: list[str] | None, reread: np.ndarray
) -> dict[str, list[Profile]]:
    """The 95 % interval of every coordinate from the run-ups alone and from the load curves
    alone: profiles of each part's ``χ²`` about the joint estimate ``x``, on the same cached
    evaluations (the scan's candidates ``reread`` among them, :func:`.search.confirm_points`),
    measured from that part's level at ``x`` (:func:`.uncertainty.chi2_level`) and widened to the
    candidates that part finds consistent (:func:`.uncertainty.consistent_points`). A flat
    profile is "not identified", as in the joint fit."""
    out = {}
    for part in ("runup", "load"):
        view = obj.seeing(part)
        best = view.best(members).chi2
        thr = birge(best, view.n_stats, len(view.names))
        level = chi2_level(view, x, members)
        ok = consistent_points(view, reread, members, best)
        out[part] = all_profiles(view, x, members, which, None, thr, ok, level)[0]
    return out


def load_result(
    obj: Objective,
    x: np.ndarray,
    settings: FitSizes,
    profiles: list[Profile],
    reread: np.ndarray,
    progress: Callable[[str], None] | None,
) -> LoadFit:
    """The joint fit's load part: identifiability intervals (on ``settings.members``, for the
    coordinates ``settings.profile``), the fitted load curve's band and the load part's ``χ²``
    at the estimate; for synthetic data the generating point read too, its own likelihood on
    ``settings.pilot_members`` run-up members (:func:`loglik_at_truth`)."""
    part, members = obj.load, settings.members
    which = settings.profile and list(settings.profile)
    intervals = identifiability(obj, x, members, which, reread)
    intervals["both"] = profiles
    if progress is not None:
        for j, name in enumerate(p.name for p in profiles):
            cells = [
                f"{k} [{intervals[k][j].ci_low:.4g}, {intervals[k][j].ci_high:.4g}]"
                for k in ("runup", "load", "both")
            ]
            progress(f"identifiability {name}: " + "; ".join(cells))
    xs = snap(x)
    theta = obj.theta(xs)
    chi2_load = obj.seeing("load").chi2_now(xs, members)
    return LoadFit(
        curves=part.curves,
        band=load_band(part, theta, xs),
        chi2=chi2_load,
        n=part.n,
        intervals=intervals,
        data_var=part.data_var(),
        chi2_generating=chi2_at_truth(obj, members),
        loglik_own=loglik_at_truth(obj, xs, settings.pilot_members, LOAD_PILOT),
        reference=part.reference,
    )
