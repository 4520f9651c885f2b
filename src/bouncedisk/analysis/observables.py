"""Observables of a run: periodicity, Lyapunov exponent, rotor speed trend, regime.

All functions take plain numpy arrays of the event table (``t``, ``phase``, ``v_rel``,
``omega_after``, ``kind``; see :mod:`bouncedisk.engine`) so they serve any solver.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from math import isfinite, log, sqrt

import numpy as np
from numba import njit

from ..engine import KIND_CHATTER, KIND_IMPACT
from ..engine.noise import member_key, noisy_restitution
from ..model import stator

TWO_PI = 2.0 * math.pi


@njit(cache=True, nogil=True)
def _restitutions(e, e_sigma, key, first, n):
    """``e_k`` of the events ``first … first + n − 1`` of one noise stream (the engine's draws)."""
    out = np.empty(n)
    for i in range(n):
        out[i] = noisy_restitution(e, e_sigma, key, first + i)
    return out


def event_restitution(
    e: float, e_sigma: float, seed: int, member: int, first: int, n: int
) -> np.ndarray:
    """Each event's own restitution ``e_k`` (docs/model.md "Long-run statistics").

    The engine draws event ``k``'s restitution from the counter-based stream ``(seed, member)``
    (:mod:`bouncedisk.engine.noise`), ``k`` counting every event of the run from 0 (impacts and
    chattering tails), so the value of each row of an event table is known without being
    recorded. ``e_sigma = 0``: ``e`` everywhere.

    Parameters
    ----------
    e, e_sigma : float
        Mean restitution and its standard deviation (0 without ``restitution_noise``).
    seed, member : int
        The run's noise stream.
    first, n : int
        Index in the run of the first row, and the number of rows.

    Returns
    -------
    ndarray, shape (n,)
    """
    if not e_sigma > 0.0:
        return np.full(n, float(e))
    key = np.uint64(member_key(np.int64(seed), np.int64(member)))
    return _restitutions(float(e), float(e_sigma), key, np.int64(first), n)


def circular_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance between phases on the circle, in ``[0, π]``."""
    d = np.mod(np.asarray(a) - np.asarray(b), TWO_PI)
    return np.minimum(d, TWO_PI - d)


@dataclass(frozen=True)
class Periodicity:
    """A periodic impact sequence: ``p`` impacts every ``q`` stator periods."""

    p: int
    q: int
    phases: np.ndarray  # the p impact phases of one cycle, sorted

    @property
    def label(self) -> str:
        """``period-p``, or ``period-p/q`` when the cycle spans q != p stator periods."""
        return f"period-{self.p}" if self.p == self.q else f"period-{self.p}/{self.q}"


def find_period(
    t: np.ndarray,
    phase: np.ndarray,
    v_rel: np.ndarray,
    kind: np.ndarray,
    omega_s: float,
    max_period: int = 16,
    tail: int = 200,
    tol: float = 1e-6,
) -> Periodicity | None:
    """Smallest ``p <= max_period`` with ``(φ, V)_{k+p} = (φ, V)_k`` over the last ``tail`` impacts.

    Parameters
    ----------
    t, phase, v_rel, kind : ndarray
        Event table of a run (after transients).
    omega_s : float
        Stator frequency, to count stator periods per cycle.
    tol : float
        Tolerance on phase (radians) and relative velocity.

    Returns
    -------
    Periodicity or None
        ``None`` when no period up to ``max_period`` fits, or the tail has chattering rows.
    """
    n = min(tail, len(t))
    if n < 2 * max_period + 2:
        n = len(t)
    if n < 4:
        return None
    sl = slice(len(t) - n, len(t))
    ph, vr, tt, kd = phase[sl], v_rel[sl], t[sl], kind[sl]
    ph, vr, kd = np.asarray(ph), np.asarray(vr), np.asarray(kd)
    if ph.dtype == np.float64 and vr.dtype == np.float64:
        p = _first_period(ph, vr, kd, max_period, tol)
    else:  # other precisions as numpy computes them
        p = _first_period_numpy(ph, vr, kd, max_period, tol)
    if p == 0:
        return None
    q = int(round((tt[-1] - tt[-1 - p]) * omega_s / TWO_PI))
    return Periodicity(p=p, q=q, phases=np.sort(ph[-p:]))


def _first_period_numpy(ph, vr, kd, max_period, tol):
    """:func:`_first_period` in numpy (any dtype)."""
    n = len(ph)
    for p in range(1, max_period + 1):
        if n <= 2 * p:
            break
        dph = circular_distance(ph[p:], ph[:-p])
        dv = np.abs(vr[p:] - vr[:-p])
        same_kind = np.all(kd[p:] == kd[:-p])
        if same_kind and np.all(dph < tol) and np.all(dv < tol * (1.0 + np.abs(vr[:-p]))):
            return p
    return 0


@njit(cache=True, inline="always")
def _circular(a, b):
    """:func:`circular_distance` of two scalars (the same bits: floored ``%``, as ``np.mod``)."""
    d = (a - b) % TWO_PI
    return min(d, TWO_PI - d)


@njit(cache=True, nogil=True)
def _first_period(ph, vr, kd, max_period, tol):
    """The loop of :func:`find_period` (compiled, releases the GIL): the smallest ``p`` whose
    shift matches every row in kind, phase and relative velocity, or 0."""
    n = len(ph)
    for p in range(1, max_period + 1):
        if n <= 2 * p:
            break
        ok = True
        for i in range(n - p):
            if kd[i + p] != kd[i]:
                ok = False
                break
        if not ok:
            continue
        for i in range(n - p):
            if not _circular(ph[i + p], ph[i]) < tol:
                ok = False
                break
        if not ok:
            continue
        for i in range(n - p):
            if not abs(vr[i + p] - vr[i]) < tol * (1.0 + abs(vr[i])):
                ok = False
                break
        if ok:
            return p
    return 0


def impact_jacobians(
    t: np.ndarray,
    phase: np.ndarray,
    v_rel: np.ndarray,
    kind: np.ndarray,
    e: float | np.ndarray,
    omega_s: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Jacobians of the exact impact map for consecutive free-flight impacts.

    With ``v_k = v_s(t_k) + e_k V_k`` the rotor velocity after impact ``k``, flight time ``Δ``
    and relative impact velocity ``V_{k+1}``, differentiating the first-root condition (eq. 20)
    and the restitution law (eq. 4) with the landing impact's restitution ``e' = e_{k+1}``
    gives::

        ∂t'/∂t = (v_s(t_k) − v_k + Δ)/V_{k+1},   ∂t'/∂v = Δ/V_{k+1},
        c = e' − (1 + e') w² sin φ_{k+1},
        ∂v'/∂t = c ∂t'/∂t − e',                  ∂v'/∂v = c ∂t'/∂v − e'.

    At a period-1 fixed point this gives ``det J = e²`` and
    ``trace J = 1 + e² − (1 + e)² Γ sin φ`` (docs/model.md "Impact map Jacobian").

    Parameters
    ----------
    t, phase, v_rel, kind : ndarray
        Event table of a run.
    e : float or ndarray
        Restitution: one value, or each row's own ``e_k`` (restitution noise:
        :func:`event_restitution`). A run with noise needs its rows' own values: with the mean
        ``e`` the flights do not land where the table says and the derivatives are wrong.
    omega_s : float
        Stator frequency ``w``.

    Returns
    -------
    jac : ndarray, shape (m, 2, 2)
        One matrix per valid pair.
    index : ndarray, shape (m,)
        Index ``k`` of the first impact of each pair. A pair is valid when both rows are impacts
        and the free flight from ``k`` lands at ``k + 1`` (no contact in between).
    """
    w = omega_s
    if len(t) < 2:
        return np.empty((0, 2, 2)), np.empty(0, dtype=int)
    e = np.broadcast_to(np.asarray(e, dtype=float), np.shape(t))
    vs = stator.velocity(phase, w)
    v_post = vs + e * v_rel
    dt = np.diff(t)
    u0 = stator.position(phase[:-1])
    landing = u0 + v_post[:-1] * dt - 0.5 * dt**2
    ok = (
        (kind[:-1] == KIND_IMPACT)
        & (kind[1:] == KIND_IMPACT)
        & (np.abs(landing - stator.position(phase[1:])) < 1e-7 * (1.0 + dt**2))
        & (v_rel[1:] > 0.0)
    )
    idx = np.nonzero(ok)[0]
    V = v_rel[idx + 1]
    d = dt[idx]
    a = (vs[idx] - v_post[idx] + d) / V
    b = d / V
    e1 = e[idx + 1]
    c = e1 - (1.0 + e1) * w * w * np.sin(phase[idx + 1])
    jac = np.empty((len(idx), 2, 2))
    jac[:, 0, 0] = a
    jac[:, 0, 1] = b
    jac[:, 1, 0] = c * a - e1
    jac[:, 1, 1] = c * b - e1
    return jac, idx


@njit(cache=True, nogil=True)
def benettin(jac, idx, vec, prev, skip):
    """Benettin's tangent-vector iteration over impact-map Jacobians, resetting at every reset.

    ``jac[j]`` maps the tangent vector across the free flight from impact ``idx[j]`` to
    ``idx[j] + 1``. A pair that does not follow the previous one (``idx[j] != prev + 1``: contact
    or a complete chatter in between) starts a fresh vector: the chatter's Jacobian is zero
    (docs/model.md "Long-run statistics"), so growth is only measured between resets.

    Parameters
    ----------
    jac : ndarray, shape (m, 2, 2)
    idx : ndarray of int64, shape (m,)
        Global index of the first impact of each pair.
    vec : ndarray, shape (2,)
        Tangent vector carried in (updated in place, so a stream can continue).
    prev : int
        Global index of the pair before ``idx[0]`` (``-2`` for none).
    skip : int
        Leading pairs left out of the sum (transient of the vector's alignment).

    Returns
    -------
    total, count, prev
        Sum of ``log |J v|`` and number of terms, and the last pair's index.
    """
    total = 0.0
    count = 0
    c = 1.0 / sqrt(2.0)
    for j in range(len(idx)):
        k = idx[j]
        if k != prev + 1:
            vec[0] = c
            vec[1] = c
        prev = k
        x = jac[j, 0, 0] * vec[0] + jac[j, 0, 1] * vec[1]
        y = jac[j, 1, 0] * vec[0] + jac[j, 1, 1] * vec[1]
        norm = sqrt(x * x + y * y)
        if norm == 0.0 or not isfinite(norm):
            vec[0] = c
            vec[1] = c
            continue
        vec[0] = x / norm
        vec[1] = y / norm
        if j >= skip:
            total += log(norm)
            count += 1
    return total, count, prev


def lyapunov_exponent(
    t: np.ndarray,
    phase: np.ndarray,
    v_rel: np.ndarray,
    kind: np.ndarray,
    e: float | np.ndarray,
    omega_s: float,
    skip: int = 100,
) -> tuple[float, float]:
    """Largest Lyapunov exponent of the impact map between resets (Benettin, exact Jacobian).

    Contact and chattering episodes collapse all perturbations (:func:`benettin`); they are
    left out of the average, so the value is the mean expansion rate over free flights. ``e``:
    one restitution or each row's own (:func:`impact_jacobians`).

    Returns
    -------
    per_impact, per_time : float
        Exponent per impact and per unit nondimensional time (``nan`` if too few free flights).
    """
    jac, idx = impact_jacobians(t, phase, v_rel, kind, e, omega_s)
    if len(idx) <= skip + 10:
        return math.nan, math.nan
    vec = np.full(2, 1.0 / math.sqrt(2.0))
    total, count, _ = benettin(jac, idx.astype(np.int64), vec, -2, skip)
    if count == 0:
        return math.nan, math.nan
    elapsed = float(np.sum(t[idx[skip:] + 1] - t[idx[skip:]]))
    return total / count, total / elapsed


@dataclass(frozen=True)
class FirstOrderTrend:
    """``Ω(t) ≈ Ω∞ (1 − exp(−(t − t0)/τ)) + Ω0 exp(−(t − t0)/τ)`` fitted to a speed record."""

    steady: float
    tau: float
    omega0: float
    t0: float
    ripple_rms: float

    def __call__(self, t: np.ndarray) -> np.ndarray:
        x = np.exp(-(np.asarray(t) - self.t0) / self.tau)
        return self.steady * (1.0 - x) + self.omega0 * x


def _line_fits(
    x: np.ndarray, y: np.ndarray, ym: float, dy: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least-squares lines ``y ≈ a + b x`` in closed form, one per row of ``x``: ``(a, b, Σ r²)``.

    ``ym`` and ``dy`` are ``y``'s mean and centred values (the same for every row). Centred sums
    (stable when ``x`` barely varies), each a fixed-order ``np.add.reduce`` of elementwise
    products along the row: no BLAS call, so the result does not depend on which kernel a CPU
    picks or on the thread count (docs/user_guide/reproducible.md), and a row gives the same bits alone
    or stacked with others. A constant row gives ``b = 0``.
    """
    n = x.shape[-1]
    xm = np.add.reduce(x, axis=-1) / n
    dx = x - xm[..., None]
    sxx = np.add.reduce(dx * dx, axis=-1)
    sxy = np.add.reduce(dx * dy, axis=-1)
    b = np.where(sxx > 0.0, sxy / np.where(sxx > 0.0, sxx, 1.0), 0.0)
    a = ym - b * xm
    r = y - (a[..., None] + b[..., None] * x)
    return a, b, np.add.reduce(r * r, axis=-1)


#: Points of the coarse grid of ``log τ`` that brackets the first-order trend's minimum.
TREND_GRID = 25
#: Grid values times samples solved in one stacked call (a few MB of temporaries at most).
TREND_BLOCK = 1 << 17


def first_order_trend(t: np.ndarray, omega: np.ndarray) -> FirstOrderTrend:
    """Least-squares first-order response (steady value and time constant) through ``(t, Ω)``.

    For a fixed ``τ`` the model ``Ω∞ (1 − x) + Ω0 x`` with ``x = exp(−(t − t0)/τ)`` is the line
    ``Ω∞ + (Ω0 − Ω∞) x`` (:func:`_line_fits`, closed form), so the fit is a bounded 1-D search
    over ``log τ`` with that solve inside (variable projection): a grid of :data:`TREND_GRID`
    values (solved together), then a bounded search between the best one's neighbours. Times
    enter only as ``t − t0``: the time origin does not matter. The ripple is the RMS of the
    residual about the trend.
    """
    from scipy.optimize import minimize_scalar

    t = np.asarray(t, float)
    y = np.asarray(omega, float)
    t0 = float(t[0])
    span = float(t[-1] - t0) or 1.0
    dt = t - t0
    ym = float(np.add.reduce(y)) / len(y)
    dy = y - ym

    def solve(log_tau: float) -> tuple[float, float, float]:
        a, b, cost = _line_fits(np.exp(-dt / math.exp(log_tau)), y, ym, dy)
        return float(cost), float(a), float(a + b)

    grid = np.linspace(math.log(1e-4 * span), math.log(10.0 * span), TREND_GRID)
    taus = np.array([math.exp(g) for g in grid])  # the scalar exp, as in solve
    rows = max(1, min(TREND_GRID, TREND_BLOCK // max(1, len(dt))))  # bounded temporaries
    costs = np.concatenate(
        [
            _line_fits(np.exp(-dt[None, :] / taus[i : i + rows, None]), y, ym, dy)[2]
            for i in range(0, TREND_GRID, rows)
        ]
    )
    k = int(np.argmin(costs))
    a, b = grid[max(0, k - 1)], grid[min(len(grid) - 1, k + 1)]
    best = minimize_scalar(
        lambda g: solve(g)[0], bounds=(a, b), method="bounded", options={"xatol": 1e-6}
    )
    log_tau = float(best.x) if best.fun <= costs[k] else float(grid[k])
    _cost, s, o0 = solve(log_tau)
    tau = math.exp(log_tau)
    resid = y - (s * (1.0 - np.exp(-dt / tau)) + o0 * np.exp(-dt / tau))
    return FirstOrderTrend(
        steady=float(s), tau=tau, omega0=float(o0), t0=t0, ripple_rms=float(np.std(resid))
    )


#: Regime codes and names (docs/model.md "Long-run statistics of chaotic motion"); ``unresolved``:
#: no period up to the search limit, no chatter and no positive exponent (run longer).
REGIMES: dict[int, str] = {
    0: "unresolved",
    1: "periodic",
    2: "chattering-periodic",
    3: "chaotic-reinjection",
    4: "chaotic",
    5: "rest",
}
REGIME_CODES: dict[str, int] = {name: code for code, name in REGIMES.items()}


def regime_flags(dtype: type | str = np.int64) -> dict:
    """CF ``flag_values``/``flag_meanings`` of a ``regime`` variable (:data:`REGIMES`).

    CF flag meanings are single words, so ``chattering-periodic`` is written
    ``chattering_periodic``.
    """
    return {
        "flag_values": np.array(list(REGIMES), dtype=dtype),
        "flag_meanings": " ".join(n.replace("-", "_") for n in REGIMES.values()),
    }


@dataclass(frozen=True)
class Regime:
    """Dynamical regime of a run's tail: a name of :data:`REGIMES`, and ``[p, q]`` if periodic."""

    name: str
    p: int = 0  # impacts per cycle (chatter tails not counted)
    q: int = 0  # stator periods per cycle

    @property
    def code(self) -> int:
        """The regime's code in :data:`REGIMES`."""
        return REGIME_CODES[self.name]


def chatter_cycle(
    t: np.ndarray,
    phase: np.ndarray,
    v_rel: np.ndarray,
    kind: np.ndarray,
    omega_s: float,
    tol: float = 1e-6,
) -> tuple[int, int] | None:
    """``(p, q)`` if the tail repeats one chatter-to-chatter cycle, else ``None``.

    A complete chatter resets the state (docs/model.md), so a cycle that contains one repeats exactly:
    the last three chatters must be equally spaced in events, and the events of the last two
    cycles must agree in kind, phase and relative velocity within ``tol``.
    """
    phase, v_rel, kind = np.asarray(phase), np.asarray(v_rel), np.asarray(kind)
    where = None
    if phase.dtype == np.float64 and v_rel.dtype == np.float64:
        m = _chatter_cycle_length(phase, v_rel, kind, tol)
    else:  # other precisions as numpy computes them
        where = np.nonzero(kind == KIND_CHATTER)[0]
        m = -1
        if len(where) >= 3 and where[-1] - where[-2] == where[-2] - where[-3]:
            a, b, c = where[-3], where[-2], where[-1]
            m = c - b
            dph = circular_distance(phase[b + 1 : c + 1], phase[a + 1 : b + 1])
            dv = np.abs(v_rel[b + 1 : c + 1] - v_rel[a + 1 : b + 1])
            if (
                np.any(kind[b + 1 : c + 1] != kind[a + 1 : b + 1])
                or np.any(dph > tol)
                or np.any(dv > tol)
            ):
                m = -1
    if m < 0:
        return None
    if where is None:
        where = np.nonzero(kind == KIND_CHATTER)[0]
    b, c = where[-2], where[-1]
    q = int(round((t[c] - t[b]) * omega_s / TWO_PI))
    return int(m - 1), q


@njit(cache=True, nogil=True)
def _chatter_cycle_length(phase, v_rel, kind, tol):
    """The test of :func:`chatter_cycle` (compiled, releases the GIL): the events from one of
    the last three chatters to the next, ``m``, when the last two cycles agree; else -1."""
    a = -1
    b = -1
    c = -1
    found = 0
    for i in range(len(kind) - 1, -1, -1):
        if kind[i] == KIND_CHATTER:
            if found == 0:
                c = i
            elif found == 1:
                b = i
            else:
                a = i
            found += 1
            if found == 3:
                break
    if found < 3 or c - b != b - a:
        return -1
    m = c - b
    for i in range(m):
        if kind[b + 1 + i] != kind[a + 1 + i]:
            return -1
    for i in range(m):
        if _circular(phase[b + 1 + i], phase[a + 1 + i]) > tol:
            return -1
    for i in range(m):
        if abs(v_rel[b + 1 + i] - v_rel[a + 1 + i]) > tol:
            return -1
    return m


#: Tolerance of a cycle's repetition without noise (radians of phase, relative velocity).
CYCLE_TOL = 1e-6
#: Under restitution noise a stable cycle repeats within its response to the noise: ``σ_e``
#: times this gain (the scatter of a cycle's phase is tens of ``σ_e``, more near a bifurcation)...
NOISE_TOL_GAIN = 1000.0
#: ...up to this resolution: a tail that scatters more is not resolved as a cycle.
NOISE_TOL_MAX = 0.1


def cycle_tolerance(e_sigma: float) -> float:
    """Tolerance of a cycle's repetition in a run with restitution noise ``e_sigma``
    (docs/model.md "Regimes"): ``max(CYCLE_TOL, min(NOISE_TOL_GAIN σ_e, NOISE_TOL_MAX))``."""
    return max(CYCLE_TOL, min(NOISE_TOL_GAIN * float(e_sigma), NOISE_TOL_MAX))


def classify(
    t: np.ndarray,
    phase: np.ndarray,
    v_rel: np.ndarray,
    kind: np.ndarray,
    omega_s: float,
    lyapunov: float,
    chatters: int | None = None,
    max_period: int = 32,
    e_sigma: float = 0.0,
    in_contact: bool = True,
) -> Regime:
    """Classify the tail of a run (docs/model.md "Regimes").

    Parameters
    ----------
    t, phase, v_rel, kind : ndarray
        The last events of a run, after its transient.
    lyapunov : float
        Exponent per impact between resets (:func:`lyapunov_exponent`), ``nan`` if unknown.
    chatters : int, optional
        Complete chatters over the whole averaging window, when longer than the tail (a rare
        reinjection may fall outside the tail); default: those in the tail.
    e_sigma : float
        The run's restitution noise: a cycle repeats within :func:`cycle_tolerance`.
    in_contact : bool
        Whether the run ended with the rotor on the stator: a tail without events is ``rest``
        only then; a rotor in flight through the whole tail (a flight longer than the window)
        is ``unresolved``.

    Returns
    -------
    Regime
        ``rest`` (no event, the rotor on the stator), ``periodic`` (``p`` impacts every ``q`` periods, no chatter in the
        tail), ``chattering-periodic`` (one chatter-to-chatter cycle repeating),
        ``chaotic-reinjection`` (chatters, no repeating cycle), ``chaotic`` (positive exponent),
        else ``unresolved``.
    """
    if len(t) == 0:
        return Regime("rest" if in_contact else "unresolved")
    tol = cycle_tolerance(e_sigma)
    in_tail = bool(np.any(kind == KIND_CHATTER))
    if in_tail:
        cyc = chatter_cycle(t, phase, v_rel, kind, omega_s, tol)
        if cyc is not None:
            return Regime("chattering-periodic", *cyc)
        return Regime("chaotic-reinjection")
    per = find_period(t, phase, v_rel, kind, omega_s, max_period, len(t), tol)
    if per is not None:
        return Regime("periodic", per.p, per.q)
    if chatters:
        return Regime("chaotic-reinjection")
    if math.isfinite(lyapunov) and lyapunov > 0.0:
        return Regime("chaotic")
    return Regime("unresolved")


def period_n_threshold(n: int, e: float) -> float:
    """``Γ_n = nπ(1 − e)/(1 + e)``: smallest ``Γ`` with a period-n orbit (docs/model.md)."""
    return n * math.pi * (1.0 - e) / (1.0 + e)


def period_doubling_threshold(n: int, e: float) -> float:
    """``Γ = sqrt(Γ_n² + (2(1 + e²)/(1 + e)²)²)``: the period-n orbit doubles (docs/model.md)."""
    g = period_n_threshold(n, e)
    return math.sqrt(g * g + (2.0 * (1.0 + e * e) / (1.0 + e) ** 2) ** 2)


def period_n_fixed_point(n: int, e: float, omega_s: float) -> tuple[float, float]:
    """Stable period-n orbit: impact phase ``φ`` (``cos φ = Γ_n/Γ``, ``sin φ > 0``) and the rotor
    velocity just after impact ``v⁺ = T/2`` with ``T = 2πn/w``."""
    g = omega_s**2
    c = period_n_threshold(n, e) / g
    if c > 1.0:
        raise ValueError(f"no period-{n} orbit below Γ_{n} = {period_n_threshold(n, e):.6g}")
    return math.acos(c), math.pi * n / omega_s
