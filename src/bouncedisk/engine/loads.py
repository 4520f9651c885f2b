"""One axial trajectory, several load torques: ``∫Ω dt`` of every load from one impact search.

The rotor's axial motion never depends on its rotation (docs/model.md "Events": the restitution law
and the normal load involve ``u``, ``v`` and the stator only; the load torque acts on ``Ω`` alone,
"The motor under load"), and a member's restitution noise is a pure function of its stream and
the event count (:mod:`.noise`). So runs of one member that differ only in ``τ_L`` share every
flight, impact, chattering tail and separation; they differ in ``Ω`` and in where contact
sticks and slips. :func:`run_loads` advances them together: each flight's first root
(:func:`~.kernel._flight_search`, most of an impact's cost) and its restitution are computed
once and handed to every load's :func:`~.kernel._flight_land`; in contact each load takes its own
segments (:func:`~.kernel._contact_step`) to the contact's end, which is the same for all.

Every load's state is the kernel's own (one row of ``st``, ``ist``, ``prm`` per load), updated by
the kernel's own functions with the same arguments as a run with that load alone, so each row's
``∫Ω dt`` is **bit-identical** to :func:`~.driver.iterate`'s (``tests/test_engine_loads.py``).
Should the rows' axial states ever part (they cannot, short of a kernel change that lets ``Ω``
feed back into the axial motion), the run stops with :data:`ST_APART` and
:func:`omega_integrals` runs the loads one by one instead.
"""

from dataclasses import replace

import numpy as np
from numba import njit

from . import _cache  # noqa: F401  (the cache locators, before anything here is decorated)
from . import kernel as K
from .driver import (
    STATUS_TEXT,
    EngineConfig,
    EngineError,
    InitialState,
    Returning,
    _pack,
    initial_state,
    iterate,
)
from .noise import member_key, noisy_restitution
from .roots import inflections

#: Status of :func:`run_loads` when the rows' axial states differ (see the module docstring).
ST_APART = 100


@njit(cache=True, inline="always")
def _same_axial(st, ist, l):
    """Row ``l`` is at row 0's axial state (mode, events, period, phase, flight origin)."""
    return (
        ist[l, K.I_MODE] == ist[0, K.I_MODE]
        and ist[l, K.I_EVENTS] == ist[0, K.I_EVENTS]
        and ist[l, K.I_PERIOD] == ist[0, K.I_PERIOD]
        and st[l, K.S_PHASE] == st[0, K.S_PHASE]
        and st[l, K.S_U] == st[0, K.S_U]
        and st[l, K.S_V] == st[0, K.S_V]
    )


# numba's reference counting off, as the kernel's steps (kernel._on_arrays): these allocate
# nothing, and the atomic count of every array argument of every call (the event buffer is six)
# made omega_integrals 1.7x as slow (4.1 against 2.4 ms for 16 loads, 2026-11-25)
@njit(cache=True, **K._nrt_off())
def _contact_to_end(prm, flg, st, ist, ev, evk, traj, strobe, info, sep):
    """Contact segments of one load's row until the contact ends (flight) or the run does.

    The kernel's :func:`~.kernel.run_chunk` loop restricted to contact; the event buffer is
    reused (only ``∫Ω dt`` is kept). Returns ``ST_CONTINUE`` or the status that ended the run.
    """
    w = prm[K.P_W]
    while ist[K.I_MODE] == K.MODE_CONTACT:
        if ist[K.I_EVENTS] >= flg[K.F_MAXEV]:
            return K._finish(ist, info, K.ST_EVENTS)
        info[K.O_EVENTS] = 0
        n = ist[K.I_PERIOD]
        th = st[K.S_PHASE]
        t_now = (n * K.TWO_PI + th) / w
        status = K._contact_step(prm, flg, st, ist, ev, evk, traj, strobe, info, n, th, t_now, sep)
        if status != K.ST_CONTINUE:
            return status
    return K.ST_CONTINUE


@njit(cache=True, nogil=True, **K._nrt_off())
def run_loads(prm, flg, st, ist, ev, evk, traj, strobe, info):
    """Advance the rows of ``st``, ``ist`` (one per load, parameters ``prm[l]``) to their end.

    Parameters
    ----------
    prm : ndarray, shape (L, N_PRM)
        The kernel's parameter vector of each load (equal but for ``P_LOAD``).
    flg : ndarray
        Effect flags (shared; no trajectory or stroboscopic samples).
    st, ist : ndarray, shape (L, N_ST), (L, N_IST)
        Each load's float and integer state, from the same initial state.
    ev, evk, traj, strobe : tuple of ndarray, ndarray
        Scratch buffers of the kernel's layouts (:func:`~.kernel.run_chunk`; at least one event
        row).
    info : ndarray, shape (L, N_OUT)
        Scratch output counters.

    Returns
    -------
    int
        The run's status (``ST_TIME``, ``ST_EVENTS``, ``ST_REST`` …, or :data:`ST_APART`).
    """
    n_loads = prm.shape[0]
    w = prm[0, K.P_W]
    xtol = prm[0, K.P_TOL]
    e = prm[0, K.P_E]
    noise_key = member_key(flg[K.F_SEED], flg[K.F_MEMBER])
    sep = K._separation_constants(w)
    infl = inflections(0.0, -1.0, -0.5, w)
    while True:
        if ist[0, K.I_MODE] == K.MODE_DONE:
            return ist[0, K.I_STATUS]
        for l in range(1, n_loads):
            if not _same_axial(st, ist, l):
                return ST_APART
        if ist[0, K.I_MODE] == K.MODE_CONTACT:
            for l in range(n_loads):
                _contact_to_end(prm[l], flg, st[l], ist[l], ev, evk, traj, strobe, info[l], sep)
            continue
        if ist[0, K.I_EVENTS] >= flg[K.F_MAXEV]:
            for l in range(n_loads):
                K._finish(ist[l], info[l], K.ST_EVENTS)
            continue
        n = ist[0, K.I_PERIOD]
        th = st[0, K.S_PHASE]
        t_now = (n * K.TWO_PI + th) / w
        tau, dk, ph, v_minus = K._flight_search(st[0], th, w, xtol, infl)
        if tau < 0.0:
            for l in range(n_loads):
                K._finish(ist[l], info[l], K.ST_NUMERICAL)
            continue
        e_k = (
            noisy_restitution(e, prm[0, K.P_ESIG], noise_key, ist[0, K.I_EVENTS])
            if flg[K.F_NOISE]
            else e
        )
        hit = (tau, dk, ph, v_minus, e_k)
        for l in range(n_loads):
            info[l, K.O_EVENTS] = 0
            K._flight_land(
                prm[l], flg, st[l], ist[l], ev, evk, traj, strobe, info[l], n, th, t_now, hit
            )
    return K.ST_NUMERICAL  # unreachable


def _check_config(cfg: EngineConfig) -> None:
    """The settings :func:`omega_integrals` supports: ``∫Ω dt`` only, the loads' model."""
    if cfg.traj_dt > 0.0 or cfg.stroboscopic:
        raise ValueError("omega_integrals keeps no samples: set traj_dt = 0, stroboscopic = False")
    if cfg.clipped:
        raise ValueError("omega_integrals runs the rigid contact model, not the clipped one")
    if not np.isfinite(cfg.stats_from) or not np.isfinite(cfg.t_end):
        raise ValueError("omega_integrals needs a finite window: stats_from and t_end")


def omega_integrals(
    cfg: EngineConfig,
    loads: np.ndarray,
    init: InitialState | None = None,
    reached_only: bool = False,
) -> np.ndarray:
    """``∫Ω dt`` over ``[cfg.stats_from, cfg.t_end]`` of one member under each load torque.

    Equal, bit for bit, to running ``cfg`` with ``load_torque = loads[l]`` through
    :func:`~.driver.iterate` for every ``l`` (module docstring), at about the cost of one run
    plus the rotation of the others.

    Parameters
    ----------
    cfg : EngineConfig
        The member's configuration (its ``load_torque`` is ignored); finite ``stats_from``
        and ``t_end``, no samples, not clipped.
    loads : array_like of float
        Nondimensional load torques ``τ_L`` (docs/model.md "The motor under load").
    init : InitialState, optional
        The common initial state (default: the kernel's default).
    reached_only : bool
        NaN for a load whose run ended before ``t_end`` (the event budget ``max_events``): its
        integral covers part of the window only (default: that partial integral, as
        :func:`~.driver.iterate` returns it).

    Returns
    -------
    ndarray
        ``∫Ω dt`` of each load.

    Raises
    ------
    EngineError
        When a run fails (a missing effect, a failed event search), as :func:`~.driver.iterate`.
    """
    _check_config(cfg)
    loads = np.asarray(loads, dtype=float)
    init = init or InitialState()
    cfgs = [replace(cfg, load_torque=float(x)) for x in loads]
    _, flg = _pack(cfg)
    prm = np.array([_pack(c)[0] for c in cfgs])
    # each load's own initial state: in contact, the stick–slip state depends on τ_L
    states = [initial_state(c, init) for c in cfgs]
    st = np.array([s for s, _ in states])
    ist = np.array([i for _, i in states])
    rows = len(loads)
    ev = tuple(np.empty((K.EV_COLS, 1)))  # the kernel's event columns, one row
    evk = np.empty(1, dtype=np.int8)
    traj = np.empty((0, K.TRAJ_COLS))
    strobe = np.empty((0, K.STROBE_COLS))
    info = np.zeros((rows, K.N_OUT), dtype=np.int64)
    status = run_loads(prm, flg, st, ist, ev, evk, traj, strobe, info)
    if status == ST_APART:  # pragma: no cover - see the module docstring
        return np.array([_one_load(cfg, x, init) for x in loads])
    if status in (K.ST_NEED_CONTACT, K.ST_NUMERICAL):
        raise EngineError(f"{STATUS_TEXT[status]} (after {ist[0, K.I_EVENTS]} events)", status)
    out = st[:, K.S_OMEGA_INTEGRAL].copy()
    if reached_only:
        out[ist[:, K.I_STATUS] != K.ST_TIME] = np.nan
    return out


def _one_load(cfg: EngineConfig, load: float, init: InitialState) -> float:
    """``∫Ω dt`` of one run under ``load`` (:func:`~.driver.iterate`)."""
    gen = Returning(iterate(replace(cfg, load_torque=float(load)), init))
    for _ in gen:
        pass
    return gen.value[1]["omega_integral"]
