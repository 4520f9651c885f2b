"""Ensembles: members that differ by their restitution-noise streams, run in parallel.

Every member is one run of the engine (:func:`bouncedisk.engine.driver.iterate_views`) with its own noise
stream ``(seed, member)`` (:mod:`bouncedisk.engine.noise`), reduced chunk by chunk to the
long-run observables of docs/model.md "Long-run statistics of chaotic motion": the time-averaged
rotor speed and slip, impact and chatter rates, the Lyapunov exponent between resets, and the
regime. Memory per member is bounded (a tail of events), whatever the run's length. Members run
on a thread pool: the compiled kernel releases the GIL, so ``cores`` threads use ``cores`` cores,
and a member's numbers do not depend on how many run at once.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from math import cos, isfinite, log, sin, sqrt

import numpy as np
from numba import njit

from ..engine import KIND_CHATTER, KIND_IMPACT, EngineConfig, InitialState
from ..engine.driver import ChunkView, EngineError, audit_balances, iterate_views
from ..engine.kernel import EV_PHASE, EV_T, EV_V_REL
from ..engine.layout import ST_EVENTS
from ..engine.noise import member_key, noisy_restitution
from ..model import stator
from ..run.cores import map_on_threads
from . import observables as ob

#: Events kept from the end of each member's run to classify its regime.
TAIL_EVENTS = 1200
#: Leading Jacobian pairs of a member left out of its Lyapunov sum (vector alignment).
LYAPUNOV_SKIP = 20


@dataclass(frozen=True)
class MemberStats:
    """Long-run observables of one member over ``[t_from, t_end]`` (nondimensional).

    ``lyapunov`` is ``-inf`` for a chattering-periodic member (its cycle passes through a reset,
    whose Jacobian is zero) and ``nan`` when too few free flights were seen. The powers are the
    energy audit's terms over the window divided by its duration (docs/model.md "Power and energy
    audit"): the load's ``τ_L Ω̄``, the stator's torsional and axial inputs, the axial energy left
    to summed chattering tails; ``efficiency_torsion = W_L / W_t``; the residuals are the
    balances' relative residuals (:func:`bouncedisk.engine.driver.audit_balances`).
    """

    member: int
    mean_omega: float
    mean_slip: float
    impact_rate: float
    chatter_rate: float
    chatter_interval: float
    lyapunov: float
    regime: int
    period_p: int
    period_q: int
    n_impacts: int
    n_chatter: int
    duration: float
    power_out: float = math.nan
    power_torsion_in: float = math.nan
    power_axial_in: float = math.nan
    power_chatter_axial: float = math.nan
    efficiency_torsion: float = math.nan
    audit_residual_axial: float = math.nan
    audit_residual_torsion: float = math.nan


# slots of the reducer's state arrays (:func:`_reduce_chunk`)
_I_IMPACTS, _I_CHATTER, _I_PREV, _I_OFFSET, _I_SKIP, _I_COUNT, _I_TAIL = range(7)
_I_SEEN = 7  # events of the run seen so far, before t_from too (the next row's noise counter)
_N_INTS = 8
_F_FIRST, _F_LAST, _F_TOTAL, _F_SIN, _F_COS = range(5)
_F_E = 5  # restitution of the tail's last row
_N_FLOATS = 6
#: Where Benettin's vector restarts: ``(1, 1)/√2``.
_RESET = 1.0 / sqrt(2.0)


@njit(cache=True, nogil=True, inline="always")
def _pair_jacobian(p_t, p_vr, p_s, p_c, p_e, tj, s_j, vr_j, e, w):
    """The impact map's Jacobian of two successive impacts, if they are one free flight apart.

    The previous impact at ``p_t`` (``sin φ, cos φ = p_s, p_c``, relative velocity ``p_vr``,
    restitution ``p_e``) and this one at ``tj`` (``s_j = sin φ``, ``vr_j``, restitution ``e``).
    The pair is valid when the flight from the first lands on the second
    (``|landing − s_j| < 1e-7 (1 + Δt²)``) with ``vr_j > 0``; returns ``(valid, a, b, j10,
    j11)``, the formulas and the order of operations of
    :func:`~bouncedisk.analysis.observables.impact_jacobians` (docs/model.md "Impact map
    Jacobian").
    """
    vs = w * p_c
    v_post = vs + p_e * p_vr
    dt = tj - p_t
    landing = p_s + v_post * dt - 0.5 * (dt * dt)
    if not (abs(landing - s_j) < 1e-7 * (1.0 + dt * dt) and vr_j > 0.0):
        return False, 0.0, 0.0, 0.0, 0.0
    a = (vs - v_post + dt) / vr_j
    b = dt / vr_j
    c = e - (1.0 + e) * w * w * s_j
    return True, a, b, c * a - e, c * b - e


@njit(cache=True, nogil=True, inline="always")
def _benettin_step(vec, a, b, j10, j11):
    """One step of Benettin's method on the unit vector ``vec`` (updated in place).

    Returns the norm of the Jacobian times ``vec`` (``log`` of it is the step's stretch), or 0
    when it is zero or not finite, and ``vec`` restarts at ``(1, 1)/√2``
    (:func:`~bouncedisk.analysis.observables.benettin`).
    """
    x = a * vec[0] + b * vec[1]
    y = j10 * vec[0] + j11 * vec[1]
    norm = sqrt(x * x + y * y)
    if norm == 0.0 or not isfinite(norm):
        vec[0] = _RESET
        vec[1] = _RESET
        return 0.0
    vec[0] = x / norm
    vec[1] = y / norm
    return norm


@njit(cache=True, nogil=True)
def _keep_tail(t, phase, v_rel, kind, t_from, kept, tail_f, tail_k, n_tail):
    """The tail becomes the last ``TAIL_EVENTS`` rows: the previous one's last row (if
    ``n_tail > 0``) in front of the chunk's ``kept`` rows with ``t >= t_from``; returns its length.
    """
    rows = kept + (1 if n_tail > 0 else 0)
    n_new = min(rows, TAIL_EVENTS)
    if kept < n_new:  # the previous last row stays, first
        tail_f[0, 0] = tail_f[n_tail - 1, 0]
        tail_f[0, 1] = tail_f[n_tail - 1, 1]
        tail_f[0, 2] = tail_f[n_tail - 1, 2]
        tail_k[0] = tail_k[n_tail - 1]
    i = n_new - 1
    for j in range(len(t) - 1, -1, -1):
        if i < n_new - kept or i < 0:
            break
        if not t[j] >= t_from:
            continue
        tail_f[i, 0] = t[j]
        tail_f[i, 1] = phase[j]
        tail_f[i, 2] = v_rel[j]
        tail_k[i] = kind[j]
        i -= 1
    return n_new


@njit(cache=True, nogil=True)
def _reduce_chunk(t, phase, v_rel, kind, t_from, noise, w, vec, ints, fl, tail_f, tail_k):
    """One chunk of :meth:`_Reducer.add`, compiled (releases the GIL); returns the rows kept.

    The events with ``t >= t_from``, preceded by the tail's last row, are counted and walked
    pair by pair: the impact map's Jacobian of each valid pair (:func:`_pair_jacobian`, with
    each impact's own restitution: ``noise = (e, e_sigma, key)``, the chunk's first row being
    the run's event ``ints[_I_SEEN]``; :func:`~bouncedisk.engine.noise.noisy_restitution`) goes
    straight into Benettin's step (:func:`_benettin_step`); the chunk's sum of logs and its
    count go to ``fl[_F_TOTAL]``, ``ints[_I_COUNT]``; the tail is renewed (:func:`_keep_tail`).
    The state arrays ``ints``, ``fl`` (slots ``_I_*``, ``_F_*``) carry the counts from chunk to
    chunk. The stator's ``sin φ``, ``cos φ`` come from libm, as in the engine: the same bits as
    numpy's on the reference machine (``model/stator.py``; 2e8 phases compared), and
    ``tests/test_ensemble_reducer.py`` holds the whole reduction to the numpy one.
    """
    n_tail = ints[_I_TAIL]
    have = n_tail > 0  # the previous row of the first pair
    start = ints[_I_OFFSET] - (1 if have else 0)
    skip, prev = ints[_I_SKIP], ints[_I_PREV]
    n_imp, n_chat = ints[_I_IMPACTS], ints[_I_CHATTER]
    first, last = fl[_F_FIRST], fl[_F_LAST]
    e, e_sigma, key = noise
    seen = ints[_I_SEEN]
    p_t, p_vr, p_k, p_s, p_c, p_e = 0.0, 0.0, 0, 0.0, 0.0, e
    if have:
        p_t, p_vr, p_k = tail_f[n_tail - 1, 0], tail_f[n_tail - 1, 2], tail_k[n_tail - 1]
        p_s, p_c, p_e = fl[_F_SIN], fl[_F_COS], fl[_F_E]
    total = 0.0
    count = 0
    j_pair = 0  # index of the pair among this chunk's valid pairs
    li = 1 if have else 0  # index of the row in the chunk's rows with the previous one in front
    for j in range(len(t)):
        tj = t[j]
        if not tj >= t_from:
            continue
        kj = kind[j]
        if kj == KIND_IMPACT:
            n_imp += 1
        elif kj == KIND_CHATTER:
            if n_chat == 0:
                first = tj
            last = tj
            n_chat += 1
        ph_j = phase[j]
        s_j = sin(ph_j)
        vr_j = v_rel[j]
        e_j = noisy_restitution(e, e_sigma, key, seen + j) if e_sigma > 0.0 else e
        if li > 0 and p_k == KIND_IMPACT and kj == KIND_IMPACT:
            valid, a, b, j10, j11 = _pair_jacobian(p_t, p_vr, p_s, p_c, p_e, tj, s_j, vr_j, e_j, w)
            if valid:
                k = li - 1 + start
                if k != prev + 1:
                    vec[0] = _RESET
                    vec[1] = _RESET
                prev = k
                norm = _benettin_step(vec, a, b, j10, j11)
                if norm > 0.0 and j_pair >= skip:
                    total += log(norm)
                    count += 1
                j_pair += 1
        p_t, p_vr, p_k, p_s, p_c, p_e = tj, vr_j, kj, s_j, cos(ph_j), e_j
        li += 1
    ints[_I_SEEN] = seen + len(t)
    kept = li - (1 if have else 0)
    if kept == 0:
        return 0
    ints[_I_TAIL] = _keep_tail(t, phase, v_rel, kind, t_from, kept, tail_f, tail_k, n_tail)
    ints[_I_IMPACTS], ints[_I_CHATTER], ints[_I_PREV], ints[_I_COUNT] = n_imp, n_chat, prev, count
    fl[_F_FIRST], fl[_F_LAST], fl[_F_TOTAL], fl[_F_SIN], fl[_F_COS] = first, last, total, p_s, p_c
    fl[_F_E] = p_e
    return kept


class _Reducer:
    """Streams one member's events after ``t_from`` into counts, a Lyapunov sum and a tail.

    The reduction of a chunk is compiled and releases the GIL (:func:`_reduce_chunk`), so the
    members of an ensemble reduce in parallel as they run. ``e_sigma, seed, member``: the run's
    restitution noise (its events' own ``e_k`` enter the Jacobians); every chunk of the run must
    be added, from its first event, those before ``t_from`` too.
    """

    def __init__(
        self,
        e: float,
        omega_s: float,
        t_from: float,
        e_sigma: float = 0.0,
        seed: int = 0,
        member: int = 0,
    ):
        self.e = e
        key = np.uint64(member_key(np.int64(seed), np.int64(member)) if e_sigma > 0.0 else 0)
        self._noise = (float(e), float(e_sigma), key)
        self.w = omega_s
        self.t_from = t_from
        self.n_impacts = 0
        self.n_chatter = 0
        self.chatter_first = math.nan
        self.chatter_last = math.nan
        self.lyap_sum = 0.0
        self.lyap_count = 0
        self.vec = np.full(2, 1.0 / math.sqrt(2.0))
        self.prev_pair = -2
        self.offset = 0  # global index of the first event kept
        # the tail (the last chunk's events, and the one before them), with sin and cos of its
        # last phase (the first row of the next chunk's pairs)
        self._tail_f = np.empty((TAIL_EVENTS, 3))  # t, phase, v_rel
        self._tail_k = np.empty(TAIL_EVENTS, dtype=np.int8)
        self._ints = np.zeros(_N_INTS, dtype=np.int64)
        self._floats = np.zeros(_N_FLOATS)

    @property
    def tail(self) -> dict[str, np.ndarray]:
        """The last events kept: ``t``, ``phase``, ``v_rel``, ``kind`` (copies)."""
        n = int(self._ints[_I_TAIL])
        f = self._tail_f[:n]
        return {
            "t": f[:, 0].copy(),
            "phase": f[:, 1].copy(),
            "v_rel": f[:, 2].copy(),
            "kind": self._tail_k[:n].copy(),
        }

    def add(self, t, phase, v_rel, kind) -> None:
        """Add one chunk's events (those before ``t_from`` are ignored).

        The same numbers, bit for bit, as :func:`~bouncedisk.analysis.observables.impact_jacobians`
        and :func:`~bouncedisk.analysis.observables.benettin` over the chunk's events after
        ``t_from`` with the previous chunk's last one in front.
        """
        ints = self._ints
        ints[_I_IMPACTS] = self.n_impacts
        ints[_I_CHATTER] = self.n_chatter
        ints[_I_PREV] = self.prev_pair
        ints[_I_OFFSET] = self.offset
        ints[_I_SKIP] = max(0, LYAPUNOV_SKIP - self.lyap_count)
        fl = self._floats
        fl[_F_FIRST] = self.chatter_first
        fl[_F_LAST] = self.chatter_last
        kept = _reduce_chunk(
            t,
            phase,
            v_rel,
            kind,
            self.t_from,
            self._noise,
            self.w,
            self.vec,
            ints,
            fl,
            self._tail_f,
            self._tail_k,
        )
        if kept == 0:
            return
        self.n_impacts = int(ints[_I_IMPACTS])
        self.n_chatter = int(ints[_I_CHATTER])
        self.chatter_first = float(fl[_F_FIRST])
        self.chatter_last = float(fl[_F_LAST])
        self.lyap_sum += float(fl[_F_TOTAL])
        self.lyap_count += int(ints[_I_COUNT])
        self.prev_pair = int(ints[_I_PREV])
        self.offset += kept

    def result(
        self, member: int, final: dict, t_end: float, r_phi: float, psi: float
    ) -> MemberStats:
        """The member's :class:`MemberStats` from its final state (``final["omega_integral"]``
        = ``∫Ω dt`` over the window, ``final["audit"]`` the energy audit's terms)."""
        omega_integral = final["omega_integral"]
        dur = t_end - self.t_from
        mean_om = omega_integral / dur
        # ∫Ω_s dt = φ_s(t_end) − φ_s(t_from), φ_s = sin(w t + ψ): the mean slip s = RΩ − Ω_s
        twist = stator.twist(self.w * t_end, psi) - stator.twist(self.w * self.t_from, psi)
        tl = self.tail
        lam = self.lyap_sum / self.lyap_count if self.lyap_count else math.nan
        reg = ob.classify(
            tl["t"],
            tl["phase"],
            tl["v_rel"],
            tl["kind"],
            self.w,
            lam,
            self.n_chatter,
            e_sigma=self._noise[1],
            in_contact=bool(final["in_contact"]),
        )
        if reg.name == "chattering-periodic":
            lam = -math.inf
        interval = math.nan
        if self.n_chatter >= 2:
            interval = (self.chatter_last - self.chatter_first) / (self.n_chatter - 1)
        return MemberStats(
            member=member,
            mean_omega=mean_om,
            mean_slip=r_phi * mean_om - twist / dur,
            impact_rate=self.n_impacts / dur,
            chatter_rate=self.n_chatter / dur,
            chatter_interval=interval,
            lyapunov=lam,
            regime=reg.code,
            period_p=reg.p,
            period_q=reg.q,
            n_impacts=self.n_impacts,
            n_chatter=self.n_chatter,
            duration=dur,
            **_powers(final["audit"], dur),
        )


def _powers(audit: dict, duration: float) -> dict[str, float]:
    """Mean powers, efficiency and audit residuals of one member (see :class:`MemberStats`)."""
    res_ax, res_t = audit_balances(audit)
    w_t = audit["work_torsion"]
    return {
        "power_out": audit["work_load"] / duration,
        "power_torsion_in": w_t / duration,
        "power_axial_in": audit["work_axial"] / duration,
        "power_chatter_axial": audit["chatter_axial"] / duration,
        "efficiency_torsion": audit["work_load"] / w_t if w_t > 0.0 else math.nan,
        "audit_residual_axial": res_ax,
        "audit_residual_torsion": res_t,
    }


class CappedRun(EngineError):
    """A member stopped at its safety cap on events (``max_events``) before the end of its
    averaging window: its time averages would be over a window the run did not reach."""

    def __init__(self, member: int, t_reached: float, t_end: float, max_events: int):
        self.member = member
        self.t_reached = t_reached
        self.t_end = t_end
        self.max_events = max_events
        super().__init__(self.said(), ST_EVENTS)

    def said(self, who: str | None = None) -> str:
        """The message, naming the run as ``who`` (a basin map's start, say), else its member."""
        return (
            f"{who or f'member {self.member}'} stopped at the safety cap of {self.max_events} "
            f"events at t = {self.t_reached:.6g}, before the end of its averaging window "
            f"(t = {self.t_end:.6g})"
        )


def run_member(
    cfg: EngineConfig,
    init: InitialState,
    member: int,
    t_from: float,
    should_stop: Callable[[], bool] | None = None,
    on_chunk: Callable[[ChunkView], None] | None = None,
) -> tuple[MemberStats, dict[str, float], dict[str, np.ndarray]]:
    """Run member ``member`` of the ensemble of ``cfg`` and reduce it after ``t_from``.

    ``cfg.t_end`` must be finite: the averages are over ``[t_from, t_end]``. With ``on_chunk``
    every chunk's views (:class:`bouncedisk.engine.driver.ChunkView`, valid until the next
    chunk) are handed to it, and the trajectory samples ``cfg`` asks for are kept in them;
    without, the run takes no samples.

    Returns
    -------
    stats, final, tail
        The member's observables, its final state (:func:`bouncedisk.engine.iterate`) and its
        last :data:`TAIL_EVENTS` events (``t``, ``phase``, ``v_rel``, ``kind``).

    Raises
    ------
    CappedRun
        The run stopped at ``cfg.max_events`` before ``cfg.t_end``: no average over the window.
    """
    if not math.isfinite(cfg.t_end) or cfg.t_end <= t_from:
        raise ValueError("an ensemble member needs a finite end time after t_from")
    traj_dt = cfg.traj_dt if on_chunk is not None else 0.0
    cfg = dataclasses.replace(
        cfg, member=member, stats_from=t_from, traj_dt=traj_dt, stroboscopic=False
    )
    red = _Reducer(cfg.e, cfg.omega_s, t_from, cfg.e_sigma, cfg.seed, member)
    gen = iterate_views(cfg, init)  # the kernel's buffers, reduced in place: no copies
    while True:
        if should_stop is not None and should_stop():
            raise KeyboardInterrupt
        try:
            c = next(gen)
        except StopIteration as stop:
            status, final = stop.value
            break
        ev = c.ev
        red.add(ev[:, EV_T], ev[:, EV_PHASE], ev[:, EV_V_REL], c.evk)
        if on_chunk is not None:
            on_chunk(c)
    if status == ST_EVENTS:  # the cap, not the window's end, stopped the run
        raise CappedRun(member, final["t"], cfg.t_end, cfg.max_events)
    stats = red.result(member, final, cfg.t_end, cfg.r_phi, cfg.psi)
    return stats, final, red.tail


def run_ensemble(
    cfg: EngineConfig,
    init: InitialState,
    members: int,
    t_from: float,
    cores: int = 1,
    on_member: Callable[[int, int], None] | None = None,
    should_stop: Callable[[], bool] | None = None,
) -> list[MemberStats]:
    """Run members ``0 … members−1`` on ``cores`` threads; results in member order.

    ``on_member(done, total)`` is called as members finish (progress); ``should_stop()`` is
    polled between chunks and stops every member with ``KeyboardInterrupt``.
    """

    def one(m: int) -> MemberStats:
        return run_member(cfg, init, m, t_from, should_stop)[0]

    return map_on_threads(one, range(members), cores, on_member)
