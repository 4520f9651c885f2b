"""The compiled event loop: flights, impacts, chattering, contact with stick–slip, separation.

One call advances the simulation until its output buffers are full or the run ends; the whole
state lives in two small arrays so that a run can be resumed chunk after chunk (streaming output,
progress reporting, interruption). Time is carried as an integer stator-period count ``n`` and a
phase ``θ ∈ [0, 2π)``: ``t = (2πn + θ)/w``. Every event phase is therefore exact to the
rounding of one period, however long the run (MODEL.md "Things that are easy to get wrong").

Array layouts (indices below) are private to the engine; :mod:`bouncedisk.engine.driver` fills
and reads them.
"""

from math import cos, floor, inf, pi, sin, sqrt

import numpy as np
from numba import njit

from .laws import (
    GRAZE_GAP,
    chatter_time,
    impact_law,
    separation_phase,
    separation_window,
    slip_omega,
    slip_omega_integral,
    stick_omega_integral,
)
from .noise import member_key, noisy_restitution
from .roots import TWO_PI, first_root

# --- parameter vector (float64) ---------------------------------------------------------------
P_E, P_W, P_R, P_PSI, P_TOL, P_INERTIA, P_RHO, P_TEND, P_DT, P_T0, P_T1 = range(11)
P_ESIG = 11  # restitution noise σ_e (effect `restitution_noise`)
P_TSTAT = 12  # time from which ∫Ω dt is accumulated (ensemble statistics)
N_PRM = 13
# --- flags (int64) ----------------------------------------------------------------------------
F_CONTACT, F_TORSION, F_CAP, F_TRAJ, F_STROBE, F_MAXEV, F_CLIPPED = range(7)
F_NOISE, F_SEED, F_MEMBER, F_STATS = range(7, 11)  # restitution noise stream; accumulate ∫Ω dt
N_FLG = 11
# --- float state ------------------------------------------------------------------------------
S_TH, S_U, S_V, S_OM, S_TA, S_GA, S_THC = range(7)
S_IOM = 7  # ∫Ω dt since prm[P_TSTAT] (when flg[F_STATS])
N_ST = 8
# --- int state --------------------------------------------------------------------------------
I_N, I_MODE, I_SIG, I_GUARD, I_CHAT, I_NC, I_NEV, I_JTRAJ, I_KSTROBE, I_ZERO, I_STATUS, I_FREE = (
    range(12)
)
I_LASTMODE = 12  # the mode (flight or contact) the run ended in
N_IST = 13
# --- modes ------------------------------------------------------------------------------------
MODE_FLIGHT, MODE_CONTACT, MODE_DONE = 0, 1, 2
# --- statuses ---------------------------------------------------------------------------------
ST_CHUNK = 0  # a buffer is full; call again
ST_EVENTS = 1  # the requested number of events was reached
ST_TIME = 2  # the requested end time was reached
ST_REST = 3  # the rotor stays in contact for ever: no further impact can occur
ST_NEED_CONTACT = 4  # the dynamics need the `contact` effect, which the scene left out
ST_NUMERICAL = 5  # a root search failed or made no progress
ST_NEED_TRAJ = 6  # trajectory buffer full inside a segment; rows written: info[5], info[6]
ST_NEED_STROBE = 7  # stroboscopic buffer full inside a segment (as ST_NEED_TRAJ)
# --- event kinds ------------------------------------------------------------------------------
KIND_IMPACT, KIND_CHATTER = 0, 1
# --- segment kinds for sampling ---------------------------------------------------------------
SEG_FLIGHT, SEG_CONTACT, SEG_SLIP, SEG_STICK = 0, 1, 2, 3

# GRAZE_GAP (laws): separations whose whole flight stays below it are grazing (stay in contact)
EV_COLS = 6  # t, phase, v_rel, omega_after, u, omega_before
TRAJ_COLS = 5  # t, u, v, u_stator, omega
STROBE_COLS = 5  # period, t, u, v, omega


@njit(cache=True, inline="always")
def _advance(n, th, dphi):
    """Add ``dphi`` to phase ``th`` of period ``n``; returns the reduced ``(n, θ)``."""
    x = th + dphi
    k = floor(x / TWO_PI)
    r = x - k * TWO_PI
    if r >= TWO_PI:
        r -= TWO_PI
        k += 1
    elif r < 0.0:
        r += TWO_PI
        k -= 1
    return n + np.int64(k), r


@njit(cache=True)
def flight_next_impact(u0, v0, th0, ta, ga, w, xtol):
    """Next impact of a flight (first root of the gap, paper eq. 20).

    The flight starts at the origin ``(u0, v0)`` at stator phase ``th0``; the search starts at
    the anchor ``ta >= 0`` after the origin, where the gap is ``ga >= 0``. The rotor cannot hit
    the stator while ``u > 1``, so a flight rising above the band ``|u| <= 1`` is searched only
    while ascending below 1 and after it falls back to ``u = 1`` (MODEL.md "Events").

    Returns
    -------
    tau, dk, phase, v_minus
        Time of impact after the origin (-1 on failure), whole stator periods added to the
        origin's period count, the impact phase in ``[0, 2π)``, the rotor velocity before impact.
    """
    va = v0 - ta
    if ta == 0.0:
        ka = 0
        pha = th0
        ua = u0
    else:
        ka, pha = _advance(0, th0, w * ta)
        ua = sin(pha) + ga
    if ua < 1.0:
        if va > 0.0 and va * va > 2.0 * (1.0 - ua):
            disc = sqrt(va * va - 2.0 * (1.0 - ua))
            t_up = 2.0 * (1.0 - ua) / (va + disc)
            r = first_root(ga, va, -0.5, 0.0, -1.0, pha, w, t_up, xtol)
            if r >= 0.0:
                k, ph = _advance(ka, pha, w * r)
                return ta + r, k, ph, va - r
            t_dn = va + disc
            vd = -disc
        else:
            t_bot = va + sqrt(va * va + 2.0 * (ua + 1.0))
            r = first_root(ga, va, -0.5, 0.0, -1.0, pha, w, t_bot * (1.0 + 1e-12) + 1e-12, xtol)
            if r < 0.0:
                return -1.0, 0, 0.0, 0.0
            k, ph = _advance(ka, pha, w * r)
            return ta + r, k, ph, va - r
    else:
        rad = sqrt(va * va + 2.0 * (ua - 1.0))
        t_dn = va + rad
        vd = -rad
    k2, ph2 = _advance(ka, pha, w * t_dn)
    g2 = 1.0 - sin(ph2)
    t_bot2 = 4.0 / (sqrt(vd * vd + 4.0) - vd)
    r = first_root(g2, vd, -0.5, 0.0, -1.0, ph2, w, t_bot2 * (1.0 + 1e-12) + 1e-12, xtol)
    if r < 0.0:
        return -1.0, 0, 0.0, 0.0
    k, ph = _advance(k2, ph2, w * r)
    return ta + t_dn + r, k, ph, vd - r


@njit(cache=True, inline="always")
def _seg_state(kind, u0, v0, om0, sig, w, r, psi, th0, tau):
    """Rotor ``(u, v, Ω)`` at ``tau`` into a segment, from the closed forms."""
    if kind == SEG_FLIGHT:
        return u0 + v0 * tau - 0.5 * tau * tau, v0 - tau, om0
    ph = th0 + w * tau
    if kind == SEG_SLIP:
        return sin(ph), w * cos(ph), slip_omega(om0, sig, w, th0, tau)
    if kind == SEG_STICK:
        return sin(ph), w * cos(ph), w * cos(ph + psi) / r
    return sin(ph), w * cos(ph), om0


@njit(cache=True)
def _sample(
    kind,
    n_a,
    th_a,
    length,
    inclusive,
    u0,
    v0,
    om0,
    sig,
    prm,
    flg,
    ist,
    traj,
    n_tr,
    strobe,
    n_sb,
    info,
):
    """Write the trajectory and stroboscopic samples falling in a segment.

    Returns the new row counts. When a buffer fills up inside the segment, the samples that fit
    are written, the sample counters ``I_JTRAJ`` / ``I_KSTROBE`` record how far the segment got,
    ``info`` gets the status ``ST_NEED_TRAJ`` (or ``ST_NEED_STROBE``), the rows still to write
    (``info[4]``) and the row counts written in this call (``info[5]``, ``info[6]``), and
    ``(-1, -1)`` is returned: the caller returns without advancing the state, the driver takes
    the full buffers, and the next call resumes the same segment where the samples stopped. The
    buffers are therefore bounded whatever one segment's length (a flight of 1e10 time units).
    """
    w = prm[P_W]
    r = prm[P_R]
    psi = prm[P_PSI]
    t_a = (n_a * TWO_PI + th_a) / w
    t_b = t_a + length
    j0 = ist[I_JTRAJ]
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
    k0 = ist[I_KSTROBE]
    k1 = k0
    if flg[F_STROBE]:
        # period k starts at phase 0: tau_k = (2π(k − n_a) − θ_a)/w
        x = (th_a + w * length) / TWO_PI
        k1 = n_a + np.int64(floor(x)) + 1
        if not inclusive and (k1 - 1 - n_a) * TWO_PI - th_a >= w * length:
            k1 -= 1
        if k1 < k0:
            k1 = k0
    # rows that do not fit in this call are left for the next one (see the docstring)
    full = 0
    need = 0
    if n_tr + (j1 - j0) > traj.shape[0]:
        need = j1 - j0
        j1 = j0 + (traj.shape[0] - n_tr)
        full = ST_NEED_TRAJ
    if n_sb + (k1 - k0) > strobe.shape[0]:
        if full == 0:
            need = k1 - k0
            full = ST_NEED_STROBE
        k1 = k0 + (strobe.shape[0] - n_sb)
    if flg[F_TRAJ]:
        dt = prm[P_DT]
        t0 = prm[P_T0]
        for j in range(j0, j1):
            tj = t0 + j * dt
            tau = tj - t_a
            u, v, om = _seg_state(kind, u0, v0, om0, sig, w, r, psi, th_a, tau)
            traj[n_tr, 0] = tj
            traj[n_tr, 1] = u
            traj[n_tr, 2] = v
            traj[n_tr, 3] = sin(th_a + w * tau)
            traj[n_tr, 4] = om
            n_tr += 1
        ist[I_JTRAJ] = j1
    if flg[F_STROBE]:
        for k in range(k0, k1):
            tau = ((k - n_a) * TWO_PI - th_a) / w
            u, v, om = _seg_state(kind, u0, v0, om0, sig, w, r, psi, th_a, tau)
            strobe[n_sb, 0] = k
            strobe[n_sb, 1] = k * TWO_PI / w
            strobe[n_sb, 2] = u
            strobe[n_sb, 3] = v
            strobe[n_sb, 4] = om
            n_sb += 1
        ist[I_KSTROBE] = k1
    if full != 0:
        info[0] = full
        info[4] = need
        info[5] = n_tr
        info[6] = n_sb
        return -1, -1
    return n_tr, n_sb


@njit(cache=True, inline="always")
def _omega_integral(kind, om0, sig, w, r, psi, th0, tau):
    """``∫_0^τ Ω dτ'`` over the first ``τ`` of a segment (closed forms; see :func:`_seg_state`)."""
    if kind == SEG_SLIP:
        return slip_omega_integral(om0, sig, w, th0, tau)
    if kind == SEG_STICK:
        return stick_omega_integral(w, r, psi, th0, tau)
    return om0 * tau


@njit(cache=True)
def _accumulate_omega(st, prm, kind, n_a, th_a, length, om0, sig):
    """Add ``∫Ω dt`` over the part of a segment after ``prm[P_TSTAT]`` to ``st[S_IOM]``."""
    w = prm[P_W]
    tau0 = prm[P_TSTAT] - (n_a * TWO_PI + th_a) / w
    if tau0 >= length:
        return
    r = prm[P_R]
    psi = prm[P_PSI]
    total = _omega_integral(kind, om0, sig, w, r, psi, th_a, length)
    if tau0 > 0.0:
        total -= _omega_integral(kind, om0, sig, w, r, psi, th_a, tau0)
    st[S_IOM] += total


@njit(cache=True, inline="always")
def _report(info, n_ev, n_tr, n_sb):
    """Record how many rows of each buffer this call wrote."""
    info[1] = n_ev
    info[2] = n_tr
    info[3] = n_sb


@njit(cache=True)
def _finish(ist, info, status, n_ev, n_tr, n_sb):
    if ist[I_MODE] != MODE_DONE:
        ist[I_LASTMODE] = ist[I_MODE]
    ist[I_MODE] = MODE_DONE
    ist[I_STATUS] = status
    info[0] = status
    _report(info, n_ev, n_tr, n_sb)


@njit(cache=True, nogil=True)
def run_chunk(prm, flg, st, ist, ev, evk, traj, strobe, info):
    """Advance the simulation; see the module docstring.

    Parameters
    ----------
    prm, flg : ndarray
        Parameters and effect flags (layouts ``P_*`` and ``F_*``).
    st, ist : ndarray
        Float and integer state (``S_*``, ``I_*``), updated in place.
    ev, evk : ndarray
        Event buffer ``(cap, 6)`` — t, phase, v_rel, omega_after, u, omega_before — and kinds ``(cap,)``.
    traj, strobe : ndarray
        Sample buffers ``(cap, 5)``.
    info : ndarray
        Output: status, events, trajectory rows and stroboscopic rows written, rows needed.
    """
    e = prm[P_E]
    w = prm[P_W]
    r = prm[P_R]
    psi = prm[P_PSI]
    tol = prm[P_TOL]
    inertia = prm[P_INERTIA]
    rho = prm[P_RHO]
    t_end = prm[P_TEND]
    contact = flg[F_CONTACT] != 0
    torsion = flg[F_TORSION] != 0
    cap = flg[F_CAP] != 0
    max_ev = flg[F_MAXEV]
    clipped = flg[F_CLIPPED] != 0
    noise = flg[F_NOISE] != 0
    e_sigma = prm[P_ESIG]
    noise_key = member_key(flg[F_SEED], flg[F_MEMBER])
    stats = flg[F_STATS] != 0
    xtol = tol
    per = TWO_PI / w
    w_eps = GRAZE_GAP * (1.0 + w)
    never_sep = w <= 1.0
    th_sep = -1.0
    t_win = 0.0
    g_win = 0.0
    v_win = 0.0
    if not never_sep:
        t_win, g_win, v_win = separation_window(w)
        if g_win < GRAZE_GAP:
            never_sep = True
        else:
            th_sep = separation_phase(w)
    n_ev = 0
    n_tr = 0
    n_sb = 0
    info[4] = 0
    if ist[I_MODE] == MODE_DONE:
        _finish(ist, info, ist[I_STATUS], n_ev, n_tr, n_sb)
        return
    while True:
        if ist[I_NEV] >= max_ev:
            _finish(ist, info, ST_EVENTS, n_ev, n_tr, n_sb)
            return
        if n_ev >= ev.shape[0]:
            info[0] = ST_CHUNK
            _report(info, n_ev, n_tr, n_sb)
            return
        n = ist[I_N]
        th = st[S_TH]
        t_now = (n * TWO_PI + th) / w
        if ist[I_MODE] == MODE_FLIGHT:
            u0 = st[S_U]
            v0 = st[S_V]
            om = st[S_OM]
            tau, dk, ph, v_minus = flight_next_impact(u0, v0, th, st[S_TA], st[S_GA], w, xtol)
            if tau < 0.0:
                _finish(ist, info, ST_NUMERICAL, n_ev, n_tr, n_sb)
                return
            n_hit = n + dk
            t_hit = (n_hit * TWO_PI + ph) / w
            ends = t_hit > t_end  # the run's end comes before the impact
            length = t_end - t_now if ends else tau
            a, b = _sample(
                SEG_FLIGHT,
                n,
                th,
                length,
                ends,
                u0,
                v0,
                om,
                0.0,
                prm,
                flg,
                ist,
                traj,
                n_tr,
                strobe,
                n_sb,
                info,
            )
            if a < 0:
                _report(info, n_ev, n_tr, n_sb)
                return
            n_tr = a
            n_sb = b
            if stats:
                _accumulate_omega(st, prm, SEG_FLIGHT, n, th, length, om, 0.0)
            if ends:
                st[S_U] = u0 + v0 * length - 0.5 * length * length
                st[S_V] = v0 - length
                ist[I_N], st[S_TH] = _advance(n, th, w * length)
                _finish(ist, info, ST_TIME, n_ev, n_tr, n_sb)
                return
            e_k = noisy_restitution(e, e_sigma, noise_key, ist[I_NEV]) if noise else e
            v_rel, v_plus, om_plus = impact_law(
                e_k, w, r, psi, ph, v_minus, om, torsion, cap, inertia
            )
            ev[n_ev, 0] = t_hit
            ev[n_ev, 1] = ph
            ev[n_ev, 2] = v_rel
            ev[n_ev, 3] = om_plus
            ev[n_ev, 4] = sin(ph)
            ev[n_ev, 5] = om
            evk[n_ev] = KIND_IMPACT
            n_ev += 1
            ist[I_NEV] += 1
            ist[I_N] = n_hit
            st[S_TH] = ph
            st[S_OM] = om_plus
            n_load = 1.0 - w * w * sin(ph)
            w_rel = e_k * v_rel
            go_contact = False
            t_acc = -1.0
            if n_load >= 0.0:
                if w_rel <= w_eps:
                    go_contact = True
                else:
                    t_acc = chatter_time(e, w, ph, w_rel, tol)
                    if t_acc > 0.0:
                        go_contact = True
            if go_contact:
                if not contact:
                    _finish(ist, info, ST_NEED_CONTACT, n_ev, n_tr, n_sb)
                    return
                ist[I_MODE] = MODE_CONTACT
                ist[I_GUARD] = 0
                ist[I_ZERO] = 0
                if t_acc > 0.0:
                    ist[I_CHAT] = 1
                    ist[I_NC], st[S_THC] = _advance(n_hit, ph, w * t_acc)
                else:
                    ist[I_CHAT] = 0
                ist[I_SIG] = 0
                if torsion:
                    _enter_contact_torsion(st, ist, r, w, psi, rho, ph)
            else:
                ist[I_MODE] = MODE_FLIGHT
                st[S_U] = sin(ph)
                st[S_V] = v_plus
                st[S_TA] = 0.0
                st[S_GA] = 0.0
            continue

        # ---------------------------------------------------------------- contact
        om = st[S_OM]
        sig = ist[I_SIG]
        if ist[I_FREE]:
            # clipped spring-contact model: N is clipped to 0 while 1 + a_s < 0; no torque, the
            # rotor keeps its angular velocity and rides the stator to the window's end
            th_back = pi - th_sep
            d = th_back - th
            if d < 0.0:
                d += TWO_PI
            seg = min(d / w, t_end - t_now)
            a, b = _sample(
                SEG_CONTACT,
                n,
                th,
                seg,
                seg < d / w,
                0.0,
                0.0,
                om,
                0.0,
                prm,
                flg,
                ist,
                traj,
                n_tr,
                strobe,
                n_sb,
                info,
            )
            if a < 0:
                _report(info, n_ev, n_tr, n_sb)
                return
            n_tr = a
            n_sb = b
            if stats:
                _accumulate_omega(st, prm, SEG_CONTACT, n, th, seg, om, 0.0)
            if seg < d / w:
                ist[I_N], st[S_TH] = _advance(n, th, w * seg)
                st[S_U] = sin(st[S_TH])
                st[S_V] = w * cos(st[S_TH])
                _finish(ist, info, ST_TIME, n_ev, n_tr, n_sb)
                return
            ist[I_N] = n + (1 if th > th_back else 0)
            st[S_TH] = th_back
            ist[I_FREE] = 0
            if torsion:
                _enter_contact_torsion(st, ist, r, w, psi, rho, th_back)
            continue
        if never_sep:
            tau_sep = inf
        else:
            d = th_sep - th
            if d < 0.0:
                if th < pi - th_sep:
                    d = 0.0  # N < 0 by rounding: separate now
                else:
                    d += TWO_PI
            tau_sep = d / w
        tau_t = t_end - t_now
        tau_c = inf
        if ist[I_CHAT]:
            tau_c = ((ist[I_NC] - n) * TWO_PI + (st[S_THC] - th)) / w
            if tau_c < 0.0:
                tau_c = 0.0
        tau_end = min(tau_sep, tau_t, tau_c)
        if tau_end == inf or (clipped and t_end == inf):
            _finish(ist, info, ST_REST, n_ev, n_tr, n_sb)
            return
        seg = tau_end
        kind = SEG_CONTACT
        new_sig = sig
        new_guard = 0
        hit_event = False
        if torsion:
            if sig != 0:
                kind = SEG_SLIP
                if ist[I_GUARD]:
                    # leaving s = 0: the slip grows until RN + σα_s returns to >= 0
                    s0 = sin(th + psi)
                    q0 = -r * (1.0 - w * w * sin(th)) + sig * w * w * s0
                    if q0 < 0.0:
                        q0 = 0.0
                    tq = first_root(
                        q0,
                        0.0,
                        0.0,
                        sig * w * w * sin(psi),
                        r * w * w + sig * w * w * cos(psi),
                        th,
                        w,
                        tau_end,
                        xtol,
                    )
                    if tq >= 0.0:
                        seg = tq
                else:
                    f0 = sig * (r * om - w * cos(th + psi))
                    if f0 < 0.0:
                        f0 = 0.0
                    tz = first_root(
                        f0,
                        -r,
                        0.0,
                        -r * w - sig * w * cos(psi),
                        sig * w * sin(psi),
                        th,
                        w,
                        tau_end,
                        xtol,
                    )
                    if tz >= 0.0:
                        seg = tz
                        hit_event = True
            else:
                kind = SEG_STICK
                win = tau_end
                if win > per:
                    win = per
                rr = rho * r
                best = -1.0
                for sgn in (1.0, -1.0):
                    m0 = rr * (1.0 - w * w * sin(th)) - sgn * w * w * sin(th + psi)
                    if m0 < 0.0:
                        m0 = 0.0
                    rt = first_root(
                        m0,
                        0.0,
                        0.0,
                        -sgn * w * w * sin(psi),
                        -rr * w * w - sgn * w * w * cos(psi),
                        th,
                        w,
                        win,
                        xtol,
                    )
                    if rt >= 0.0 and (best < 0.0 or rt < best):
                        best = rt
                        new_sig = np.int64(sgn)
                if best >= 0.0:
                    seg = best
                    new_guard = 1
                    hit_event = True
                else:
                    new_sig = 0
        if seg <= 0.0:
            ist[I_ZERO] += 1
            if ist[I_ZERO] > 32:
                _finish(ist, info, ST_NUMERICAL, n_ev, n_tr, n_sb)
                return
        else:
            ist[I_ZERO] = 0
        at_end = (not hit_event) and seg == tau_end
        inclusive = at_end and tau_end == tau_t
        a, b = _sample(
            kind,
            n,
            th,
            seg,
            inclusive,
            0.0,
            0.0,
            om,
            float(sig),
            prm,
            flg,
            ist,
            traj,
            n_tr,
            strobe,
            n_sb,
            info,
        )
        if a < 0:
            _report(info, n_ev, n_tr, n_sb)
            return
        n_tr = a
        n_sb = b
        if stats:
            _accumulate_omega(st, prm, kind, n, th, seg, om, float(sig))
        # advance the state to the end of the segment
        if at_end and tau_end == tau_sep and tau_sep < tau_t and tau_sep <= tau_c:
            n1 = n + (1 if th > th_sep else 0)
            th1 = th_sep
        elif at_end and tau_end == tau_c and tau_c < tau_t:
            n1 = ist[I_NC]
            th1 = st[S_THC]
        else:
            n1, th1 = _advance(n, th, w * seg)
        if kind == SEG_SLIP:
            om1 = slip_omega(om, float(sig), w, th, seg)
        elif kind == SEG_STICK:
            om1 = w * cos(th1 + psi) / r
        else:
            om1 = om
        ist[I_N] = n1
        st[S_TH] = th1
        st[S_OM] = om1
        if torsion:
            if kind == SEG_SLIP:
                if ist[I_GUARD]:
                    ist[I_GUARD] = 0
                elif hit_event:
                    # the slip reached zero: stick, or slip on in the stator's direction (§2.5)
                    st[S_OM] = w * cos(th1 + psi) / r
                    _enter_contact_torsion(st, ist, r, w, psi, rho, th1)
            elif hit_event:
                ist[I_SIG] = new_sig
                ist[I_GUARD] = new_guard
        if at_end:
            if tau_end == tau_t:
                if kind == SEG_CONTACT or kind == SEG_SLIP or kind == SEG_STICK:
                    st[S_U] = sin(th1)
                    st[S_V] = w * cos(th1)
                _finish(ist, info, ST_TIME, n_ev, n_tr, n_sb)
                return
            if tau_end == tau_c and ist[I_CHAT]:
                ist[I_CHAT] = 0
                ev[n_ev, 0] = (n1 * TWO_PI + th1) / w
                ev[n_ev, 1] = th1
                ev[n_ev, 2] = 0.0
                ev[n_ev, 3] = st[S_OM]
                ev[n_ev, 4] = sin(th1)
                ev[n_ev, 5] = st[S_OM]
                evk[n_ev] = KIND_CHATTER
                n_ev += 1
                ist[I_NEV] += 1
                if tau_c < tau_sep:
                    continue
            if tau_end == tau_sep and clipped:
                ist[I_FREE] = 1
                continue
            if tau_end == tau_sep:
                # separation: fly through the window where N < 0, then search from its end
                ist[I_MODE] = MODE_FLIGHT
                st[S_U] = 1.0 / (w * w)
                st[S_V] = w * cos(th_sep)
                st[S_TA] = t_win
                st[S_GA] = g_win
                ist[I_CHAT] = 0


@njit(cache=True, inline="always")
def _slip_is_zero(r, w, psi, omega, phase):
    """``s = RΩ − Ω_s`` is zero to rounding."""
    return abs(r * omega - w * cos(phase + psi)) <= 1e-14 * (abs(r * omega) + w)


@njit(cache=True)
def _contact_sigma(r, w, psi, rho, omega, phase):
    """Slip direction in contact: ``sgn(s)``, or at ``s = 0`` stick (0) when ``|α_s| <= ρRN``,
    else the direction set by the stator's acceleration (paper §2.5, corrected)."""
    if not _slip_is_zero(r, w, psi, omega, phase):
        return 1 if r * omega - w * cos(phase + psi) > 0.0 else -1
    n_load = 1.0 - w * w * sin(phase)
    alpha = -w * w * sin(phase + psi)
    if abs(alpha) <= rho * r * n_load:
        return 0
    return 1 if alpha < 0.0 else -1


@njit(cache=True)
def _enter_contact_torsion(st, ist, r, w, psi, rho, phase):
    """Torsional state on entering contact at ``phase`` with the rotor's current ``Ω``.

    Sets the slip direction (:func:`_contact_sigma`); when the rotor leaves ``s = 0`` the guard,
    so the slip search starts once the slip has grown (module ``run_chunk``); when it sticks,
    ``RΩ = Ω_s`` exactly.
    """
    om = st[S_OM]
    sig = _contact_sigma(r, w, psi, rho, om, phase)
    ist[I_SIG] = sig
    ist[I_GUARD] = 1 if sig != 0 and _slip_is_zero(r, w, psi, om, phase) else 0
    if sig == 0:
        st[S_OM] = w * cos(phase + psi) / r
