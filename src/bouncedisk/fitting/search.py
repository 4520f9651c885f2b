"""Global-then-local search of the synthetic likelihood (:mod:`.objective`).

1. A Sobol scan of the ``(e, omega_s)`` plane (the axial motion depends on nothing else, and the
   landscape is rugged there: periodic windows); at every scan point ``ψ`` is chosen from a grid
   and ``R_φ`` matched to the trend, on cheap ensembles (``global_members``) and the robust loss
   ``Σ log(1 + r²)`` with provisional scales (a block bootstrap of the data). A zoom then samples
   the same way around the best distinct scan points (``zoom`` points each, one scan spacing
   wide): a periodic window narrower than the scan's spacing is found from a neighbour.
2. A pilot ensemble (``pilot_members``) at the best point measures the model's across-member
   covariance ``C`` (with ``e_sigma`` fitted, at ``e_sigma >= 1e-8``: :func:`metric_point`); the
   objective switches to it. The best ``candidates`` distinct scan points are re-ranked on
   ``members`` members (one member is a noisy estimate where the model is chaotic), ``C`` is
   measured again at the best of them. With load curves the candidates are the scan points that
   reproduce the run-ups, each also with ``R_φ`` moved to the load curve's torque scale and,
   with ``e_sigma`` fitted, each also at the noise levels of :data:`CANDIDATE_NOISE`
   (:func:`at_noise_levels`), and a joint zoom around the best of them
   (:func:`joint_candidates`, :func:`joint_zoom`), ranked by the joint ``χ²``; when none of them
   reproduces both data sets, shrinking patches in ``(e, ψ, omega_s)`` from the best run-up
   candidates and a walk along the valley they reach (:func:`joint_refine`,
   :func:`valley_walk`).
3. :func:`scipy.optimize.least_squares` on the whitened residuals, in coordinates scaled to the
   search box, from each of the best few re-ranked points (multi-start); with ``e_sigma`` fitted,
   a sweep of it (:func:`noise_sweep`); for a joint fit with ``e_sigma`` fitted or stated 0, the
   walk along the deterministic limit's valley (:mod:`.limit_walk`); then ``C`` is measured
   again at the best point (the walk's only if it gained more than
   :data:`.limit_walk.WALK_GAIN`) and the search polished.

Every evaluation is logged, and the result is the best logged point at the final ensemble size
under the final metric: the search never returns a point worse than one it evaluated.

Round-off chooses nothing (docs/user_guide/reproducible.md): the objective evaluates on a lattice
(:func:`.objective.snap`) with BLAS-free reductions, and every ranking of candidates (scan, zoom,
re-ranking, starts, the result) uses the total order :func:`.likelihood_basins.rank_key`, the same whatever
order the threads logged the points in.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import qmc

from .likelihood_basins import rank_key
from .likelihood_basins import ranked as rank_order
from .limit_walk import WALK_GAIN, deterministic_walk
from .loadpart import LOAD_PILOT
from .objective import SNAP_DECIMALS, Evaluation, Objective, snap
from .summary_stats import regularized_cov, stat_floor

#: Allowed sizes of the scan and of the zoom around each centre (``bouncedisk fit --scan/--zoom``,
#: the pipeline's ``prototype.scan/zoom``; the config schema states the same bounds, tested).
SIZE_LIMITS: dict[str, tuple[int, int]] = {"scan": (8, 100_000), "zoom": (0, 100_000)}


@dataclass(frozen=True)
class SearchSettings:
    """Sizes of the search stages (see the module docstring); the defaults of the fit's own
    settings (:class:`~bouncedisk.fitting.core.FitSettings` takes them from here, the one place),
    with the ensemble sizes of one run-up."""

    seed: int = 12345
    scan: int = 192
    global_members: int = 1
    members: int = 12
    pilot_members: int = 32
    local_nfev: int = 12
    zoom: int = 16
    zoom_centres: int = 6
    candidates: int = 24
    starts: int = 4
    joint_zoom: int = 48  # points around each joint candidate (:func:`joint_zoom`)

    def __post_init__(self) -> None:
        for name, (low, high) in SIZE_LIMITS.items():
            if not low <= getattr(self, name) <= high:
                raise ValueError(
                    f"{name} must be between {low} and {high}, got {getattr(self, name)}"
                )


def _say(progress: Callable[[str], None] | None, msg: str) -> None:
    if progress is not None:
        progress(msg)


#: Coordinates set by matching the trend (:func:`matched_point`), not searched globally.
MATCHED = ("log10_r_phi", "log10_speed_scale")


def matched_point(obj: Objective, x: np.ndarray, members: int, steps: int = 2) -> np.ndarray:
    """Move ``log10 R_φ`` (and the free speed scale) so the trend matches the data's.

    docs/model.md's scaling: ``x = R_φ Ω`` evolves at a rate ``∝ R_φ`` while the axial motion does
    not depend on ``R_φ``, so the time constant goes like ``1/R_φ`` and the steady speed barely
    moves with it; with Φ0 unknown the speed in rad/s is proportional to the speed scale.
    ``steps`` such corrections, each one evaluation; the point with the best robust loss is kept.
    """
    x = np.clip(np.asarray(x, float), obj.lo, obj.hi)
    best, best_loss = x, obj.robust(x, members)
    for _ in range(steps):
        x = _matched_step(obj, x, members)
        loss = obj.robust(x, members)
        if loss < best_loss:
            best, best_loss = x, loss
    return best


def _matched_step(obj: Objective, x: np.ndarray, members: int) -> np.ndarray:
    """One correction of :func:`matched_point` from ``x`` (inside the range)."""
    names = obj.names
    m = obj.ensemble(x, members).mean
    x = x.copy()
    if "log10_r_phi" in names:
        j = names.index("log10_r_phi")
        x[j] += (m[1] - obj.target[1]) / np.log(10.0)
    if "log10_speed_scale" in names and m[0] * obj.target[0] > 0:
        j = names.index("log10_speed_scale")
        x[j] += np.log10(obj.target[0] / m[0])
    return np.clip(x, obj.lo, obj.hi)


#: ψ values tried at every (e, omega_s) point of the scan (the trend's smooth dependence).
PSI_GRID = 8
#: Least-squares evaluations refining (ψ, R_φ) at every scan point.
INNER_NFEV = 6
#: Grid points of ψ refined at every scan point.
INNER_STARTS = 2


def _inner(obj: Objective, x: np.ndarray, members: int) -> np.ndarray:
    """Best ``(ψ, R_φ)`` for fixed ``(e, omega_s)``: a ψ grid, each with a trend-matched ``R_φ``.

    The axial motion depends only on ``(e, omega_s)`` (torsion never feeds back), so at a fixed
    ``(e, omega_s)`` the statistics are smooth in ``ψ`` and scale simply with ``R_φ``
    (docs/model.md); the rugged part of the problem is the 2-D ``(e, omega_s)`` plane only.
    """
    names = obj.names
    if "psi" not in names:
        return matched_point(obj, x, members, steps=1)
    j = names.index("psi")
    starts = []
    for psi in np.linspace(-np.pi, np.pi, PSI_GRID, endpoint=False):
        y = np.clip(x, obj.lo, obj.hi)
        y[j] = psi
        starts.append(y)
    # the grid and its matched points, each set from one axial run per member (Objective.prefetch)
    obj.prefetch(starts, members)
    obj.prefetch([_matched_step(obj, y, members) for y in starts], members)
    grid = []
    for y in starts:
        y = matched_point(obj, y, members, steps=1)
        grid.append((obj.robust(y, members), y))
    grid.sort(key=lambda g: g[0])
    # refine (ψ, R_φ [, speed scale]) by least squares from the best INNER_STARTS grid points:
    # the grid step is far coarser than the steady speed's sensitivity to ψ
    best, best_chi2 = grid[0][1], obj.chi2(grid[0][1], members)
    for _, start in grid[:INNER_STARTS]:
        y, c = polish(obj, start, members, INNER_NFEV)
        if c < best_chi2:
            best, best_chi2 = y, c
    return best


def polish(
    obj: Objective, start: np.ndarray, members: int, nfev: int, own: bool = False
) -> tuple[np.ndarray, float]:
    """``(ψ, R_φ [, speed scale])`` refined by least squares from ``start`` at its fixed
    ``(e, omega_s)`` (at most ``nfev`` evaluations, not logged), on the held metric or, ``own``,
    on each point's own covariance (:meth:`.objective.Objective.own_residuals`); the end point's
    ``χ²`` (held metric), logged."""
    free = [k for k, n in enumerate(obj.names) if n in ("psi", *MATCHED)]
    read = obj.own_residuals if own else obj.residuals

    def at(u):
        return obj.from_unit(u, start, free)

    def fun(u):
        return read(at(u), members)

    def step(u):
        # with the points where the Jacobian after an accepted step reads: one axial run
        obj.prefetch([at(v) for v in (u, *difference_points(u, DIFF_STEP))], members)
        return fun(u)

    def differences(f, us):
        # the Jacobian's points (``step`` prefetched them when right) share (e, omega_s): one
        # axial run per member for all; read with ``fun``, not with ``f`` (scipy's wrapper of
        # ``step``), which would prefetch the differences of the differences
        us = list(us)
        obj.prefetch([at(u) for u in us], members)
        return [fun(u) for u in us]

    res = least_squares(
        step,
        obj.to_unit(start, free),
        bounds=(0.0, 1.0),
        diff_step=DIFF_STEP,
        max_nfev=nfev,
        workers=differences,
    )
    y = at(res.x)
    return y, obj.chi2(y, members)


#: Relative step of :func:`polish`'s forward differences, in the unit box.
DIFF_STEP = 1e-3


def difference_points(u: np.ndarray, rel_step: float) -> list[np.ndarray]:
    """Where a forward-difference Jacobian at ``u`` in the unit box reads the function.

    scipy's ``approx_derivative`` (``'2-point'``, relative step, bounds ``[0, 1]``):
    ``h_i = rel_step · sign(u_i) · |u_i|`` (``√ε · max(1, |u_i|)`` where that step vanishes),
    turned back where it leaves the box and fits on the other side, else the distance to the
    farther bound; the points are ``u + h_i e_i``. :func:`polish` evaluates them with ``u``, so a
    point predicted wrongly costs a share of a run, never a different result.
    """
    u = np.asarray(u, float)
    sign = np.where(u >= 0.0, 1.0, -1.0)
    h = rel_step * sign * np.abs(u)
    h = np.where(
        (u + h) - u == 0.0, np.sqrt(np.finfo(float).eps) * sign * np.maximum(1.0, np.abs(u)), h
    )
    lower, upper = u, 1.0 - u
    fits = np.abs(h) <= np.maximum(lower, upper)
    h = np.where(((u + h < 0.0) | (u + h > 1.0)) & fits, -h, h)
    h = np.where(fits, h, np.where(upper >= lower, upper, -lower))
    pts = []
    for i in range(len(u)):
        v = u.copy()
        v[i] = u[i] + h[i]
        pts.append(v)
    return pts


#: Most candidate points re-read on the fit's members (:func:`confirm_points`).
CONFIRM_CAP = 128
#: Least-squares evaluations refining ``(ψ, R_φ)`` of a re-read candidate (:func:`polish`).
CONFIRM_NFEV = 4


def _cheap_scores(obj: Objective) -> dict[tuple, float]:
    """Every logged point's lowest ``χ²`` per statistic (of the data its evaluation saw)."""
    n = {p: obj.seeing(p).n_stats for p in {ev.parts for ev in obj.log}}
    out: dict[tuple, float] = {}
    for ev in obj.log:
        key = tuple(ev.x)
        out[key] = min(out.get(key, np.inf), ev.chi2 / max(1, n[ev.parts]))
    return out


def confirm_points(
    obj: Objective,
    points: np.ndarray,
    members: int,
    near: float = np.inf,
    near_own: float = np.inf,
) -> np.ndarray:
    """Re-read the candidate ``points`` (the scan's, read on one member) on the fit's
    ``members`` members, so that :func:`.uncertainty.acceptable_points` judges them like every
    other point: the scan's own reading, one member against the data, accepts points the fit's
    members reject. A candidate whose ``χ²`` there is at most ``near`` has its ``(ψ, R_φ)``
    refined (:func:`polish`), and one whose ``χ²`` on its own covariance is at most
    ``near_own`` refined on that: a nuisance matched on one member is not matched on many. At
    most :data:`CONFIRM_CAP`: those read best per statistic so far, when there are more. Returns
    the points re-read and the polished ones."""
    pts = np.unique(snap(np.asarray(points, float)).reshape(-1, len(obj.names)), axis=0)
    if len(pts) > CONFIRM_CAP:
        score = _cheap_scores(obj)
        order = sorted(
            range(len(pts)), key=lambda i: rank_key(score.get(tuple(pts[i]), np.inf), pts[i])
        )
        pts = pts[np.sort(order[:CONFIRM_CAP])]

    def one(x: np.ndarray) -> list[np.ndarray]:
        out = [x]
        if obj.chi2(x, members) <= near:
            out.append(polish(obj, x, members, CONFIRM_NFEV)[0])
        if obj.own_chi2(x, members) <= near_own:
            out.append(polish(obj, x, members, CONFIRM_NFEV, own=True)[0])
        return out

    done = obj.map(one, list(pts))
    return np.array([y for ys in done for y in ys]).reshape(-1, len(obj.names))


def global_stage(
    obj: Objective, s: SearchSettings, progress: Callable[[str], None] | None = None
) -> list[Evaluation]:
    """Scan the rugged ``(e, omega_s)`` plane, with ``(ψ, R_φ)`` fitted at every point.

    A Sobol sample of ``s.scan`` points of ``(e, omega_s)``; at each, :func:`_inner` chooses
    ``ψ`` from a grid and matches ``R_φ`` (and a free speed scale) to the trend. Cheap ensembles
    (``global_members``) under the provisional metric. Returns the logged cheap evaluations, best
    first (by ``χ²`` under the provisional metric).
    """
    names = obj.names
    axial = [names.index("e"), names.index("omega_s")]
    base = 0.5 * (obj.lo + obj.hi)
    if "log10_r_phi" in names:
        base[names.index("log10_r_phi")] = -2.5
    if "e_sigma" in names:  # fitted: the scan at the stated value, the local search moves it
        base[names.index("e_sigma")] = obj.spec.e_sigma

    def at(units: np.ndarray) -> list[np.ndarray]:
        pts = []
        for u in units:
            x = base.copy()
            x[axial] = obj.lo[axial] + np.clip(u, 0.0, 1.0) * obj.span[axial]
            pts.append(x)
        return pts

    ranked = _scan(obj, at(_sobol(s.scan, s.seed)), s.global_members, "scan", progress)
    if s.zoom > 0 and s.zoom_centres > 0:
        # narrow basins (periodic windows) fall between scan points: sample around the best
        half = 1.0 / np.sqrt(s.scan)
        patch = (2.0 * _sobol(s.zoom, s.seed + 1) - 1.0) * half
        units = [
            (ev.x[axial] - obj.lo[axial]) / obj.span[axial] + patch
            for ev in _distinct(ranked, obj.span, s.zoom_centres)
        ]
        ranked = _scan(obj, at(np.concatenate(units)), s.global_members, "zoom", progress)
    return ranked


def _sobol(n: int, seed: int, dim: int = 2) -> np.ndarray:
    """``n`` scrambled Sobol points of the unit square (cube for ``dim`` 3; seeded)."""
    with warnings.catch_warnings():
        # any size is allowed; the balance that scipy warns about is exact only at powers of
        # two, the low discrepancy holds
        warnings.filterwarnings("ignore", "The balance properties of Sobol", UserWarning)
        return qmc.Sobol(dim, seed=seed).random(n)


def _scan(
    obj: Objective,
    pts: list[np.ndarray],
    members: int,
    label: str,
    progress: Callable[[str], None] | None,
) -> list[Evaluation]:
    """:func:`_inner` at every point (in chunks, on the objective's threads); all cheap
    evaluations logged so far, best first."""
    chunk = 32
    for i in range(0, len(pts), chunk):
        obj.map(lambda x: _inner(obj, x, members), pts[i : i + chunk])
        best = min(ev.chi2 for ev in obj.log if ev.members == members)
        _say(
            progress,
            f"{label}: {min(i + chunk, len(pts))}/{len(pts)} (e, omega_s) points, "
            f"best chi2 {best:.4g}",
        )
    return sorted(
        (ev for ev in obj.log if ev.members == members), key=lambda ev: rank_key(ev.chi2, ev.x)
    )


#: The least restitution noise a covariance is measured at (:func:`metric_point`): the objective's
#: smallest nonzero ``e_sigma`` (its lattice, :func:`.objective.snap`, rounds the model's
#: natural-measure noise ``1e-9`` to 0); like it, physically nothing, enough to sample the
#: natural measure.
METRIC_E_SIGMA = 10.0**-SNAP_DECIMALS


def measure_cov(obj: Objective, x: np.ndarray, members: int) -> np.ndarray:
    """Regularized across-member covariance of the statistics at ``x`` (``members`` members).

    With load curves the load part's covariance ``C_L`` is measured at ``x`` too (its
    :data:`.loadpart.LOAD_PILOT` members) and held from now on. A fitted ``e_sigma`` is measured
    at :data:`METRIC_E_SIGMA` at least (:func:`metric_point`).
    """
    x = metric_point(obj, x)
    ens = obj.ensemble(x, members)
    if obj.load is not None:
        xs = snap(x)
        obj.load.set_cov(obj.load.values(obj.theta(xs), xs, LOAD_PILOT))
    return regularized_cov(ens.cov, stat_floor(obj.target))


def metric_point(obj: Objective, x: np.ndarray) -> np.ndarray:
    """Where the covariance of ``x`` is measured: ``x`` with a fitted ``e_sigma`` raised to
    :data:`METRIC_E_SIGMA` (docs/model.md "Long-run statistics of chaotic motion").

    At ``e_sigma = 0`` every member runs the same orbit, so a chaotic motor's members coincide
    and their covariance holds the reading noise only: measured there, the metric can make a
    chaotic motor's generating point read a ``χ²`` of millions and the fit inadequate. At
    :data:`METRIC_E_SIGMA` a chaotic point's members part (``tests/test_joint_fit.py``), as at
    the model's natural-measure ``1e-9``, while a periodic motor's converge to one orbit.
    """
    if "e_sigma" not in obj.names:
        return x
    j = obj.names.index("e_sigma")
    out = np.array(x, float)
    out[j] = max(out[j], METRIC_E_SIGMA)
    return out


def joint_candidates(
    obj: Objective,
    ranked: list[Evaluation],
    s: SearchSettings,
    progress: Callable[[str], None] | None = None,
) -> list[np.ndarray]:
    """The scan points to refine: with load curves, every distinct scan point that reproduces
    the run-ups (:func:`.uncertainty.scan_acceptable`), also at each noise level with ``e_sigma``
    fitted (:func:`at_noise_levels`), as it is and with its ``R_φ`` moved to the load curve's
    torque scale (:func:`load_matched`), re-ranked by the joint ``χ²`` on the scan's ensemble
    size — the run-ups leave a valley of points that reproduce them, the load curve picks along
    it; without load curves, the best ``s.candidates`` distinct scan points. When no candidate,
    nor any point of the joint zoom, reproduces both data sets (:func:`joint_missed`), the best
    run-up candidates are refined into the joint valley (:func:`joint_refine`)."""
    if obj.load is None:
        return [ev.x for ev in _distinct(ranked, obj.span, s.candidates)]
    from .uncertainty import scan_acceptable

    ok = {tuple(x) for x in scan_acceptable(obj, s.global_members)}
    pool = [ev.x for ev in _distinct([ev for ev in ranked if tuple(ev.x) in ok], obj.span, len(ok))]
    runup = pool or [ev.x for ev in _distinct(ranked, obj.span, s.candidates)]  # best first
    runup = runup + at_noise_levels(obj, runup)
    # each point as the run-ups matched it and with R_phi moved to the load curve's torque scale
    pool = runup + obj.map(lambda x: load_matched(obj, x), runup)
    scores = obj.map(lambda x: obj.chi2(x, s.global_members), pool)
    near = joint_zoom(obj, [pool[i] for i in rank_order(scores, pool)], s)
    pool = pool + near
    scores = scores + obj.map(lambda x: obj.chi2(x, s.global_members), near)
    if joint_missed(obj, scores):
        # no candidate reproduces both data sets: the joint valley lies between the scan's
        # points; refine the best run-up candidates (distinct in (e, omega_s)) into it
        _say(
            progress,
            f"no joint candidate reproduces both data sets (best chi2 "
            f"{min(scores):.4g} on {s.global_members} member(s)): the best run-up "
            "candidates refined into the joint valley",
        )
        more = joint_refine(obj, _distinct_axial(obj, runup, REFINE_CENTRES), s)
        pool = pool + [x for x, _ in more]
        scores = scores + [c for _, c in more]
    return [pool[i] for i in rank_order(scores, pool)[: s.candidates]]


#: Restitution noise levels at which a fitted ``e_sigma``'s joint candidates are read besides the
#: scan's stated one (:func:`at_noise_levels`), about every 0.03 of the range [0, 0.1]. Not 0,
#: the deterministic limit being the walk's (:mod:`.limit_walk`): without :func:`metric_point`,
#: a candidate at 0 would set the metric where a chaotic motor's members coincide.
CANDIDATE_NOISE = (0.01, 0.06, 0.09)


def at_noise_levels(obj: Objective, xs: list[np.ndarray]) -> list[np.ndarray]:
    """With ``e_sigma`` fitted: every point of ``xs`` again at each :data:`CANDIDATE_NOISE`
    level (none without).

    The scan reads the run-ups at the stated noise, and at fixed other coordinates the joint
    ``χ²`` is sharp in ``e_sigma`` (a change of 0.01 can multiply it several times), so a basin
    whose noise is far from the stated one is never a candidate; read at the levels, its load
    curve can make it one. More candidates then reproduce both data sets, so the joint
    refinement (:func:`joint_missed`) runs less often.
    """
    if "e_sigma" not in obj.names:
        return []
    return [y for x in xs for y in noise_copies(obj, x, CANDIDATE_NOISE)]


def noise_copies(obj: Objective, x: np.ndarray, levels: Sequence[float]) -> list[np.ndarray]:
    """Copies of ``x`` with its (fitted) ``e_sigma`` at each of ``levels``, the other
    coordinates as they are."""
    j = obj.names.index("e_sigma")
    out = []
    for v in levels:
        y = np.array(x, float)
        y[j] = v
        out.append(y)
    return out


def joint_missed(obj: Objective, scores: list[float]) -> bool:
    """Whether no joint candidate reproduces both data sets on the scan's ensemble size.

    A cheap candidate is one model realization against the data's, so it is consistent with the
    data when its ``χ²`` is below twice the 95 % point of ``χ²(n)``
    (:func:`.uncertainty.realization_limit`, as for the scan's points). Above that for every
    candidate, the search has not reached the joint valley.

    Parameters
    ----------
    obj : Objective
        The joint objective (``parts`` ``"both"``: ``n`` counts the run-ups' statistics and
        the readings).
    scores : list of float
        The candidates' joint ``χ²`` on the scan's ensemble size.

    Returns
    -------
    bool
        ``True`` when every score exceeds the limit.
    """
    from .uncertainty import realization_limit

    return min(scores) > realization_limit(obj.n_stats)


#: The joint refinement (:func:`joint_refine`): run-up candidates refined, independent chains
#: from each, levels of each chain and points of each level (its patch halves at every level).
REFINE_CENTRES = 2
REFINE_CHAINS = 2
REFINE_LEVELS = 6
REFINE_POINTS = 12
#: The valley walk (:func:`valley_walk`): steps each way along ``e`` and their length, as a
#: fraction of the range of ``e``; points of each step's two patches; the first patch's
#: half-widths across the valley, as fractions of the ranges of ``ψ`` and ``omega_s``.
WALK_STEPS = 5
WALK_STEP = 0.011
WALK_POINTS = 12
WALK_HALF = (0.016, 0.007)


def joint_refine(
    obj: Objective, centres: list[np.ndarray], s: SearchSettings
) -> list[tuple[np.ndarray, float]]:
    """Shrinking patches in ``(e, ψ, omega_s)`` from the best run-up candidates into the joint
    valley, then a walk along it (:func:`valley_walk`); every point evaluated, with its joint
    ``χ²`` on the scan's ensemble size.

    Near a bifurcation the joint valley is a thin tube along a curve of ``(e, ψ, omega_s)`` (the
    ``near_boundary`` recovery case: about 0.005 in ``e``, 0.02 in ``ψ`` and 0.002 in ``omega_s``
    across), narrower than the joint zoom's spacing, and ``ψ`` must move with ``(e, omega_s)``
    along it, which the zoom (``ψ`` held) cannot do. Each of :data:`REFINE_CHAINS` chains per
    centre samples a patch of :data:`REFINE_POINTS` points ``± JOINT_ZOOM_HALF`` of the ranges
    around its best point so far and halves the patch at each of :data:`REFINE_LEVELS` levels.
    A chain ends where it meets the tube, not where the tube is deepest, so the walk then
    follows the tube from the best point found.

    Parameters
    ----------
    obj : Objective
        The joint objective, its covariance the pilot's.
    centres : list of ndarray
        Run-up candidates (search coordinates), best first.
    s : SearchSettings
        Seed and the scan's ensemble size (``global_members``).

    Returns
    -------
    list of (ndarray, float)
        Every point evaluated (the chains' starts, their patches and the walk's) with its joint
        ``χ²``, in evaluation order.
    """
    ax = [obj.names.index(n) for n in ("e", "psi", "omega_s")]
    starts = [load_matched(obj, c) for c in centres for _ in range(REFINE_CHAINS)]
    chis = obj.map(lambda x: obj.chi2(x, s.global_members), starts)
    best = list(zip(starts, chis, strict=True))
    out = list(best)
    for level in range(REFINE_LEVELS):
        half = np.full(3, JOINT_ZOOM_HALF * 0.5**level)
        seeds = [s.seed + 3 + 97 * i + level for i in range(len(best))]
        found = _patches(obj, [c for c, _ in best], ax, half, seeds, REFINE_POINTS, s)
        best = [_best_of([b, *f]) for b, f in zip(best, found, strict=True)]
        out += [p for f in found for p in f]
    return out + valley_walk(obj, _best_of(best)[0], s)


def valley_walk(obj: Objective, start: np.ndarray, s: SearchSettings) -> list[tuple]:
    """Points along the joint valley from ``start``, both ways in ``e``, with their ``χ²``.

    The load curve pins ``omega_s`` (and with the run-ups ``ψ``) far more tightly than ``e``, so
    the valley is followed in steps of :data:`WALK_STEP` of the range of ``e``: at each, ``(ψ,
    omega_s)`` is predicted from the last two steps (linearly) and sampled by two patches across
    the valley, the second around the first's best at a quarter of its half-widths
    (:data:`WALK_HALF`). The walk goes on past worse steps (the landscape is rough on the
    scan's few members); the re-ranking on ``members`` members picks among all its points.

    Parameters
    ----------
    obj : Objective
        The joint objective.
    start : ndarray
        A point in the valley (search coordinates).
    s : SearchSettings
        Seed and the scan's ensemble size (``global_members``).

    Returns
    -------
    list of (ndarray, float)
        Every point evaluated with its joint ``χ²`` (at most ``2 · WALK_STEPS · 2 ·
        WALK_POINTS``; a walk stops at the range of ``e``).
    """
    ie, cross = obj.names.index("e"), [obj.names.index(n) for n in ("psi", "omega_s")]
    out: list[tuple] = []
    for sign in (-1.0, 1.0):
        prev, cur = None, start
        for k in range(WALK_STEPS):
            pred = cur.copy()
            pred[ie] = cur[ie] + sign * WALK_STEP * obj.span[ie]
            if not obj.lo[ie] <= pred[ie] <= obj.hi[ie]:
                break
            if prev is not None:
                slope = (cur[cross] - prev[cross]) / (cur[ie] - prev[ie])
                pred[cross] = cur[cross] + slope * (pred[ie] - cur[ie])
            half = np.array(WALK_HALF)
            for level in range(2):
                seed = s.seed + 5 + 31 * k + 2 * level + (sign > 0)
                found = _patches(obj, [pred], cross, half, [seed], WALK_POINTS, s)[0]
                out += found
                pred, half = _best_of(found)[0], half / 4.0
            prev, cur = cur, pred
    return out


def _patches(
    obj: Objective,
    centres: list[np.ndarray],
    dims: list[int],
    half: np.ndarray,
    seeds: list[int],
    n: int,
    s: SearchSettings,
) -> list[list[tuple[np.ndarray, float]]]:
    """``n`` Sobol points ``± half`` of the ranges in coordinates ``dims`` around each centre
    (its own seed), ``R_φ`` load-matched, with their joint ``χ²`` on the scan's ensemble size;
    all centres' points evaluated together (threads). One list of ``(x, χ²)`` per centre."""
    batch = []
    for c, seed in zip(centres, seeds, strict=True):
        batch += _around(obj, c, dims, (2.0 * _sobol(n, seed, len(dims)) - 1.0) * half)
    batch = obj.map(lambda x: load_matched(obj, x), batch)
    chis = obj.map(lambda x: obj.chi2(x, s.global_members), batch)
    pairs = list(zip(batch, chis, strict=True))
    return [pairs[i * n : (i + 1) * n] for i in range(len(centres))]


def _around(obj: Objective, c: np.ndarray, dims: list[int], offsets: np.ndarray) -> list:
    """``c`` moved by each row of ``offsets`` times the ranges in coordinates ``dims``, clipped
    to the search box and snapped (:func:`.objective.snap`): one patch of points."""
    pts = []
    for d in offsets:
        x = c.copy()
        x[dims] = np.clip(c[dims] + d * obj.span[dims], obj.lo[dims], obj.hi[dims])
        pts.append(snap(x))
    return pts


def _best_of(pairs: list[tuple[np.ndarray, float]]) -> tuple[np.ndarray, float]:
    """The best ``(x, χ²)`` by :func:`.likelihood_basins.rank_key`."""
    return min(pairs, key=lambda p: rank_key(p[1], p[0]))


#: The joint zoom (:func:`joint_zoom`): centres, points around each, and the patch's half-width
#: as a fraction of the range of ``e`` and of ``omega_s``.
JOINT_ZOOM_CENTRES = 4
JOINT_ZOOM_POINTS = SearchSettings.joint_zoom  # the default; ``SearchSettings.joint_zoom`` sets it
JOINT_ZOOM_HALF = 0.04


def joint_zoom(obj: Objective, ranked: list[np.ndarray], s: SearchSettings) -> list[np.ndarray]:
    """Points around the best joint candidates, ``R_φ`` moved to the load curve's torque scale.

    The load curve pins ``(e, omega_s)`` to a valley far narrower than the scan's spacing (on the
    shipped motor a change of 0.04 in ``omega_s`` at fixed ``(e, ψ, R_φ)`` raises the load part's
    ``χ²`` by hundreds), so a candidate of the scan lies beside it, not in it. Around each of the
    best :data:`JOINT_ZOOM_CENTRES` candidates distinct in ``(e, omega_s)``, a Sobol patch of
    ``s.joint_zoom`` points (:data:`JOINT_ZOOM_POINTS` by default) ``± JOINT_ZOOM_HALF`` of the
    range keeps the centre's
    ``(ψ, R_φ)`` with ``R_φ`` load-matched (:func:`load_matched`); the local search refines the
    best of them. Cheap because a load curve costs about one run
    (:mod:`bouncedisk.engine.loads`).
    """
    ax = [obj.names.index("e"), obj.names.index("omega_s")]
    patch = (2.0 * _sobol(s.joint_zoom, s.seed + 2) - 1.0) * JOINT_ZOOM_HALF
    pts = [
        x
        for c in _distinct_axial(obj, ranked, JOINT_ZOOM_CENTRES)
        for x in _around(obj, c, ax, patch)
    ]
    return obj.map(lambda x: load_matched(obj, x), pts)


def load_matched(obj: Objective, x: np.ndarray) -> np.ndarray:
    """``x`` with ``log10 R_φ`` moved so the load curves' torque scale matches the data's.

    docs/model.md's scaling: at fixed ``(e, ω_s, ψ)`` the speed in rad/s does not depend on ``R_φ``
    (``x = R_φ Ω`` is what evolves, and ``R_φ Φ0 / t_c`` converts ``Ω``), while the torque scale
    ``μ m_r g_eff r_eff`` is proportional to it; apart from the run-up transient inside the window,
    a reading at torque ``T`` under ``s R_φ`` is the reading at ``T / s`` under ``R_φ``. One
    member's readings at ``x`` (interpolated, extrapolated linearly) give every ``s``; the best on a
    grid of ``s`` in ``[1/3, 3]`` is taken. For ranking candidates only: the likelihood itself is
    always the exact one.
    """
    part, names = obj.load, obj.names
    if "log10_r_phi" not in names:
        return x
    xs = snap(x)
    v = part.mean(obj.theta(xs), xs, 1, obj.points_parallel)
    sigma = np.sqrt(part.data_var())
    best, best_loss = 1.0, np.inf
    for s in np.exp(np.linspace(-np.log(3.0), np.log(3.0), 121)):
        pred = np.concatenate([_extrapolated(t / s, t, v[sl]) for t, sl in part.slices()])
        loss = float(np.sum(((pred - part.y) / sigma) ** 2))
        if loss < best_loss:
            best, best_loss = s, loss
    out = xs.copy()
    j = names.index("log10_r_phi")
    out[j] = np.clip(out[j] + np.log10(best), obj.lo[j], obj.hi[j])
    return snap(out)


def _extrapolated(t_new: np.ndarray, t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``v(t)`` at ``t_new``: linear between the samples, continued by the end segments."""
    out = np.interp(t_new, t, v)
    lo, hi = t_new < t[0], t_new > t[-1]
    out[lo] = v[0] + (t_new[lo] - t[0]) * (v[1] - v[0]) / (t[1] - t[0])
    out[hi] = v[-1] + (t_new[hi] - t[-1]) * (v[-1] - v[-2]) / (t[-1] - t[-2])
    return out


def local_stage(
    obj: Objective,
    starts: list[np.ndarray],
    members: int,
    nfev: int,
    progress: Callable[[str], None] | None = None,
) -> tuple[Evaluation, list[np.ndarray]]:
    """Least squares on the whitened residuals from every one of ``starts`` (box-scaled).

    Multi-start: the landscape in ``(e, omega_s)`` is rugged (periodic windows), so each start is
    refined on its own. Returns the best logged point with ``members`` members and each start's
    end point (in the order of ``starts``: the waterfall's points, :attr:`SearchResult.ends`).
    """

    def logged(u):
        x = obj.from_unit(u, obj.lo)
        obj.chi2(x, members)
        return obj.residuals(x, members)

    ends = []
    for k, x0 in enumerate(starts):
        res = least_squares(
            logged, obj.to_unit(x0), bounds=(0.0, 1.0), diff_step=2e-3, max_nfev=nfev, x_scale=1.0
        )
        ends.append(snap(obj.from_unit(res.x, obj.lo)))
        _say(
            progress,
            f"local search ({members} members): start {k + 1}/{len(starts)}, best "
            f"chi2 {obj.best(members).chi2:.4g}",
        )
    best = obj.best(members)
    _say(progress, f"local search: chi2 {best.chi2:.4g} ({len(obj.read)} ensembles evaluated)")
    return best, ends


@dataclass(frozen=True)
class SearchResult:
    """The search's best point and the end point of each of its local searches' starts."""

    #: The best logged point at the fit's members under the final covariance.
    best: Evaluation
    #: Where each start of the multi-start stage ended (search coordinates; each was evaluated):
    #: with their ``χ²`` under the final covariance, best first, the fit's waterfall
    #: (:func:`waterfall`).
    ends: list[np.ndarray]


def waterfall(
    obj: Objective, ends: list[np.ndarray], members: int
) -> tuple[np.ndarray, np.ndarray]:
    """The starts' end ``χ²`` under the objective's covariance now and their end points, best
    first: how many starts reach the best value is the search's own evidence that it found the
    best basin, and where they ended tells another basin from a start that stopped early."""
    chis = [obj.chi2_now(x, members) for x in ends]
    order = sorted(range(len(ends)), key=lambda i: rank_key(chis[i], ends[i]))
    points = np.array([ends[i] for i in order]).reshape(len(ends), len(obj.names))
    return np.array([chis[i] for i in order]), points


def search(
    obj: Objective, s: SearchSettings, progress: Callable[[str], None] | None = None
) -> SearchResult:
    """The whole search (module docstring): the best logged point at ``s.members`` and the ends
    of the multi-start stage's starts."""
    ranked = global_stage(obj.seeing("runup"), s, progress)  # the scan fits the run-ups
    obj.set_cov(measure_cov(obj, ranked[0].x, s.pilot_members))
    # one member per scan point is noisy where the model is chaotic: re-rank the best distinct
    # scan points on `members` members under the model's covariance, measured at the best of them
    cands = joint_candidates(obj, ranked, s, progress)
    if obj.load is not None:
        _say(
            progress,
            f"load curve read at the distinct scan points that reproduce the run-ups, "
            f"R_phi matched to its torque scale; the best {len(cands)} by the joint "
            "chi2 go on",
        )
    scores = rerank(obj, cands, s)
    starts = [cands[i] for i in rank_order(scores, cands)[: s.starts]]
    if obj.load is not None:
        # the joint valley is narrow in (e, omega_s): one start per distinct (e, omega_s)
        starts = _distinct_axial(obj, [cands[i] for i in rank_order(scores, cands)], JOINT_STARTS)
    _say(
        progress,
        f"pilot: model covariance from {s.pilot_members} members; {len(cands)} scan "
        f"points re-ranked on {s.members} members, best chi2 {min(scores):.4g}",
    )
    # the starts themselves, then each refined (never worse than the best start)
    # joint: more starts (distinct in (e, omega_s)), each refined half as long, then polished
    nfev = s.local_nfev if obj.load is None else max(4, s.local_nfev // 2)
    best, ends = local_stage(obj, starts, s.members, nfev, progress)
    best = noise_sweep(obj, best, s.members, progress)
    if obj.load is not None and ("e_sigma" in obj.names or obj.spec.e_sigma == 0.0):
        # a periodic motor's valley at e_sigma = 0 is narrower than the scan sees (limit_walk)
        walked = deterministic_walk(obj, best, s.members, progress)
        best = walked if walked.chi2 < best.chi2 - WALK_GAIN else best
    obj.set_cov(measure_cov(obj, best.x, s.pilot_members))
    best, _ = local_stage(obj, [best.x], s.members, max(8, s.local_nfev // 3), progress)
    return SearchResult(best, ends)


#: Values of a fitted restitution noise tried at the local search's best point (:func:`noise_sweep`).
NOISE_GRID = (0.0, 0.01, 0.02, 0.03, 0.045, 0.06, 0.08, 0.1)


def noise_sweep(
    obj: Objective, best: Evaluation, members: int, progress: Callable[[str], None] | None = None
) -> Evaluation:
    """With ``e_sigma`` fitted: its :data:`NOISE_GRID` at the best point, the other coordinates
    held; the best logged point after it (the search never returns a worse one).

    The scan runs at the stated noise and a local step in ``e_sigma`` sees the landscape only
    near it, while the noise moves whole load curves (a few % at no load between 0 and 0.03): the
    grid lets the final refinement start where the data put it, and its points, logged, widen
    the profile interval of ``e_sigma`` wherever they are acceptable.
    """
    if "e_sigma" not in obj.names:
        return best
    j = obj.names.index("e_sigma")
    obj.map(lambda x: obj.chi2(x, members), noise_copies(obj, best.x, NOISE_GRID))
    out = obj.best(members)
    _say(
        progress,
        f"noise sweep: e_sigma {out.x[j]:.4g}, chi2 {out.chi2:.4g} (before: "
        f"{best.x[j]:.4g}, {best.chi2:.4g})",
    )
    return out


def rerank(obj: Objective, cands: list[np.ndarray], s: SearchSettings) -> list[float]:
    """``χ²`` of the candidates on ``s.members`` members under the model's covariance, measured
    at the best of them (:func:`measure_cov`): one member per scan point is noisy where the model
    is chaotic.

    Parameters
    ----------
    obj : Objective
        The objective; its covariance (and the load part's) is set at the best candidate.
    cands : list of ndarray
        Candidates (search coordinates).
    s : SearchSettings
        ``members`` and ``pilot_members``.

    Returns
    -------
    list of float
        Each candidate's ``χ²`` under the new covariance.
    """
    scores = obj.map(lambda x: obj.chi2(x, s.members), cands)
    obj.set_cov(measure_cov(obj, cands[rank_order(scores, cands)[0]], s.pilot_members))
    return [obj.chi2(x, s.members) for x in cands]


#: Local-search starts of a joint fit, distinct in ``(e, omega_s)`` (:func:`_distinct_axial`).
JOINT_STARTS = 6


def _distinct_axial(obj: Objective, ranked: list[np.ndarray], k: int) -> list[np.ndarray]:
    """The best ``k`` points at least 3 % of the range apart in ``e`` or ``omega_s``."""
    ax = [obj.names.index("e"), obj.names.index("omega_s")]
    out: list[np.ndarray] = []
    for x in ranked:
        if all(np.max(np.abs(x[ax] - o[ax]) / obj.span[ax]) > 0.03 for o in out):
            out.append(x)
        if len(out) == k:
            break
    return out


def _distinct(ranked: list[Evaluation], span: np.ndarray, k: int) -> list[Evaluation]:
    """The best ``k`` points at least 5 % of the range apart (in some coordinate)."""
    out: list[Evaluation] = []
    for ev in ranked:
        if all(np.max(np.abs(ev.x - o.x) / span) > 0.05 for o in out):
            out.append(ev)
        if len(out) == k:
            break
    return out
