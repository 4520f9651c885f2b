"""One axial trajectory, several rotations: ``∫Ω dt`` of every load, or samples, from one search.

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
The same holds for runs that differ in ``R_φ`` and ``ψ`` (:data:`ROTATION_FIELDS`): the fit's
points at one ``(e, omega_s)`` take their samples from one axial run (:func:`row_trajectories`).
Should the rows' axial states ever part (they cannot, short of a kernel change that lets ``Ω``
feed back into the axial motion), the run stops with :data:`ST_APART` and
:func:`omega_integrals` runs the loads one by one instead.
"""

import math
from collections.abc import Sequence
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
    simulate_arrays,
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
# nothing, and an atomic count of every array argument of every call (the event buffer is six)
# would dominate the cost of a short contact segment
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
    """Advance the rows of ``st``, ``ist`` (parameters ``prm[l]``) to their end.

    Parameters
    ----------
    prm : ndarray, shape (L, N_PRM)
        The kernel's parameter vector of each row: equal in everything the axial motion uses,
        free in ``P_LOAD``, ``P_R`` and ``P_PSI`` (the rotation's).
    flg : ndarray
        Effect flags (shared; no stroboscopic samples).
    st, ist : ndarray, shape (L, N_ST), (L, N_IST)
        Each row's float and integer state, from the same initial state.
    ev, evk, strobe : tuple of ndarray, ndarray
        Scratch buffers of the kernel's layouts (:func:`~.kernel.run_chunk`; at least one event
        row).
    traj : ndarray, shape (L, cap, TRAJ_COLS)
        Each row's trajectory samples (``cap`` 0 without samples; with them, room for every
        sample of the run: a full buffer is not resumed here).
    info : ndarray, shape (L, N_OUT)
        Output counters of each row (``O_TRAJ``: its samples written).

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
                _contact_to_end(prm[l], flg, st[l], ist[l], ev, evk, traj[l], strobe, info[l], sep)
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
                prm[l], flg, st[l], ist[l], ev, evk, traj[l], strobe, info[l], n, th, t_now, hit
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
    status, st, ist, _traj, _info = _run_rows(cfgs, init, 0)
    if status == ST_APART:  # pragma: no cover - see the module docstring
        return np.array([_one_load(cfg, x, init) for x in loads])
    if status in (K.ST_NEED_CONTACT, K.ST_NUMERICAL):
        raise EngineError(f"{STATUS_TEXT[status]} (after {ist[0, K.I_EVENTS]} events)", status)
    out = st[:, K.S_OMEGA_INTEGRAL].copy()
    if reached_only:
        out[ist[:, K.I_STATUS] != K.ST_TIME] = np.nan
    return out


def _run_rows(cfgs: Sequence[EngineConfig], init: InitialState, samples: int) -> tuple:
    """:func:`run_loads` on one row per configuration of ``cfgs``, all from ``init``, with room
    for ``samples`` trajectory samples a row; returns ``(status, st, ist, traj, info)``.

    Each row starts from its own initial state: in contact the stick–slip state depends on the
    rotation's parameters (``τ_L``, ``R_φ``, ``ψ``).
    """
    _, flg = _pack(cfgs[0])
    prm = np.array([_pack(c)[0] for c in cfgs])
    states = [initial_state(c, init) for c in cfgs]
    st = np.array([s for s, _ in states])
    ist = np.array([i for _, i in states])
    traj = np.empty((len(cfgs), samples, K.TRAJ_COLS))
    info = np.zeros((len(cfgs), K.N_OUT), dtype=np.int64)
    ev = tuple(np.empty((K.EV_COLS, 1)))  # the kernel's event columns, one row
    evk = np.empty(1, dtype=np.int8)
    status = run_loads(prm, flg, st, ist, ev, evk, traj, np.empty((0, K.STROBE_COLS)), info)
    return status, st, ist, traj, info


#: Fields of :class:`~.driver.EngineConfig` the axial motion does not use (docs/model.md
#: "Events", "The motor under load"): the rows of one :func:`run_loads` may differ in these only.
ROTATION_FIELDS = {"load_torque": 0.0, "r_phi": 1.0, "psi": 0.0}


def _check_rows(cfgs: Sequence[EngineConfig]) -> None:
    """The runs :func:`row_trajectories` supports: one axial motion, samples on a finite grid."""
    base = replace(cfgs[0], **ROTATION_FIELDS)
    if any(replace(c, **ROTATION_FIELDS) != base for c in cfgs[1:]):
        raise ValueError("rows must differ only in " + ", ".join(ROTATION_FIELDS))
    if base.traj_dt <= 0.0 or not math.isfinite(min(base.traj_t1, base.t_end)):
        raise ValueError("row_trajectories samples a finite grid: set traj_dt and traj_t1")
    if base.stroboscopic or base.clipped:
        raise ValueError("row_trajectories keeps no stroboscopic samples and runs the rigid model")


def row_trajectories(
    cfgs: Sequence[EngineConfig], init: InitialState | None = None
) -> list[np.ndarray]:
    """Trajectory samples of runs that share their axial motion, from one impact search.

    The runs may differ in the load torque, ``R_φ`` and ``ψ`` (:data:`ROTATION_FIELDS`): none
    of them feeds back into the axial motion (module docstring), so one flight search serves
    every row, as it serves every load in :func:`omega_integrals`.

    Parameters
    ----------
    cfgs : sequence of EngineConfig
        The runs; equal but for :data:`ROTATION_FIELDS`, with samples on a finite grid.
    init : InitialState, optional
        The common initial state (default: the kernel's default).

    Returns
    -------
    list of ndarray
        Each run's samples ``(n, TRAJ_COLS)``: bit for bit :func:`~.driver.simulate_arrays`'s
        ``traj`` of that configuration alone (``tests/test_engine_loads.py``).
    """
    _check_rows(cfgs)
    cfg, init = cfgs[0], init or InitialState()
    last = math.floor((min(cfg.traj_t1, cfg.t_end) - cfg.traj_t0) / cfg.traj_dt + 1e-9)
    # room for every sample of the grid (a run starting later writes fewer): never resumed here
    status, _st, _ist, traj, info = _run_rows(cfgs, init, max(0, last + 2))
    if status in (ST_APART, K.ST_NEED_CONTACT, K.ST_NUMERICAL):
        # rows parted, or row 0 failed (in contact its own segments can): each row alone, so
        # that a row fails exactly when its own run does (simulate_arrays raises)
        return [simulate_arrays(c, init).traj for c in cfgs]
    return [traj[k, : info[k, K.O_TRAJ]].copy() for k in range(len(cfgs))]


def _one_load(cfg: EngineConfig, load: float, init: InitialState) -> float:
    """``∫Ω dt`` of one run under ``load`` (:func:`~.driver.iterate`)."""
    gen = Returning(iterate(replace(cfg, load_torque=float(load)), init))
    for _ in gen:
        pass
    return gen.value[1]["omega_integral"]
