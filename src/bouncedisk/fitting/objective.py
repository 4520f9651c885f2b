"""The objective: a synthetic likelihood of the data's statistics under the model's ensemble.

For a parameter point ``θ`` the model's ``K`` members (:func:`.members.member_records`) give
statistics ``s_k(θ)`` (:func:`.summary_stats.record_stats`) with mean ``μ(θ)``. A measured curve is
one more realization, so its statistics differ from ``μ(θ)`` by the across-member spread ``C``
(which includes the measurement noise, added to every member); the data's statistics ``s_d`` are
the mean over ``M`` run-ups of one motor (``M = 1`` for one curve, :mod:`~bouncedisk.fitting.runs`), which spreads
by ``C / M``, and the model's mean has the Monte-Carlo error ``C / K``:

    χ²(θ) = (s_d − μ(θ))ᵀ [C (1/M + 1/K)]⁻¹ (s_d − μ(θ)),

``−2 log`` of a Gaussian synthetic likelihood (Wood, Nature 466, 1102, 2010) with ``C`` held at
its value near the optimum (regularized, :func:`.summary_stats.regularized_cov`). The members'
noise streams are fixed (common random numbers), so ``χ²`` is deterministic for a seed.

With load curves (:mod:`.loadpart`) the objective is the joint ``χ²`` of both experiments, the
run-ups' plus the load curves' (independent: the covariance is block-diagonal). ``parts`` selects
which data the objective sees — ``"runup"``, ``"load"`` or ``"both"`` — fixed per objective;
:meth:`Objective.seeing` gives a view of another part on the same cached evaluations, so the
intervals from each data set alone come from them (:func:`.joint.identifiability`).

Round-off cannot move it (docs/user_guide/reproducible.md): every point is first put on a lattice of
:data:`SNAP_DECIMALS` decimals (:func:`snap`; an optimizer's step that differs in the last bits
between BLAS kernels lands on the same lattice point), the members' statistics are reduced in a
fixed order, and the whitening and ``χ²`` use :mod:`.detlinalg` (no BLAS).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import InitVar, dataclass, field, replace

import numpy as np

from ..io.runup_curves import MotorCurve
from . import detlinalg
from .likelihood_basins import rank_key
from .loadpart import LoadPart, members_for
from .members import BOUNDS, EnsembleSpec, member_records, rows_records, thread_map
from .summary_stats import EnsembleStats, Layout, records_stats, regularized_cov, stat_floor

#: The data an objective can see (:meth:`Objective.seeing`).
PARTS = ("runup", "load", "both")
#: Decimals of the lattice every evaluated point is put on (:func:`snap`): far finer than any step
#: of the search (the finest, a finite difference, is 1e-3 of a range), far coarser than round-off.
SNAP_DECIMALS = 8


def snap(x: np.ndarray) -> np.ndarray:
    """``x`` on the lattice of :data:`SNAP_DECIMALS` decimals, where the objective evaluates.

    A change of ``x`` by round-off (1e-16) moves the lattice point only if ``x`` lies within that
    much of a cell boundary (probability ~1e-8 per coordinate), so two machines whose optimizer
    steps differ in the last bits evaluate the model at the same points.
    """
    return np.round(np.asarray(x, float), SNAP_DECIMALS) + 0.0  # + 0.0: no negative zero


def _sum_of_squares(r: np.ndarray) -> float:
    """``rᵀr`` (BLAS-free, :mod:`.detlinalg`); 1e300 for a reading the run did not reach."""
    value = detlinalg.dot(r, r)
    return value if math.isfinite(value) else 1e300


@dataclass
class _Metric:
    """The across-member covariance ``C`` in use and its whitening: one object shared by an
    objective and its views (:meth:`Objective.seeing`), so a change reaches all of them."""

    cov: np.ndarray | None = None
    white: np.ndarray | None = None


@dataclass
class Evaluation:
    """One evaluated point: search coordinates, members used and ``χ²`` under the metric then."""

    x: np.ndarray
    members: int
    chi2: float
    parts: str = "runup"  # the data the objective saw (Objective.parts)


@dataclass
class Objective:
    """``χ²`` and whitened residuals of the statistics, with a cache and a log of evaluations.

    Parameters
    ----------
    curve : MotorCurve
        The (possibly downsampled) measured curve.
    names : list of str
        Search coordinates (:func:`.members.param_names`).
    layout : Layout
        Where the statistics are taken.
    target : ndarray
        The data's statistics ``s_d``.
    spec : EnsembleSpec
        Restitution noise, seed and cores of the members.
    members : int
        Members per evaluation ``K`` (changeable between stages).
    runs : int
        Run-ups ``M`` whose mean statistics ``target`` is.
    load : LoadPart or None
        The load curves' part of the likelihood (:mod:`.loadpart`); ``None``: run-ups only.
    parts : str
        The data the objective sees: ``"runup"``, ``"load"`` or ``"both"``.
    initial_cov : ndarray or None
        The covariance ``C`` to start with (identity when ``None``); :meth:`set_cov` changes it,
        :attr:`covariance` reads it.
    """

    curve: MotorCurve
    names: list[str]
    layout: Layout
    target: np.ndarray
    spec: EnsembleSpec
    members: int
    initial_cov: InitVar[np.ndarray | None] = None
    cache: dict = field(default_factory=dict)
    #: The points (with their member counts) whose statistics were read: the fit's evaluations
    #: (a point :meth:`prefetch` ran ahead and nobody read is not one).
    read: set = field(default_factory=set)
    log: list[Evaluation] = field(default_factory=list)
    on_eval: Callable[[int], None] | None = None
    points_parallel: bool = False
    runs: int = 1
    load: LoadPart | None = None
    parts: str = "runup"

    def __post_init__(self, initial_cov: np.ndarray | None):
        b = np.array([BOUNDS[n] for n in self.names])
        self.lo, self.hi = b[:, 0], b[:, 1]
        self._metric = _Metric()
        self.set_cov(np.eye(len(self.target)) if initial_cov is None else initial_cov)

    def seeing(self, parts: str) -> Objective:
        """The same objective seeing only ``parts`` (``"runup"``, ``"load"`` or ``"both"``): a
        view sharing the cache, the log, the covariance (a :meth:`set_cov` on either reaches
        both) and the load part, its own ``parts`` fixed (the mode is an argument, never a
        string saved and restored)."""
        if parts not in PARTS:
            raise ValueError(f"parts must be one of {PARTS}, got {parts!r}")
        view = copy.copy(self)
        view.parts = parts
        return view

    @property
    def span(self) -> np.ndarray:
        """Width of the search range of every coordinate."""
        return self.hi - self.lo

    def to_unit(self, x: np.ndarray, free: list[int] | slice = slice(None)) -> np.ndarray:
        """The coordinates ``free`` of ``x`` in the unit box of their search ranges, clipped to
        it (the box the least-squares stages search in)."""
        return np.clip((np.asarray(x, float)[free] - self.lo[free]) / self.span[free], 0.0, 1.0)

    def from_unit(
        self, u: np.ndarray, start: np.ndarray, free: list[int] | slice = slice(None)
    ) -> np.ndarray:
        """A copy of ``start`` with its coordinates ``free`` at the unit-box position ``u``
        (the inverse of :meth:`to_unit`)."""
        y = np.array(start, float)
        y[free] = self.lo[free] + u * self.span[free]
        return y

    @property
    def covariance(self) -> np.ndarray:
        """The across-member covariance ``C`` in use."""
        return self._metric.cov

    def set_cov(self, cov: np.ndarray) -> None:
        """Use the across-member covariance ``cov`` (already regularized) from now on, here and
        in every view (:meth:`seeing`)."""
        cov = np.asarray(cov, float)
        self._metric.white = detlinalg.lower_inverse(detlinalg.cholesky(cov))
        self._metric.cov = cov

    def theta(self, x: np.ndarray) -> dict[str, float]:
        """Parameter dictionary of search coordinates ``x`` (ψ wrapped into ``[−π, π)``)."""
        th = dict(zip(self.names, (float(v) for v in x), strict=True))
        if "psi" in th:
            th["psi"] = (th["psi"] + math.pi) % (2.0 * math.pi) - math.pi
        return th

    def ensemble(self, x: np.ndarray, members: int | None = None) -> EnsembleStats:
        """Statistics of the first ``members`` members at ``x`` (cached per point and size)."""
        k = members or self.members
        x = snap(x)
        key = (k, *x)
        if key not in self.cache:
            self.prefetch([x], k)
        if key not in self.read:
            self.read.add(key)
            if self.on_eval is not None:
                self.on_eval(len(self.read))
        return self.cache[key]

    def prefetch(self, xs, members: int | None = None) -> None:
        """Evaluate the points ``xs`` not yet cached; those that share ``(e, omega_s, σ_e)``
        together, one axial run per member (:func:`.members.rows_records`).

        The statistics are those :meth:`ensemble` gives each point, bit for bit; a point that
        is never read costs a share of a run. The scan's ψ grid and a least-squares step's
        finite differences are such points (:mod:`.search`).
        """
        k = members or self.members
        groups: dict[tuple, dict[tuple, np.ndarray]] = {}
        for x in map(snap, xs):
            if (k, *x) not in self.cache:
                th = self.theta(x)
                key = (th["e"], th["omega_s"], th.get("e_sigma"))
                groups.setdefault(key, {})[tuple(x)] = x
        spec = replace(self.spec, cores=1) if self.points_parallel else self.spec
        for pts in (list(g.values()) for g in groups.values()):
            recs = rows_records([self.theta(x) for x in pts], self.curve, range(k), spec)
            for i, x in enumerate(pts):
                values = records_stats(np.array([r[i] for r in recs]), self.layout)
                self.cache[(k, *x)] = EnsembleStats.from_values(values)

    @property
    def n_stats(self) -> int:
        """Residuals of the data the objective sees now (``parts``)."""
        n = len(self.target) if self.parts != "load" else 0
        return n + (self.load.n if self.load is not None and self.parts != "runup" else 0)

    def _joined(
        self, runup: Callable[[], np.ndarray], load: Callable[[], np.ndarray]
    ) -> np.ndarray:
        """The run-ups' residuals, then the load curves', per ``parts`` (each made only when
        the objective sees it)."""
        out = []
        if self.parts != "load":
            out.append(runup())
        if self.load is not None and self.parts != "runup":
            out.append(load())
        return out[0] if len(out) == 1 else np.concatenate(out)

    def _whitened(self, mean: np.ndarray, white: np.ndarray, k: int) -> np.ndarray:
        """``L⁻¹ (μ − s_d) / sqrt(1/M + 1/K)`` of the run-ups' mean statistics ``mean``."""
        return detlinalg.matvec(white, mean - self.target) / math.sqrt(1.0 / self.runs + 1.0 / k)

    def residuals(self, x: np.ndarray, members: int | None = None) -> np.ndarray:
        """Whitened residuals ``L⁻¹ (μ(x) − s_d) / sqrt(1/M + 1/K)`` (``C = L Lᵀ``) of the
        run-ups, then the load curves' (:meth:`.loadpart.LoadPart.residuals`), per ``parts``."""
        k = members or self.members
        x = snap(x)
        return self._joined(
            lambda: self._whitened(self.ensemble(x, k).mean, self._metric.white, k),
            lambda: self.load.residuals(self.theta(x), x, members_for(k), self.points_parallel),
        )

    def own_residuals(self, x: np.ndarray, members: int) -> np.ndarray:
        """Whitened residuals with the run-ups' covariance measured at ``x`` itself, on its own
        ``members`` members (regularized as the held one, :func:`.summary_stats.regularized_cov`);
        the load part's as held.

        The held covariance was measured near the best point; in another regime the members
        spread many times more (measured on a random motor: 2-25 times per statistic at the
        generating point), so a point of that regime can reproduce the data within its own
        spread yet read far off under the held one (:func:`.uncertainty.consistent_points`).
        """
        x = snap(x)
        return self._joined(
            lambda: self._own_runup(x, members)[0],
            lambda: self.load.residuals(self.theta(x), x, members_for(members)),
        )

    def _own_runup(self, x: np.ndarray, members: int) -> tuple[np.ndarray, np.ndarray]:
        """The run-ups' residuals whitened by their covariance ``C(x)`` measured at ``x`` on its
        own ``members`` members (regularized as the held one), and ``C(x)``'s Cholesky factor."""
        ens = self.ensemble(x, members)
        factor = detlinalg.cholesky(regularized_cov(ens.cov, stat_floor(self.target)))
        return self._whitened(ens.mean, detlinalg.lower_inverse(factor), members), factor

    def own_loglik(self, x: np.ndarray, members: int, load_members: int | None = None) -> float:
        """``−2 log`` of the Gaussian synthetic likelihood with every covariance measured at the
        point itself (Wood, Nature 466, 1102, 2010; docs/fitting_method.md "Generating point"),
        up to a constant, not logged: the run-ups' on ``members`` members,

            (s_d − μ(x))ᵀ Σ(x)⁻¹ (s_d − μ(x)) + log det Σ(x),   Σ(x) = C(x) (1/M + 1/K),

        plus the load curves' likewise on ``load_members`` (:func:`.loadpart.members_for` when
        ``None``; :meth:`.loadpart.LoadPart.own_loglik`), per ``parts``; ``inf`` where a member
        did not reach a reading. Unlike ``χ²`` under one held ``C``, it compares points of
        regimes whose members spread differently: a quiet point's small ``C`` does not make a
        noisy regime's points read far off, and a noisy point's large ``C`` is charged its
        ``log det``. ``C`` is estimated from the members, so ``members`` should well exceed the
        statistics' count.
        """
        x = snap(x)

        def runup() -> float:
            if not np.isfinite(self.ensemble(x, members).values).all():
                return math.inf
            r, factor = self._own_runup(x, members)
            scale = 1.0 / self.runs + 1.0 / members
            log_det = detlinalg.log_det(factor)
            return _sum_of_squares(r) + log_det + len(self.target) * math.log(scale)

        def load() -> float:
            k = members_for(members) if load_members is None else load_members
            return self.load.own_loglik(self.theta(x), x, k)

        return math.fsum(self._joined(lambda: np.array([runup()]), lambda: np.array([load()])))

    def own_chi2(self, x: np.ndarray, members: int) -> float:
        """``χ²`` of :meth:`own_residuals`, not logged."""
        return _sum_of_squares(self.own_residuals(x, members))

    def fresh_chi2(self, x: np.ndarray, members: int, block: int) -> float:
        """``χ²`` at ``x`` on members the search never used: block ``b ≥ 1`` of ``members``
        (run-up members ``bK … (b+1)K−1``, the load part's block likewise), not logged.

        The search keeps the lowest ``χ²`` of hundreds of points on one set of members, so the
        best point's ``χ²`` is low by the Monte-Carlo noise it was selected for (the winner's
        curse); on fresh members it is an unbiased reading of the level there
        (:func:`.uncertainty.chi2_level`).
        """
        x = snap(x)
        th = self.theta(x)

        def runup() -> np.ndarray:
            recs = member_records(
                th, self.curve, range(block * members, (block + 1) * members), self.spec
            )
            mean = EnsembleStats.from_values(records_stats(np.array(recs), self.layout)).mean
            return self._whitened(mean, self._metric.white, members)

        k = members_for(members)
        return _sum_of_squares(
            self._joined(runup, lambda: self.load.residuals(th, x, k, first=block * k))
        )

    def chi2(self, x: np.ndarray, members: int | None = None) -> float:
        """``χ²`` at ``x``; every call is logged (the search never returns a worse point)."""
        x = snap(x)
        value = _sum_of_squares(self.residuals(x, members))
        self.log.append(Evaluation(x.copy(), members or self.members, value, self.parts))
        return value

    def robust(self, x: np.ndarray, members: int | None = None) -> float:
        """``Σ log(1 + r²)``: the global search's loss, insensitive to far-off statistics."""
        r = self.residuals(x, members)
        self.chi2(x, members)
        value = float(np.sum(np.log1p(r * r)))
        return value if math.isfinite(value) else 1e300  # a reading the run did not reach

    def map(self, fn: Callable, items) -> list:
        """``[fn(item) …]`` with items on ``spec.cores`` threads (members of each run serially)."""
        items = list(items)
        if self.spec.cores <= 1 or len(items) < 2:
            return [fn(i) for i in items]
        self.points_parallel = True
        try:
            return thread_map(fn, items, self.spec.cores)
        finally:
            self.points_parallel = False

    def best(self, members: int | None = None) -> Evaluation:
        """The best logged evaluation with ``members`` members under the current metric
        (ties, and ``χ²`` equal to :data:`.likelihood_basins.CHI2_DIGITS` digits, go to the smaller point in
        coordinate order: the choice does not depend on the order points were logged in)."""
        k = members or self.members
        pts = {tuple(ev.x): ev.x for ev in self.log if ev.members == k}
        scored = [(self.chi2_now(x, k), x) for x in pts.values()]
        value, x = min(scored, key=lambda s: rank_key(s[0], s[1]))
        return Evaluation(x.copy(), k, value)

    def chi2_now(self, x: np.ndarray, members: int | None = None) -> float:
        """``χ²`` at an evaluated point under the current metric, not logged."""
        return _sum_of_squares(self.residuals(x, members))
