"""The compiled event loop: flights, impacts, chattering, contact with stick–slip, separation.

One call of :func:`run_chunk` advances the simulation until its output buffers are full or the
run ends; the whole state lives in two small arrays so that a run can be resumed chunk after
chunk (streaming output, progress reporting, interruption). Time is carried as an integer
stator-period count ``n`` and a phase ``θ ∈ [0, 2π)``: ``t = (2πn + θ)/w``. Every event phase is
therefore exact to the rounding of one period, however long the run (docs/model.md "Things that are
easy to get wrong").

One compiled function per mode of motion (docs/model.md "Phases of motion", "Events"):

- flight → impact: :func:`_flight_step`, i.e. :func:`flight_next_impact` (first root of the
  gap, eq. 20) and :func:`_impact_sc` (restitution and angular impulse, eqs. 4, 8, 19; flight,
  contact or chatter after it), the row written by :func:`_record_event`;
- chattering: :func:`_enter_contact` (the jump to the accumulation point) and
  :func:`_chatter_tail` (its event);
- contact: :func:`_contact_step`, one segment ending at the first of the horizons of
  :func:`_contact_horizon` or a stick–slip transition (:func:`_slip_root`, :func:`_stick_root`,
  eqs. 22–23, §2.5), then :func:`_contact_advance` and :func:`_contact_end` (separation);
- the clipped model's unloaded ride: :func:`_clipped_ride`.

Samples and ``∫Ω dt`` of every segment go through :func:`_segment_output` (:func:`_sample`).

Array layouts (indices below) are private to the engine; :mod:`bouncedisk.engine.driver` fills
and reads them. :func:`run_chunk` and the helpers that take these arrays are compiled with
``_nrt=False`` (:data:`_on_arrays`): they allocate nothing, and numba's reference counting
would otherwise add an atomic increment and decrement of every array argument to every call,
which cost up to 27 % of the throughput when the loop was first split into these functions
(``benchmarks/compare_engine.py``, the contact-heavy case). The steps of every impact
(:func:`_flight_step`, :func:`_flight_search`, :func:`_flight_land`) and of every contact
segment (:func:`_contact_step`, :func:`_contact_end`) are moreover inlined into their callers
(:data:`_on_arrays_inline`): a call passes each array argument as its fields (pointer, shape,
strides, ...), some 70 words on the stack for these (100 with the event columns), which cost
4-5 % of the axial-only throughput. Inlining changes no result bit (no fast-math: the same
operations in the same order).

The event buffer is a tuple of column arrays (``EV_*``), not one 2-d array, so that
:func:`~bouncedisk.engine.driver.simulate_arrays` can hand the kernel its output arrays
themselves: the events are written once, where they stay.
"""

from math import cos, floor, inf, pi, sin, sqrt

import numpy as np
from numba import njit

from . import _cache  # noqa: F401  (the cache locators, before anything here is decorated)
from .laws import (
    GRAZE_GAP,
    chatter_time_sc,
    contact_axial_work,
    impact_law_sc,
    loaded_omega,
    loaded_omega_integral,
    normal_load,
    separation_phase,
    separation_window,
    slip,
    slip_load_omega_integral,
    slip_omega,
    slip_omega_integral,
    slip_twist_work,
    stick_margin_shift,
    stick_omega_integral,
    stick_twist_work,
)
from .layout import *  # the array layouts and codes (plain integers), re-exported
from .noise import member_key, noisy_restitution
from .roots import TWO_PI, first_root, first_root_walk, floor_turns, inflections, no_root


def _nrt_off() -> dict:
    """``{"_nrt": False}`` where this numba has the (private) option, else ``{}`` (slower, same bits)."""
    try:
        from numba.core.cpu import CPUTargetOptions
    except ImportError:  # pragma: no cover - numba moved it
        return {}
    return {"_nrt": False} if hasattr(CPUTargetOptions, "_nrt") else {}


#: Decorator of the compiled helpers that read and write the caller's arrays and allocate nothing:
#: no reference counting of their array arguments (module docstring).
_on_arrays = njit(cache=True, **_nrt_off())

#: :data:`_on_arrays`, inlined into its callers by numba: for the steps of every impact and
#: contact segment, whose calls would pass every array argument's fields on the stack.
_on_arrays_inline = njit(cache=True, inline="always", **_nrt_off())


@njit(cache=True, inline="always")
def _advance(n, th, dphi):
    """Add ``dphi`` to phase ``th`` of period ``n``; returns the reduced ``(n, θ)``."""
    x = th + dphi
    k = floor_turns(x)  # floor(x / 2π)
    r = x - k * TWO_PI
    if r >= TWO_PI:
        r -= TWO_PI
        k += 1
    elif r < 0.0:
        r += TWO_PI
        k -= 1
    return n + np.int64(k), r


@njit(cache=True)
def flight_next_impact(
    u0: float, v0: float, th0: float, ta: float, ga: float, w: float, xtol: float, infl: tuple
) -> tuple[float, int, float, float]:
    """Next impact of a flight (first root of the gap, paper eq. 20).

    The flight starts at the origin ``(u0, v0)`` at stator phase ``th0``; the search starts at
    the anchor ``ta >= 0`` after the origin, where the gap is ``ga >= 0``. The rotor cannot hit
    the stator while ``u > 1``, so a flight rising above the band ``|u| <= 1`` is searched only
    while ascending below 1 and after it falls back to ``u = 1`` (docs/model.md "Events").
    ``infl`` is the gap's :func:`~bouncedisk.engine.roots.inflections` ``(0, −1, −1/2, w)``, the
    same for every flight of a run (:func:`run_chunk` computes it once).

    Returns
    -------
    tau, dk, phase, v_minus
        Time of impact after the origin (-1 on failure), whole stator periods added to the
        origin's period count, the impact phase in ``[0, 2π)``, the rotor velocity before impact.
    """
    s0 = 0.0
    c0 = 0.0
    if ta == 0.0:
        s0 = sin(th0)
        c0 = cos(th0)
    return _flight_root(u0, v0, th0, s0, c0, ta, ga, w, xtol, infl)


@njit(cache=True)
def _flight_root(u0, v0, th0, s0, c0, ta, ga, w, xtol, infl):
    """:func:`flight_next_impact` with ``s0, c0 = sin θ0, cos θ0`` given (read only when
    ``ta == 0``): the impact that starts a flight has computed them already."""
    fd, dl, bt = infl
    va = v0 - ta
    if ta == 0.0:
        ka = 0
        pha = th0
        ua = u0
        sa = s0
        ca = c0
    else:
        ka, pha = _advance(0, th0, w * ta)
        sa = sin(pha)
        ca = cos(pha)
        ua = sa + ga
    if ua < 1.0:
        if va > 0.0 and va * va > 2.0 * (1.0 - ua):
            disc = sqrt(va * va - 2.0 * (1.0 - ua))
            t_up = 2.0 * (1.0 - ua) / (va + disc)
            r = _gap_root(ga, va, pha, sa, ca, w, t_up, xtol, fd, dl, bt)
            if r >= 0.0:
                k, ph = _advance(ka, pha, w * r)
                return ta + r, k, ph, va - r
            t_dn = va + disc
            vd = -disc
        else:
            t_bot = va + sqrt(va * va + 2.0 * (ua + 1.0))
            t_max = t_bot * (1.0 + 1e-12) + 1e-12
            r = _gap_root(ga, va, pha, sa, ca, w, t_max, xtol, fd, dl, bt)
            if r < 0.0:
                return -1.0, 0, 0.0, 0.0
            k, ph = _advance(ka, pha, w * r)
            return ta + r, k, ph, va - r
    else:
        rad = sqrt(va * va + 2.0 * (ua - 1.0))
        t_dn = va + rad
        vd = -rad
    k2, ph2 = _advance(ka, pha, w * t_dn)
    s2 = sin(ph2)
    c2 = cos(ph2)  # next to sin: one call of sincos
    g2 = 1.0 - s2
    t_bot2 = 4.0 / (sqrt(vd * vd + 4.0) - vd)
    t_max = t_bot2 * (1.0 + 1e-12) + 1e-12
    r = _gap_root(g2, vd, ph2, s2, c2, w, t_max, xtol, fd, dl, bt)
    if r < 0.0:
        return -1.0, 0, 0.0, 0.0
    k, ph = _advance(k2, ph2, w * r)
    return ta + t_dn + r, k, ph, vd - r


@njit(cache=True, inline="always")
def _gap_root(g0, v, th, s, c, w, t_max, xtol, fd, dl, bt):
    """First root of a flight's gap ``g0 + vτ − τ²/2 − (sin φ − sin θ)`` (``s, c = sin θ,
    cos θ``): :func:`~bouncedisk.engine.roots.first_root_from` without recomputing them, its
    first shortcut (:func:`~bouncedisk.engine.roots.no_root`) tested once, here."""
    if g0 < 0.0:
        return 0.0
    if no_root(g0, v, -0.5, 0.0, -1.0, th, s, c, w, t_max):  # a flight's ascent: no call
        return -1.0
    return first_root_walk(g0, v, -0.5, 0.0, -1.0, th, s, c, w, t_max, xtol, fd, dl, bt)


@njit(cache=True, inline="always")
def _seg_state(kind, u0, v0, om0, sig, w, r, psi, load, th0, tau):
    """Rotor ``(u, v, Ω)`` at ``tau`` into a segment, from the closed forms (with the load
    torque ``τ_L``, docs/model.md "The motor under load")."""
    if kind == SEG_FLIGHT:
        return u0 + v0 * tau - 0.5 * tau * tau, v0 - tau, loaded_omega(om0, load, tau)
    ph = th0 + w * tau
    if kind == SEG_SLIP:
        return sin(ph), w * cos(ph), slip_omega(om0, sig, w, th0, tau, load)
    if kind == SEG_STICK:
        return sin(ph), w * cos(ph), w * cos(ph + psi) / r
    return sin(ph), w * cos(ph), loaded_omega(om0, load, tau)


@_on_arrays
def _sample_range(n_a, th_a, length, inclusive, prm, flg, ist):
    """Trajectory rows ``[j0, j1)`` and stroboscopic periods ``[k0, k1)`` that fall in a segment.

    The segment starts at period ``n_a``, phase ``th_a`` and lasts ``length``; ``inclusive``
    takes a sample at its very end too (the end of the run).
    """
    w = prm[P_W]
    t_b = (n_a * TWO_PI + th_a) / w + length
    j0 = ist[I_NEXT_SAMPLE]
    j1 = j0
    if flg[F_TRAJ]:
        dt = prm[P_DT]
        t0 = prm[P_T0]
        jmax = np.int64(1) << 62
        if prm[P_T1] < inf:
            jmax = np.int64(floor((prm[P_T1] - t0) / dt + 1e-9))
        x = (t_b - t0) / dt
        j1 = np.int64(floor(x + 1e-9)) + 1 if inclusive else np.int64(np.ceil(x))
        if j1 > jmax + 1:
            j1 = jmax + 1
        if j1 < j0:
            j1 = j0
    k0 = ist[I_NEXT_STROBE]
    k1 = k0
    if flg[F_STROBE]:
        # period k starts at phase 0: tau_k = (2π(k − n_a) − θ_a)/w
        x = (th_a + w * length) / TWO_PI
        k1 = n_a + np.int64(floor(x)) + 1
        if not inclusive and (k1 - 1 - n_a) * TWO_PI - th_a >= w * length:
            k1 -= 1
        if k1 < k0:
            k1 = k0
    return j0, j1, k0, k1


@_on_arrays
def _write_samples(kind, n_a, th_a, u0, v0, om0, sig, prm, traj, n_tr, j, strobe, n_sb, k):
    """Write trajectory rows ``j = (j0, j1)`` and stroboscopic rows ``k = (k0, k1)`` of a segment.

    The rotor's state comes from the segment's closed form (:func:`_seg_state`). Returns the new
    row counts.
    """
    w = prm[P_W]
    r = prm[P_R]
    psi = prm[P_PSI]
    load = prm[P_LOAD]
    t_a = (n_a * TWO_PI + th_a) / w
    dt = prm[P_DT]
    t0 = prm[P_T0]
    for i in range(j[0], j[1]):
        tj = t0 + i * dt
        tau = tj - t_a
        u, v, om = _seg_state(kind, u0, v0, om0, sig, w, r, psi, load, th_a, tau)
        traj[n_tr, TR_T] = tj
        traj[n_tr, TR_U] = u
        traj[n_tr, TR_V] = v
        traj[n_tr, TR_U_STATOR] = sin(th_a + w * tau)
        traj[n_tr, TR_OMEGA] = om
        n_tr += 1
    for i in range(k[0], k[1]):
        tau = ((i - n_a) * TWO_PI - th_a) / w
        u, v, om = _seg_state(kind, u0, v0, om0, sig, w, r, psi, load, th_a, tau)
        strobe[n_sb, SB_PERIOD] = i
        strobe[n_sb, SB_T] = i * TWO_PI / w
        strobe[n_sb, SB_U] = u
        strobe[n_sb, SB_V] = v
        strobe[n_sb, SB_OMEGA] = om
        n_sb += 1
    return n_tr, n_sb


@_on_arrays
def _sample(
    kind, n_a, th_a, length, inclusive, u0, v0, om0, sig, prm, flg, ist, traj, strobe, info
):
    """Write the trajectory and stroboscopic samples falling in a segment.

    Returns ``ST_CONTINUE``, the row counts in ``info`` updated. When a buffer fills up inside
    the segment, the samples that fit are written, the sample counters ``I_NEXT_SAMPLE`` /
    ``I_NEXT_STROBE`` record how far the segment got, ``info`` gets the status ``ST_NEED_TRAJ``
    (or ``ST_NEED_STROBE``), the rows still to write (``O_NEED``) and the row counts including
    the rows just written (``O_TRAJ_PARTIAL``, ``O_STROBE_PARTIAL``), and that status is
    returned: the caller returns without advancing the state, the driver takes the full buffers,
    and the next call resumes the same segment where the samples stopped. The buffers are
    therefore bounded whatever one segment's length (a flight of 1e10 time units).
    """
    j0, j1, k0, k1 = _sample_range(n_a, th_a, length, inclusive, prm, flg, ist)
    n_tr = info[O_TRAJ]
    n_sb = info[O_STROBE]
    # rows that do not fit in this call are left for the next one (see the docstring)
    full = ST_CONTINUE
    need = 0
    if n_tr + (j1 - j0) > traj.shape[0]:
        need = j1 - j0
        j1 = j0 + (traj.shape[0] - n_tr)
        full = ST_NEED_TRAJ
    if n_sb + (k1 - k0) > strobe.shape[0]:
        if full == ST_CONTINUE:
            need = k1 - k0
            full = ST_NEED_STROBE
        k1 = k0 + (strobe.shape[0] - n_sb)
    n_tr, n_sb = _write_samples(
        kind, n_a, th_a, u0, v0, om0, sig, prm, traj, n_tr, (j0, j1), strobe, n_sb, (k0, k1)
    )
    if flg[F_TRAJ]:
        ist[I_NEXT_SAMPLE] = j1
    if flg[F_STROBE]:
        ist[I_NEXT_STROBE] = k1
    if full != ST_CONTINUE:
        info[O_STATUS] = full
        info[O_NEED] = need
        info[O_TRAJ_PARTIAL] = n_tr
        info[O_STROBE_PARTIAL] = n_sb
        return full
    info[O_TRAJ] = n_tr
    info[O_STROBE] = n_sb
    return ST_CONTINUE


@njit(cache=True, inline="always")
def _omega_integral(kind, om0, sig, w, r, psi, load, th0, tau):
    """``∫_0^τ Ω dτ'`` over the first ``τ`` of a segment (closed forms; see :func:`_seg_state`)."""
    if kind == SEG_SLIP:
        return slip_omega_integral(om0, sig, w, th0, tau, load)
    if kind == SEG_STICK:
        return stick_omega_integral(w, r, psi, th0, tau)
    return loaded_omega_integral(om0, load, tau)


@_on_arrays
def _accumulate(st, ist, prm, flg, kind, n_a, th_a, length, u0, v0, om0, sig):
    """Add the part of a segment after ``prm[P_TSTAT]`` to ``∫Ω dt`` and the energy audit.

    On the first segment that reaches into the window, the rotor's axial and rotational energy
    there are kept (``S_AUD_E0``, ``S_AUD_K0``) for the audit's balances.
    """
    w = prm[P_W]
    tau0 = prm[P_TSTAT] - (n_a * TWO_PI + th_a) / w
    if tau0 >= length:
        return
    r = prm[P_R]
    psi = prm[P_PSI]
    load = prm[P_LOAD]
    total = _omega_integral(kind, om0, sig, w, r, psi, load, th_a, length)
    if tau0 > 0.0:
        total -= _omega_integral(kind, om0, sig, w, r, psi, load, th_a, tau0)
    st[S_OMEGA_INTEGRAL] += total
    tb = tau0 if tau0 > 0.0 else 0.0
    u, v, om = _seg_state(kind, u0, v0, om0, sig, w, r, psi, load, th_a, tb)
    if not ist[I_AUD_STARTED]:
        ist[I_AUD_STARTED] = 1
        st[S_AUD_E0] = 0.5 * v * v + u
        st[S_AUD_K0] = 0.5 * om * om
    _audit_segment(st, prm, flg, kind, sig, om, th_a + w * tb, length - tb)


@_on_arrays
def _audit_segment(st, prm, flg, kind, sig, om, th, length):
    """The energy audit's terms of a segment from phase ``th``, with ``Ω = om`` there, ``length``
    long (docs/model.md "Power and energy audit"; closed forms in :mod:`.laws`): the stator's axial
    work in contact, and in contact with torsion its torsional input and the friction loss."""
    if kind == SEG_FLIGHT:
        return
    w = prm[P_W]
    if flg[F_AXIAL_AUDIT]:
        st[S_AUD_WAX] += contact_axial_work(w, th, length)
    if kind == SEG_SLIP:
        r = prm[P_R]
        load = prm[P_LOAD]
        w_t = slip_twist_work(sig, w, r, prm[P_PSI], th, length)
        st[S_AUD_WT] += w_t
        st[S_AUD_DF] += w_t + sig * slip_load_omega_integral(om, sig, w, th, length, load)
    elif kind == SEG_STICK:
        st[S_AUD_WT] += stick_twist_work(w, prm[P_R], prm[P_PSI], prm[P_LOAD], th, length)


@_on_arrays
def _audit_impact(st, prm, flg, w, r, psi, phase, v_minus, v_plus, om_minus, om_plus, settles):
    """The energy audit's terms of an impact (docs/model.md "Power and energy audit").

    Axial: the impulse ``F = v⁺ − v⁻`` does the work ``F v_s`` and dissipates
    ``F (v_s − (v⁺ + v⁻)/2)``. Torsional: the angular impulse ``J = Ω⁺ − Ω⁻`` puts in
    ``J Ω_s/R`` and dissipates ``−J ((Ω⁺ + Ω⁻)/2 − Ω_s/R)`` (``H |Ω_avg − Ω_s/R|`` when the slip
    does not reverse). An impact after which the rotor ``settles`` on the stator (a summed
    chattering tail, or a rebound below the grazing gap) leaves it at ``v_s``: the energy
    ``(v⁺² − v_s²)/2`` its remaining bounces dissipate is kept apart (``S_AUD_CAX``).
    """
    if flg[F_AXIAL_AUDIT]:
        vs = w * cos(phase)
        f = v_plus - v_minus
        st[S_AUD_WAX] += f * vs
        st[S_AUD_DAX] += f * (vs - 0.5 * (v_plus + v_minus))
        if settles:
            st[S_AUD_CAX] += 0.5 * (v_plus - vs) * (v_plus + vs)
    j = om_plus - om_minus
    if j != 0.0:
        os_r = w * cos(phase + psi) / r
        st[S_AUD_WT] += j * os_r
        st[S_AUD_DF] -= j * (0.5 * (om_plus + om_minus) - os_r)


@_on_arrays
def _segment_output(kind, n_a, th_a, length, inclusive, prm, flg, st, ist, traj, strobe, info):
    """Outputs of a segment that starts at the current state: its samples and ``∫Ω dt``.

    Called before the state moves past the segment (``kind`` ``SEG_*``, from period ``n_a`` and
    phase ``th_a``, ``length`` long, ``inclusive`` of its end). Returns ``ST_CONTINUE``, or the
    status of a sample buffer that filled up inside the segment (:func:`_sample`).
    """
    u0 = 0.0
    v0 = 0.0
    if kind == SEG_FLIGHT:
        u0 = st[S_U]
        v0 = st[S_V]
    om0 = st[S_OMEGA]
    sig = float(ist[I_SLIP_SIGN]) if kind == SEG_SLIP else 0.0
    if flg[F_TRAJ] or flg[F_STROBE]:
        status = _sample(
            kind, n_a, th_a, length, inclusive, u0, v0, om0, sig, prm, flg, ist, traj, strobe, info
        )
        if status != ST_CONTINUE:
            return status
    if flg[F_STATS]:
        _accumulate(st, ist, prm, flg, kind, n_a, th_a, length, u0, v0, om0, sig)
    return ST_CONTINUE


@_on_arrays
def _finish(ist, info, status):
    """End the run with ``status`` (kept in the state: a later call returns it again)."""
    if ist[I_MODE] != MODE_DONE:
        ist[I_LASTMODE] = ist[I_MODE]
    ist[I_MODE] = MODE_DONE
    ist[I_STATUS] = status
    info[O_STATUS] = status
    return status


@njit(cache=True, inline="always")
def _record_event(ev, evk, ist, info, t, phase, v_rel, omega_after, omega_before, kind):
    """Write one event, row ``info[O_EVENTS]`` of the columns ``ev[EV_*]`` (the rotor at the
    stator, ``u = sin φ``)."""
    i = info[O_EVENTS]
    ev[EV_T][i] = t
    ev[EV_PHASE][i] = phase
    ev[EV_V_REL][i] = v_rel
    ev[EV_OMEGA_AFTER][i] = omega_after
    ev[EV_U][i] = sin(phase)
    ev[EV_OMEGA_BEFORE][i] = omega_before
    evk[i] = kind
    info[O_EVENTS] = i + 1
    ist[I_EVENTS] += 1


@njit(cache=True, inline="always")
def _enter_flight(st, ist, u, v, anchor_tau, anchor_gap):
    """Start a flight from ``(u, v)`` at the current phase; the impact search starts at the anchor."""
    ist[I_MODE] = MODE_FLIGHT
    st[S_U] = u
    st[S_V] = v
    st[S_ANCHOR_TAU] = anchor_tau
    st[S_ANCHOR_GAP] = anchor_gap


@_on_arrays
def _flight_output(prm, flg, st, ist, traj, strobe, info, n, th, t_now, t_hit, tau):
    """Outputs of a flight up to its impact; or up to the run's end, if that comes first.

    The flight is the parabola of docs/model.md "Phases of motion" (``u'' = −1``, ``Ω`` constant).
    When the run's end ``t_end < t_hit`` comes first, the state is moved to ``t_end`` and the run
    ends with ``ST_TIME``. Returns ``ST_CONTINUE`` or the status that ends this call.
    """
    t_end = prm[P_TEND]
    ends = t_hit > t_end
    length = t_end - t_now if ends else tau
    # np.int64: one compiled _segment_output for every kind (a literal kind compiled its own)
    kind = np.int64(SEG_FLIGHT)
    status = _segment_output(kind, n, th, length, ends, prm, flg, st, ist, traj, strobe, info)
    if status != ST_CONTINUE or not ends:
        return status
    u0 = st[S_U]
    v0 = st[S_V]
    st[S_U] = u0 + v0 * length - 0.5 * length * length
    st[S_V] = v0 - length
    st[S_OMEGA] = loaded_omega(st[S_OMEGA], prm[P_LOAD], length)
    ist[I_PERIOD], st[S_PHASE] = _advance(n, th, prm[P_W] * length)
    return _finish(ist, info, ST_TIME)


@njit(cache=True)
def _impact_sc(e_k, e, w, r, psi, phase, sph, cph, v_minus, omega, torsion, cap, inertia, tol):
    """An impact and what follows it: flight, contact, or a chattering sequence.

    The impact law (docs/model.md "Events"; paper eqs. 4, 8, 19, or 11 with ``stator_inertia``) with
    this impact's restitution ``e_k``, with ``sph, cph = sin φ, cos φ`` of the impact phase given;
    then, if ``N >= 0``, contact when the rebound is below the grazing gap, or the accumulation
    time of a complete chattering sequence (docs/model.md "Chattering",
    :func:`~bouncedisk.engine.laws.chatter_time`, with the mean ``e``).

    Returns
    -------
    v_rel, v_plus, omega_plus, go_contact, t_acc
        Relative impact velocity, rotor velocities after the impact, whether the rotor enters
        contact, and the time from the impact to the accumulation point (-1: none).
    """
    v_rel, v_plus, omega_plus = impact_law_sc(
        e_k, w, r, psi, phase, cph, v_minus, omega, torsion, cap, inertia
    )
    n_load = 1.0 - w * w * sph  # normal_load(w, phase)
    w_rel = e_k * v_rel
    go_contact = False
    t_acc = -1.0
    if n_load >= 0.0:
        if w_rel <= GRAZE_GAP * (1.0 + w):
            go_contact = True
        else:
            t_acc = chatter_time_sc(e, w, sph, cph, w_rel, tol)
            if t_acc > 0.0:
                go_contact = True
    return v_rel, v_plus, omega_plus, go_contact, t_acc


@_on_arrays
def _enter_contact(st, ist, prm, torsion, n_hit, phase, t_acc):
    """Contact after the impact at ``(n_hit, phase)``, or a chattering sequence (``t_acc > 0``).

    A chattering sequence (docs/model.md "Chattering") accumulates ``t_acc`` after the impact: the
    rotor rides the stator until then, and the accumulation point is an event of its own
    (:func:`_chatter_tail`). With torsion, the slip state on entering contact
    (:func:`_enter_contact_torsion`).
    """
    w = prm[P_W]
    ist[I_MODE] = MODE_CONTACT
    ist[I_SLIP_GUARD] = 0
    ist[I_ZERO_STEPS] = 0
    if t_acc > 0.0:
        ist[I_CHATTERING] = 1
        ist[I_CHATTER_PERIOD], st[S_CHATTER_PHASE] = _advance(n_hit, phase, w * t_acc)
    else:
        ist[I_CHATTERING] = 0
    ist[I_SLIP_SIGN] = 0
    if torsion:
        _enter_contact_torsion(st, ist, prm, phase)


@_on_arrays
def _chatter_tail(st, ist, ev, evk, info, w, n1, th1):
    """The accumulation point of a chattering sequence: one event of kind ``KIND_CHATTER``.

    docs/model.md "Counting impacts": the infinitely many impacts of a complete chattering sequence
    count as one event, at the accumulation time, with zero relative velocity.
    """
    ist[I_CHATTERING] = 0
    om = st[S_OMEGA]
    _record_event(ev, evk, ist, info, (n1 * TWO_PI + th1) / w, th1, 0.0, om, om, KIND_CHATTER)


@njit(cache=True)
def _separation_constants(w):
    """``(never, θ_sep, T, g)``: whether contact never ends (``w <= 1`` or a grazing window),
    the separation phase and the flight through the window ``N < 0`` (docs/model.md "Contact";
    :func:`~bouncedisk.engine.laws.separation_window`)."""
    never_sep = w <= 1.0
    th_sep = -1.0
    t_win = 0.0
    g_win = 0.0
    if not never_sep:
        t_win, g_win, _v_win = separation_window(w)
        if g_win < GRAZE_GAP:
            never_sep = True
        else:
            th_sep = separation_phase(w)
    return never_sep, th_sep, t_win, g_win


@_on_arrays
def _clipped_ride(prm, flg, st, ist, traj, strobe, info, n, th, t_now, th_sep):
    """Clipped spring-contact model, unloaded (paper refs. [2, 3]): ride to the window's end.

    ``N = max(0, 1 + a_s)`` is clipped to 0 while ``1 + a_s < 0`` (phases ``(θ_sep, π − θ_sep)``):
    no friction torque, the rotor rides the stator and its ``Ω`` changes only under the load
    torque (``Ω' = −τ_L``, docs/model.md "The motor under load"). Returns ``ST_CONTINUE`` or the
    status that ends this call.
    """
    w = prm[P_W]
    th_back = pi - th_sep
    d = th_back - th
    if d < 0.0:
        d += TWO_PI
    seg = min(d / w, prm[P_TEND] - t_now)
    ends = seg < d / w
    kind = np.int64(SEG_CONTACT)  # one compiled _segment_output (as _flight_output)
    status = _segment_output(kind, n, th, seg, ends, prm, flg, st, ist, traj, strobe, info)
    if status != ST_CONTINUE:
        return status
    if ends:
        ist[I_PERIOD], st[S_PHASE] = _advance(n, th, w * seg)
        st[S_U] = sin(st[S_PHASE])
        st[S_V] = w * cos(st[S_PHASE])
        st[S_OMEGA] = loaded_omega(st[S_OMEGA], prm[P_LOAD], seg)
        return _finish(ist, info, ST_TIME)
    ist[I_PERIOD] = n + (1 if th > th_back else 0)
    st[S_PHASE] = th_back
    st[S_OMEGA] = loaded_omega(st[S_OMEGA], prm[P_LOAD], seg)
    ist[I_UNLOADED] = 0
    if flg[F_TORSION]:
        _enter_contact_torsion(st, ist, prm, th_back)
    return ST_CONTINUE


@_on_arrays
def _contact_horizon(n, th, t_now, st, ist, prm, never_sep, th_sep):
    """Times from now to the separation, the run's end and a chattering accumulation point.

    Separation at ``θ_sep`` (``N = 0`` decreasing, docs/model.md "Contact"); ``inf`` for none.
    """
    w = prm[P_W]
    tau_sep = inf
    if not never_sep:
        d = th_sep - th
        if d < 0.0:
            if th < pi - th_sep:
                d = 0.0  # N < 0 by rounding: separate now
            else:
                d += TWO_PI
        tau_sep = d / w
    tau_t = prm[P_TEND] - t_now
    tau_c = inf
    if ist[I_CHATTERING]:
        tau_c = ((ist[I_CHATTER_PERIOD] - n) * TWO_PI + (st[S_CHATTER_PHASE] - th)) / w
        if tau_c < 0.0:
            tau_c = 0.0
    return tau_sep, tau_t, tau_c


@njit(cache=True)
def _slip_root(sig, guard, om, th, tau_end, w, r, psi, load, xtol):
    """End of a slipping segment (docs/model.md "Stick–slip transitions"; paper eqs. 22–23).

    Slipping with ``σ = sgn(s)``, ``Ω' = −σN``. Just after leaving ``s = 0`` (``guard``) the
    segment ends where the slip has grown, ``RN + σα_s`` back to ``>= 0``; otherwise it ends
    where ``s`` reaches zero (eq. 23 corrected). Returns ``(seg, slip_zero)``: the segment's
    length (``tau_end`` if neither comes first) and whether it ends at ``s = 0``.
    """
    if guard:
        s0 = sin(th + psi)
        q0 = -r * normal_load(w, th) + sig * w * w * s0
        if load != 0.0:
            q0 -= sig * stick_margin_shift(r, load)
        if q0 < 0.0:
            q0 = 0.0
        a = sig * w * w * sin(psi)
        b = r * w * w + sig * w * w * cos(psi)
        tq = first_root(q0, 0.0, 0.0, a, b, th, w, tau_end, xtol)
        return (tq, False) if tq >= 0.0 else (tau_end, False)
    f0 = sig * slip(r, w, psi, om, th)
    if f0 < 0.0:
        f0 = 0.0
    a = -r * w - sig * w * cos(psi)
    c1 = -r
    if load != 0.0:
        c1 -= sig * stick_margin_shift(r, load)
    tz = first_root(f0, c1, 0.0, a, sig * w * sin(psi), th, w, tau_end, xtol)
    return (tz, True) if tz >= 0.0 else (tau_end, False)


@njit(cache=True)
def _stick_root(th, tau_end, w, r, psi, rho, load, xtol):
    """End of a sticking segment (docs/model.md "Stick–slip transitions"; paper §2.5 corrected).

    While ``RΩ = Ω_s`` the rotor sticks until ``|α_s| = ρRN`` (``ρ`` the static/kinetic
    ratio); with ``α_s < −ρRN`` the slip becomes positive, with ``α_s > ρRN`` negative. Searched
    over at most one stator period. Returns ``(seg, new_sig, slips)``: the segment's length
    (``tau_end`` if it sticks throughout), the new ``sgn(s)`` and whether it starts slipping.
    """
    win = tau_end
    per = TWO_PI / w
    if win > per:
        win = per
    rr = rho * r
    best = -1.0
    new_sig = 0
    for sgn in (1.0, -1.0):
        m0 = rr * normal_load(w, th) - sgn * w * w * sin(th + psi)
        if load != 0.0:
            m0 += sgn * stick_margin_shift(r, load)
        if m0 < 0.0:
            m0 = 0.0
        a = -sgn * w * w * sin(psi)
        b = -rr * w * w - sgn * w * w * cos(psi)
        rt = first_root(m0, 0.0, 0.0, a, b, th, w, win, xtol)
        if rt >= 0.0 and (best < 0.0 or rt < best):
            best = rt
            new_sig = np.int64(sgn)
    if best >= 0.0:
        return best, new_sig, True
    return tau_end, 0, False


@_on_arrays
def _contact_segment(st, ist, prm, torsion, th, tau_end):
    """The next contact segment: its kind (``SEG_*``), length, and whether it ends at a
    stick–slip transition (``hit``), with the slip direction after it (``new_sig``)."""
    sig = ist[I_SLIP_SIGN]
    if not torsion:
        return SEG_CONTACT, tau_end, False, sig
    w = prm[P_W]
    r = prm[P_R]
    psi = prm[P_PSI]
    xtol = prm[P_TOL]
    if sig != 0:
        guard = ist[I_SLIP_GUARD]
        seg, hit = _slip_root(sig, guard, st[S_OMEGA], th, tau_end, w, r, psi, prm[P_LOAD], xtol)
        return SEG_SLIP, seg, hit, sig
    seg, new_sig, hit = _stick_root(th, tau_end, w, r, psi, prm[P_MU_RATIO], prm[P_LOAD], xtol)
    return SEG_STICK, seg, hit, new_sig


@_on_arrays
def _contact_advance(st, ist, prm, kind, hit, new_sig, th, seg, n1, th1):
    """Move the contact state to the segment's end ``(n1, th1)``: ``Ω`` and the stick–slip state.

    ``Ω`` from eq. 23 corrected (slip) or ``RΩ = Ω_s`` (stick). A slip that reaches zero sticks
    or slips on in the stator's direction (§2.5, :func:`_enter_contact_torsion`); a stick that
    ends starts slipping with the guard set.
    """
    w = prm[P_W]
    r = prm[P_R]
    psi = prm[P_PSI]
    om = st[S_OMEGA]
    if kind == SEG_SLIP:
        om = slip_omega(om, float(ist[I_SLIP_SIGN]), w, th, seg, prm[P_LOAD])
    elif kind == SEG_STICK:
        om = w * cos(th1 + psi) / r
    ist[I_PERIOD] = n1
    st[S_PHASE] = th1
    st[S_OMEGA] = om
    if kind == SEG_SLIP:
        if ist[I_SLIP_GUARD]:
            ist[I_SLIP_GUARD] = 0
        elif hit:
            # the slip reached zero: stick, or slip on in the stator's direction (§2.5)
            st[S_OMEGA] = w * cos(th1 + psi) / r
            _enter_contact_torsion(st, ist, prm, th1)
    elif kind == SEG_STICK and hit:
        ist[I_SLIP_SIGN] = new_sig
        ist[I_SLIP_GUARD] = 1


@_on_arrays_inline
def _contact_end(st, ist, ev, evk, info, prm, clipped, taus, tau_end, n1, th1, sep):
    """What ends a contact segment at the first of its horizons ``taus = (sep, end, chatter)``.

    The run's end (``ST_TIME``); a chattering sequence's accumulation point (an event,
    :func:`_chatter_tail`), after which contact goes on; separation (docs/model.md "Separation"):
    the rotor flies through the window where ``N < 0`` and the impact search starts at its end
    (or, in the clipped model, rides unloaded, :func:`_clipped_ride`).
    """
    tau_sep, tau_t, tau_c = taus
    w = prm[P_W]
    if tau_end == tau_t:
        st[S_U] = sin(th1)
        st[S_V] = w * cos(th1)
        return _finish(ist, info, ST_TIME)
    if tau_end == tau_c and ist[I_CHATTERING]:
        _chatter_tail(st, ist, ev, evk, info, w, n1, th1)
        if tau_c < tau_sep:
            return ST_CONTINUE
    if tau_end == tau_sep and clipped:
        ist[I_UNLOADED] = 1
    elif tau_end == tau_sep:
        # separation: fly through the window where N < 0, then search from its end
        _never, th_sep, t_win, g_win = sep
        _enter_flight(st, ist, 1.0 / (w * w), w * cos(th_sep), t_win, g_win)
        ist[I_CHATTERING] = 0
    return ST_CONTINUE


@_on_arrays_inline
def _flight_step(prm, flg, st, ist, ev, evk, traj, strobe, info, n, th, t_now, noise_key, infl):
    """A flight and the impact that ends it (docs/model.md "Flight", "Impact").

    The first root of the gap (:func:`_flight_search`, eq. 20) with this impact's
    restitution (``restitution_noise``: ``e_k``, :mod:`.noise`), then :func:`_flight_land`.
    Returns ``ST_CONTINUE`` or the status that ends this call. ``infl``: the gap's inflection
    data (:func:`flight_next_impact`).
    """
    tau, dk, ph, v_minus = _flight_search(st, th, prm[P_W], prm[P_TOL], infl)
    if tau < 0.0:
        return _finish(ist, info, ST_NUMERICAL)
    e = prm[P_E]
    e_k = noisy_restitution(e, prm[P_ESIG], noise_key, ist[I_EVENTS]) if flg[F_NOISE] else e
    hit = (tau, dk, ph, v_minus, e_k)
    return _flight_land(prm, flg, st, ist, ev, evk, traj, strobe, info, n, th, t_now, hit)


@_on_arrays_inline
def _flight_search(st, th, w, xtol, infl):
    """The flight's impact ``(tau, dk, phase, v_minus)`` (:func:`_flight_root`, eq. 20), with the
    sine and cosine of its origin's phase kept by the impact that started it when they are."""
    ta = st[S_ANCHOR_TAU]
    s0 = 0.0
    c0 = 0.0
    if ta == 0.0:
        if st[S_SC_PHASE] == th and th != 0.0:  # kept by the impact that started the flight
            s0 = st[S_SC_SIN]
            c0 = st[S_SC_COS]
        else:
            s0 = sin(th)
            c0 = cos(th)
    return _flight_root(st[S_U], st[S_V], th, s0, c0, ta, st[S_ANCHOR_GAP], w, xtol, infl)


@_on_arrays_inline
def _flight_land(prm, flg, st, ist, ev, evk, traj, strobe, info, n, th, t_now, hit):
    """The rest of a flight once its impact ``hit = (tau, dk, phase, v_minus, e_k)`` is known.

    The flight's outputs (:func:`_flight_output`, which ends the run if its end comes first);
    the impact law with the restitution ``e_k`` and what follows (:func:`_impact_sc`); its event
    row; then a new flight, contact or a chattering sequence (:func:`_enter_contact`). Nothing
    here feeds back into the axial motion through ``Ω``, so runs that differ only in the load
    share ``hit`` (:mod:`bouncedisk.engine.loads`). Returns ``ST_CONTINUE`` or the status that
    ends this call.
    """
    tau, dk, ph, v_minus, e_k = hit
    e = prm[P_E]
    w = prm[P_W]
    xtol = prm[P_TOL]
    torsion = flg[F_TORSION] != 0
    cap = flg[F_CAP] != 0
    n_hit = n + dk
    t_hit = (n_hit * TWO_PI + ph) / w
    if flg[F_TRAJ] or flg[F_STROBE] or flg[F_STATS] or t_hit > prm[P_TEND]:
        status = _flight_output(prm, flg, st, ist, traj, strobe, info, n, th, t_now, t_hit, tau)
        if status != ST_CONTINUE:
            return status
    r = prm[P_R]
    psi = prm[P_PSI]
    om = loaded_omega(st[S_OMEGA], prm[P_LOAD], tau)
    sph = sin(ph)
    cph = cos(ph)
    v_rel, v_plus, om_plus, go_contact, t_acc = _impact_sc(
        e_k, e, w, r, psi, ph, sph, cph, v_minus, om, torsion, cap, prm[P_INERTIA], xtol
    )
    if flg[F_STATS] and t_hit > prm[P_TSTAT]:
        _audit_impact(st, prm, flg, w, r, psi, ph, v_minus, v_plus, om, om_plus, go_contact)
    _record_event(ev, evk, ist, info, t_hit, ph, v_rel, om_plus, om, KIND_IMPACT)
    ist[I_PERIOD] = n_hit
    st[S_PHASE] = ph
    st[S_OMEGA] = om_plus
    if not go_contact:
        _enter_flight(st, ist, sph, v_plus, 0.0, 0.0)
        st[S_SC_PHASE] = ph
        st[S_SC_SIN] = sph
        st[S_SC_COS] = cph
    elif flg[F_CONTACT]:
        _enter_contact(st, ist, prm, torsion, n_hit, ph, t_acc)
    else:
        return _finish(ist, info, ST_NEED_CONTACT)
    return ST_CONTINUE


@_on_arrays_inline
def _contact_step(prm, flg, st, ist, ev, evk, traj, strobe, info, n, th, t_now, sep):
    """One contact segment (docs/model.md "Contact", "Stick–slip transitions", "Separation").

    The rotor rides the stator (``u = u_s``, ``v = v_s``) until the first of: separation, the
    run's end, a chattering accumulation point (:func:`_contact_horizon`), or a stick–slip
    transition (:func:`_contact_segment`). Returns ``ST_CONTINUE`` or the status that ends this
    call (the rotor at rest, a stall, a full buffer, the run's end).
    """
    never_sep, th_sep = sep[0], sep[1]
    taus = _contact_horizon(n, th, t_now, st, ist, prm, never_sep, th_sep)
    tau_sep, tau_t, tau_c = taus
    tau_end = min(tau_sep, tau_t, tau_c)
    clipped = flg[F_CLIPPED] != 0
    if tau_end == inf or (clipped and prm[P_TEND] == inf):
        return _finish(ist, info, ST_REST)
    kind, seg, hit, new_sig = _contact_segment(st, ist, prm, flg[F_TORSION] != 0, th, tau_end)
    if seg > 0.0:
        ist[I_ZERO_STEPS] = 0
    else:
        ist[I_ZERO_STEPS] += 1
        if ist[I_ZERO_STEPS] > 32:
            return _finish(ist, info, ST_NUMERICAL)
    at_end = (not hit) and seg == tau_end
    inclusive = at_end and tau_end == tau_t
    status = _segment_output(kind, n, th, seg, inclusive, prm, flg, st, ist, traj, strobe, info)
    if status != ST_CONTINUE:
        return status
    # the segment's end point: exact at a separation or an accumulation point
    if at_end and tau_end == tau_sep and tau_sep < tau_t and tau_sep <= tau_c:
        n1 = n + (1 if th > th_sep else 0)
        th1 = th_sep
    elif at_end and tau_end == tau_c and tau_c < tau_t:
        n1 = ist[I_CHATTER_PERIOD]
        th1 = st[S_CHATTER_PHASE]
    else:
        n1, th1 = _advance(n, th, prm[P_W] * seg)
    _contact_advance(st, ist, prm, kind, hit, new_sig, th, seg, n1, th1)
    if not at_end:
        return ST_CONTINUE
    return _contact_end(st, ist, ev, evk, info, prm, clipped, taus, tau_end, n1, th1, sep)


@njit(cache=True, nogil=True, **_nrt_off())  # as _on_arrays, and releases the GIL
def run_chunk(
    prm: np.ndarray,
    flg: np.ndarray,
    st: np.ndarray,
    ist: np.ndarray,
    ev: tuple,
    evk: np.ndarray,
    traj: np.ndarray,
    strobe: np.ndarray,
    info: np.ndarray,
) -> None:
    """Advance the simulation; see the module docstring.

    The event loop: a flight ends at its impact (:func:`flight_next_impact`, :func:`_impact_sc`,
    one event row, :func:`_record_event`), which leads to a flight, contact or a chattering
    sequence (:func:`_enter_contact`); contact goes on segment by segment
    (:func:`_contact_step`, or :func:`_clipped_ride` in the clipped model).

    Parameters
    ----------
    prm, flg : ndarray
        Parameters and effect flags (layouts ``P_*`` and ``F_*``).
    st, ist : ndarray
        Float and integer state (``S_*``, ``I_*``), updated in place.
    ev : tuple of ndarray
        Event buffer: ``EV_COLS`` float columns ``(cap,)`` (indices ``EV_*``), each its own
        array, so that the driver can hand the kernel the run's output arrays themselves.
    evk : ndarray
        Event kinds ``(cap,)``; its length is the buffer's capacity.
    traj, strobe : ndarray
        Sample buffers ``(cap, TRAJ_COLS)`` and ``(cap, STROBE_COLS)`` (columns ``TR_*``, ``SB_*``).
    info : ndarray
        Output (``O_*``): status, events, trajectory and stroboscopic rows written, rows needed.
    """
    w = prm[P_W]
    noise_key = member_key(flg[F_SEED], flg[F_MEMBER])
    sep = _separation_constants(w)
    gap_infl = inflections(0.0, -1.0, -0.5, w)  # every flight's gap: u'' = -1, u_s = sin
    info[O_EVENTS:N_OUT] = 0
    if ist[I_MODE] == MODE_DONE:
        _finish(ist, info, ist[I_STATUS])
        return
    while True:
        if ist[I_EVENTS] >= flg[F_MAXEV]:
            _finish(ist, info, ST_EVENTS)
            return
        if info[O_EVENTS] >= evk.shape[0]:
            info[O_STATUS] = ST_CHUNK
            return
        n = ist[I_PERIOD]
        th = st[S_PHASE]
        t_now = (n * TWO_PI + th) / w
        if ist[I_MODE] == MODE_FLIGHT:
            status = _flight_step(
                prm, flg, st, ist, ev, evk, traj, strobe, info, n, th, t_now, noise_key, gap_infl
            )
        elif ist[I_UNLOADED]:
            status = _clipped_ride(prm, flg, st, ist, traj, strobe, info, n, th, t_now, sep[1])
        else:
            status = _contact_step(
                prm, flg, st, ist, ev, evk, traj, strobe, info, n, th, t_now, sep
            )
        if status != ST_CONTINUE:
            return


@njit(cache=True, inline="always")
def _slip_is_zero(r, w, psi, omega, phase):
    """``s = RΩ − Ω_s`` is zero to rounding."""
    return abs(slip(r, w, psi, omega, phase)) <= 1e-14 * (abs(r * omega) + w)


@njit(cache=True)
def _contact_sigma(r, w, psi, rho, load, omega, phase):
    """Slip direction in contact: ``sgn(s)``, or at ``s = 0`` stick (0) when
    ``|α_s + Rτ_L| <= ρRN``, else the direction set by the stator's acceleration and the load
    (paper §2.5, corrected; docs/model.md "The motor under load")."""
    if not _slip_is_zero(r, w, psi, omega, phase):
        return 1 if slip(r, w, psi, omega, phase) > 0.0 else -1
    n_load = normal_load(w, phase)
    alpha = -w * w * sin(phase + psi)
    if load != 0.0:
        alpha += stick_margin_shift(r, load)
    if abs(alpha) <= rho * r * n_load:
        return 0
    return 1 if alpha < 0.0 else -1


@_on_arrays
def _enter_contact_torsion(st, ist, prm, phase):
    """Torsional state on entering contact at ``phase`` with the rotor's current ``Ω``.

    Sets the slip direction (:func:`_contact_sigma`); when the rotor leaves ``s = 0`` the guard,
    so the slip search starts once the slip has grown (module ``run_chunk``); when it sticks,
    ``RΩ = Ω_s`` exactly.
    """
    r = prm[P_R]
    w = prm[P_W]
    psi = prm[P_PSI]
    om = st[S_OMEGA]
    sig = _contact_sigma(r, w, psi, prm[P_MU_RATIO], prm[P_LOAD], om, phase)
    ist[I_SLIP_SIGN] = sig
    ist[I_SLIP_GUARD] = 1 if sig != 0 and _slip_is_zero(r, w, psi, om, phase) else 0
    if sig == 0:
        st[S_OMEGA] = w * cos(phase + psi) / r
