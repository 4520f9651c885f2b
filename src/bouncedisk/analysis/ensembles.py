"""Ensembles: members that differ by their restitution-noise streams, run in parallel.

Every member is one run of the engine (:func:`bouncedisk.engine.iterate`) with its own noise
stream ``(seed, member)`` (:mod:`bouncedisk.engine.noise`), reduced chunk by chunk to the
long-run observables of MODEL.md "Long-run statistics of chaotic motion": the time-averaged
rotor speed and slip, impact and chatter rates, the Lyapunov exponent between resets, and the
regime. Memory per member is bounded (a tail of events), whatever the run's length. Members run
on a thread pool: the compiled kernel releases the GIL, so ``cores`` threads use ``cores`` cores,
and a member's numbers do not depend on how many run at once.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..engine import KIND_CHATTER, KIND_IMPACT, EngineConfig, InitialState, iterate
from ..engine.driver import audit_balances
from ..model import stator
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
    energy audit's terms over the window divided by its duration (MODEL.md "Power and energy
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


class _Reducer:
    """Streams one member's events after ``t_from`` into counts, a Lyapunov sum and a tail."""

    def __init__(self, e: float, omega_s: float, t_from: float):
        self.e = e
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
        self.tail = {k: np.empty(0) for k in ("t", "phase", "v_rel")}
        self.tail["kind"] = np.empty(0, dtype=np.int8)

    def add(self, t, phase, v_rel, kind) -> None:
        """Add one chunk's events (those before ``t_from`` are ignored)."""
        keep = t >= self.t_from
        if not np.any(keep):
            return
        t, phase, v_rel, kind = t[keep], phase[keep], v_rel[keep], kind[keep]
        self.n_impacts += int(np.count_nonzero(kind == KIND_IMPACT))
        chat = t[kind == KIND_CHATTER]
        if len(chat):
            if self.n_chatter == 0:
                self.chatter_first = float(chat[0])
            self.chatter_last = float(chat[-1])
            self.n_chatter += len(chat)
        # pairs across the chunk boundary: prepend the previous chunk's last event
        tl = self.tail
        m = 1 if len(tl["t"]) else 0
        cat = {
            k: np.concatenate([tl[k][len(tl[k]) - m :], v])
            for k, v in (("t", t), ("phase", phase), ("v_rel", v_rel), ("kind", kind))
        }
        jac, idx = ob.impact_jacobians(
            cat["t"], cat["phase"], cat["v_rel"], cat["kind"], self.e, self.w
        )
        start = self.offset - m
        skip = max(0, LYAPUNOV_SKIP - self.lyap_count)
        total, count, self.prev_pair = ob.benettin(
            jac, (idx + start).astype(np.int64), self.vec, self.prev_pair, skip
        )
        self.lyap_sum += total
        self.lyap_count += count
        self.offset += len(t)
        for k in tl:
            tl[k] = cat[k][-TAIL_EVENTS:]

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
            tl["t"], tl["phase"], tl["v_rel"], tl["kind"], self.w, lam, self.n_chatter
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


def run_member(
    cfg: EngineConfig,
    init: InitialState,
    member: int,
    t_from: float,
    should_stop: Callable[[], bool] | None = None,
) -> tuple[MemberStats, dict[str, float], dict[str, np.ndarray]]:
    """Run member ``member`` of the ensemble of ``cfg`` and reduce it after ``t_from``.

    ``cfg.t_end`` must be finite: the averages are over ``[t_from, t_end]``.

    Returns
    -------
    stats, final, tail
        The member's observables, its final state (:func:`bouncedisk.engine.iterate`) and its
        last :data:`TAIL_EVENTS` events (``t``, ``phase``, ``v_rel``, ``kind``).
    """
    if not math.isfinite(cfg.t_end) or cfg.t_end <= t_from:
        raise ValueError("an ensemble member needs a finite end time after t_from")
    cfg = dataclasses.replace(
        cfg, member=member, stats_from=t_from, traj_dt=0.0, stroboscopic=False
    )
    red = _Reducer(cfg.e, cfg.omega_s, t_from)
    gen = iterate(cfg, init)
    while True:
        if should_stop is not None and should_stop():
            raise KeyboardInterrupt
        try:
            c = next(gen)
        except StopIteration as stop:
            _, final = stop.value
            break
        red.add(c.t, c.phase, c.v_rel, c.kind)
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

    results: list[MemberStats] = []
    with ThreadPoolExecutor(max_workers=max(1, cores)) as pool:
        # map keeps member order, whatever order the threads finish in
        for st in pool.map(one, range(members)):
            results.append(st)
            if on_member:
                on_member(len(results), members)
    return results
