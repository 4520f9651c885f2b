"""Python driver of the compiled event loop: set-up, chunked runs, status messages.

The driver is pure numpy: no file I/O and no xarray. :func:`iterate` yields one :class:`Chunk`
per call of the kernel, so callers can stream results to disk, report progress or stop between
chunks; :func:`simulate_arrays` collects a whole run in memory.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Generator, Iterator
from dataclasses import dataclass, field
from typing import Generic, TypeVar

import numpy as np

from . import kernel as K
from .bounds import MAX_SPEED, check_config, check_run, finite
from .errors import InputError
from .layout import OK_STATUSES, STATUS_TEXT

Y = TypeVar("Y")
V = TypeVar("V")


@dataclass(frozen=True)
class EngineConfig:
    """Everything the kernel needs, already validated (see :mod:`bouncedisk.model.scene`).

    Parameters
    ----------
    e, omega_s, r_phi, psi : float
        Nondimensional parameters (docs/model.md), ``omega_s`` within the bounds of
        :mod:`.bounds`. A fast stator launches the rotor at about its own speed ``omega_s``,
        for a flight of about ``2 omega_s``: at ``omega_s = 1e4`` the first impact of the
        default start comes at ``t ≈ 2e4``, and a run stopped before that has no event.
    contact, torsion, impulse_cap : bool
        Effects (docs/model.md "Optional effects").
    inertia_ratio : float
        ``J_s/J_r`` for the ``stator_inertia`` effect; ``inf`` for a stator not moved by
        impacts (eq. 19).
    mu_ratio : float
        ``μ_static/μ_kinetic >= 1`` for the ``kinetic_static`` effect; 1 otherwise.
    tol : float
        Root tolerance of the event searches (and the chattering jump criterion).
    t_end : float
        Time at which the run stops (``inf``: stop on events only).
    max_events : int
        Number of events (impacts plus chattering tails) after which the run stops.
    traj_dt, traj_t0, traj_t1 : float
        Dense trajectory grid ``t0, t0 + dt, …, <= t1``; ``traj_dt = 0`` for none.
    stroboscopic : bool
        Sample the state at every stator period (phase 0).
    clipped : bool
        The earlier clipped-sinusoid spring-contact model (paper refs. [2, 3]) instead of the
        bouncing model: the rotor never leaves the stator and the normal load is
        ``max(0, 1 + a_s)``. Needs a time stop.
    e_sigma : float
        Standard deviation ``σ_e`` of the per-impact restitution (effect ``restitution_noise``,
        docs/model.md "Long-run statistics"); 0 for none. The ``k``-th event draws
        ``e_k = e + σ_e ξ_k`` clipped to ``[0, 1]``, ``ξ_k`` from the counter-based stream
        ``(seed, member)`` (:mod:`bouncedisk.engine.noise`).
    seed, member : int
        The noise stream: ensemble seed and member index (both ``>= 0``).
    stats_from : float
        Accumulate ``∫Ω dt`` and the energy audit from this time on (``final["omega_integral"]``,
        ``final["audit"]``, :func:`audit_balances`); ``inf`` for none.
    load_torque : float
        Constant load torque ``τ_L >= 0`` on the rotor against positive rotation (effect
        ``load``; docs/model.md "The motor under load"), in units of the friction torque at the static
        normal load; 0 for none.
    """

    e: float
    omega_s: float
    r_phi: float = 0.01
    psi: float = 0.0
    contact: bool = True
    torsion: bool = False
    impulse_cap: bool = True
    inertia_ratio: float = math.inf
    mu_ratio: float = 1.0
    tol: float = 1e-12
    t_end: float = math.inf
    max_events: int = 10_000
    traj_dt: float = 0.0
    traj_t0: float = 0.0
    traj_t1: float = math.inf
    stroboscopic: bool = False
    clipped: bool = False
    e_sigma: float = 0.0
    seed: int = 0
    member: int = 0
    stats_from: float = math.inf
    load_torque: float = 0.0

    def __post_init__(self) -> None:
        """Refuse what the kernel cannot run (:func:`.bounds.check_config`): an
        :class:`~.errors.InputError` naming the field."""
        check_config(self)


@dataclass(frozen=True)
class InitialState:
    """Initial condition (docs/model.md "Initial condition").

    ``u is None`` (default) puts the rotor in contact, moving with the stator, at ``t``.
    Otherwise the rotor starts in flight at height ``u >= u_s(t)`` with velocity ``v``.
    """

    t: float = 0.0
    omega: float = 0.0
    u: float | None = None
    v: float | None = None

    def __post_init__(self) -> None:
        """Refuse a value no run can start from (:mod:`.bounds`): ``nan``, an infinity, a
        speed or height beyond :data:`~.bounds.MAX_SPEED`. The bounds that depend on
        ``omega_s`` (the time, the first flight) are checked when a run starts
        (:func:`.bounds.check_run`)."""
        src = "InitialState"
        finite(src, "t", self.t)
        finite(src, "omega", self.omega, MAX_SPEED)
        for name in ("u", "v"):
            if getattr(self, name) is not None:
                finite(src, name, getattr(self, name), MAX_SPEED)


@dataclass
class Chunk:
    """Output of one kernel call. Arrays are views into fresh copies (safe to keep)."""

    t: np.ndarray
    phase: np.ndarray
    v_rel: np.ndarray
    omega_after: np.ndarray
    u: np.ndarray
    omega_before: np.ndarray
    kind: np.ndarray
    traj: np.ndarray  # (rows, 5): t, u, v, u_stator, omega
    strobe: np.ndarray  # (rows, 5): period, t, u, v, omega
    n_events_total: int
    t_now: float


@dataclass
class RunResult:
    """A whole run collected in memory (:func:`simulate_arrays`).

    ``events`` maps ``t``, ``phase``, ``v_rel``, ``omega_after``, ``u``, ``omega_before`` and
    ``kind`` to one array each, one row per event (a simulation file names them ``t_impact``,
    ``phase``, ``v_rel``, ``omega_after``, ``u_impact``, ``omega_before``, ``kind``;
    docs/formats.md "Simulation file"). ``traj`` is the dense trajectory, one row per sample,
    its columns named by :class:`bouncedisk.io.records.TrajColumn` (``t``, ``u``, ``v``,
    ``u_stator``, ``omega``); ``strobe`` the stroboscopic section (``StrobeColumn``). ``status``
    says how the run ended (``status_code`` its code; :attr:`ok`), ``final`` is the final state
    (``t``, ``u``, ``v``, ``omega``, ``in_contact``, ``phase``, ``omega_integral`` and, with a
    statistics window, ``audit``: the energy audit's terms). Nondimensional throughout
    (docs/model.md "Variables and scales").
    """

    events: dict[str, np.ndarray]
    traj: np.ndarray
    strobe: np.ndarray
    status: str
    status_code: int
    final: dict[str, float] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True when the run ended as asked (events or time reached, or the rotor at rest)."""
        return self.status_code in OK_STATUSES


class EngineError(RuntimeError):
    """A run could not continue (missing effect, numerical failure)."""

    def __init__(self, message: str, code: int):
        super().__init__(message)
        self.code = code


def _pack(cfg: EngineConfig) -> tuple[np.ndarray, np.ndarray]:
    prm = np.zeros(K.N_PRM)
    prm[K.P_E] = cfg.e
    prm[K.P_W] = cfg.omega_s
    prm[K.P_R] = cfg.r_phi
    prm[K.P_PSI] = cfg.psi
    prm[K.P_TOL] = cfg.tol
    j = cfg.inertia_ratio
    prm[K.P_INERTIA] = 1.0 if math.isinf(j) else j / (1.0 + j)
    prm[K.P_MU_RATIO] = cfg.mu_ratio
    prm[K.P_TEND] = cfg.t_end
    prm[K.P_DT] = cfg.traj_dt
    prm[K.P_T0] = cfg.traj_t0
    prm[K.P_T1] = min(cfg.traj_t1, cfg.t_end)
    prm[K.P_ESIG] = cfg.e_sigma
    prm[K.P_TSTAT] = cfg.stats_from
    prm[K.P_LOAD] = cfg.load_torque
    flg = np.zeros(K.N_FLG, dtype=np.int64)
    flg[K.F_CONTACT] = int(cfg.contact)
    flg[K.F_TORSION] = int(cfg.torsion)
    flg[K.F_CAP] = int(cfg.impulse_cap)
    flg[K.F_TRAJ] = int(cfg.traj_dt > 0.0)
    flg[K.F_STROBE] = int(cfg.stroboscopic)
    flg[K.F_MAXEV] = int(cfg.max_events)
    flg[K.F_CLIPPED] = int(cfg.clipped)
    flg[K.F_NOISE] = int(cfg.e_sigma > 0.0)
    flg[K.F_SEED] = int(cfg.seed)
    flg[K.F_MEMBER] = int(cfg.member)
    flg[K.F_STATS] = int(math.isfinite(cfg.stats_from))
    # the clipped model's rotor follows the stator where N is clipped to 0: no axial balance
    flg[K.F_AXIAL_AUDIT] = int(math.isfinite(cfg.stats_from) and not cfg.clipped)
    return prm, flg


def initial_state(cfg: EngineConfig, init: InitialState) -> tuple[np.ndarray, np.ndarray]:
    """Kernel state arrays for an initial condition (validated by the caller)."""
    w = cfg.omega_s
    st = np.zeros(K.N_ST)
    ist = np.zeros(K.N_IST, dtype=np.int64)
    x = w * init.t
    n0 = math.floor(x / K.TWO_PI)
    th0 = x - n0 * K.TWO_PI
    if th0 >= K.TWO_PI:
        th0 -= K.TWO_PI
        n0 += 1
    ist[K.I_PERIOD] = n0
    st[K.S_PHASE] = th0
    st[K.S_OMEGA] = init.omega
    us, vs = math.sin(th0), w * math.cos(th0)
    load = 1.0 - w * w * us
    in_contact = init.u is None or (init.u <= us and init.v == vs)
    if in_contact and load >= 0.0 and cfg.contact:
        ist[K.I_MODE] = K.MODE_CONTACT
        if cfg.torsion:
            K._enter_contact_torsion(st, ist, _pack(cfg)[0], th0)
    else:
        ist[K.I_MODE] = K.MODE_FLIGHT
        u = us if init.u is None else max(init.u, us)
        v = vs if init.v is None else init.v
        st[K.S_U] = u
        st[K.S_V] = v
        st[K.S_ANCHOR_TAU] = 0.0
        st[K.S_ANCHOR_GAP] = u - us
    if cfg.traj_dt > 0.0:
        ist[K.I_NEXT_SAMPLE] = max(0, math.ceil((init.t - cfg.traj_t0) / cfg.traj_dt - 1e-9))
    ist[K.I_NEXT_STROBE] = n0 if th0 == 0.0 else n0 + 1
    return st, ist


@dataclass
class ChunkView:
    """One kernel call's output as views into the run's buffers, valid until the next call:
    event rows ``ev`` (columns ``EV_*`` of :mod:`.kernel`), their kinds, samples."""

    ev: np.ndarray
    evk: np.ndarray
    traj: np.ndarray
    strobe: np.ndarray
    n_events_total: int
    t_now: float


class Returning(Generic[Y, V]):
    """A generator to iterate with a ``for`` loop, keeping its return value.

    ``for c in (gen := Returning(iterate(cfg))): ...`` then ``gen.value``: the generator's
    return value (``StopIteration.value``, here ``(status_code, final_state)``) once the loop has
    run to the end; ``None`` before.
    """

    def __init__(self, gen: Generator[Y, object, V]):
        self._gen = gen
        self.value: V | None = None

    def __iter__(self) -> Iterator[Y]:
        self.value = yield from self._gen


#: Stator periods of one kernel call in a run that may go on without events
#: (:func:`_may_run_without_events`): a few milliseconds to some tens of milliseconds.
_SLICE_PERIODS = 1 << 12


def _may_run_without_events(cfg: EngineConfig) -> bool:
    """Whether the rotor may ride the stator until a finite ``t_end`` without an event: the
    clipped model (it has none), or contact that never ends (``omega_s <= 1``, or a separation
    window too shallow to fly, :func:`~.kernel._separation_constants`). Every other run has an
    event at least every stator period or flight, and each kernel call ends after a bounded
    number of events; such a run would be one call to its end, deaf to SIGINT and SIGTERM
    (Python runs signal handlers between calls only), so :func:`_kernel_calls` ends its calls every :data:`_SLICE_PERIODS`
    periods through the stroboscopic buffer, which the kernel resumes exactly where it stopped.
    """
    if math.isinf(cfg.t_end):
        return False
    return cfg.clipped or (cfg.contact and bool(K._separation_constants(cfg.omega_s)[0]))


def _kernel_calls(
    cfg: EngineConfig,
    init: InitialState,
    event_buffers: Callable[[], tuple[tuple[np.ndarray, ...], np.ndarray]],
    chunk_samples: int,
) -> Iterator[tuple[int, np.ndarray, np.ndarray, int, float]]:
    """Call the kernel until the run ends, each call writing its events to ``event_buffers()``.

    ``event_buffers()`` gives the event columns (``EV_COLS`` arrays, indices ``EV_*``) and the
    kinds of one call, all of one length (:func:`~.kernel.run_chunk`); it is called again before
    every call, so the buffers of the last call may be reallocated then. Yields
    ``(events, traj, strobe, n_events_total, t_now)`` after each call that wrote anything: the
    number of event rows written and views of the sample rows. The generator's return value is
    ``(status_code, final_state)``. ``init`` is checked against ``cfg`` first
    (:func:`.bounds.check_run`). A run that may go on without events ends its calls every
    :data:`_SLICE_PERIODS` stator periods (:func:`_may_run_without_events`), so that the caller
    regains control (an interrupt, a progress report) whatever the run does.

    Raises
    ------
    InputError
        When ``init`` is out of the bounds of :mod:`.bounds` under ``cfg``.
    """
    check_run(cfg, init)
    prm, flg = _pack(cfg)
    st, ist = initial_state(cfg, init)
    traj = np.empty((chunk_samples if cfg.traj_dt > 0 else 0, K.TRAJ_COLS))
    sliced = not cfg.stroboscopic and _may_run_without_events(cfg)
    if sliced:  # stroboscopic samples nobody asked for, to end a call every few periods
        flg[K.F_STROBE] = 1
    n_strobe = _SLICE_PERIODS if sliced else chunk_samples if cfg.stroboscopic else 0
    strobe = np.empty((n_strobe, K.STROBE_COLS))
    # status, rows written, rows still needed (kernel's O_* slots)
    info = np.zeros(K.N_OUT, dtype=np.int64)
    w = cfg.omega_s
    while True:
        K.run_chunk(prm, flg, st, ist, *event_buffers(), traj, strobe, info)
        status, n_ev = int(info[K.O_STATUS]), int(info[K.O_EVENTS])
        n_tr, n_sb = int(info[K.O_TRAJ]), int(info[K.O_STROBE])
        if status in (K.ST_NEED_TRAJ, K.ST_NEED_STROBE):
            # the buffers are full: stream them out; the next call resumes the same segment
            n_tr, n_sb = int(info[K.O_TRAJ_PARTIAL]), int(info[K.O_STROBE_PARTIAL])
        t_now = (ist[K.I_PERIOD] * K.TWO_PI + st[K.S_PHASE]) / w
        if n_ev or n_tr or n_sb:
            sb = strobe[:0] if sliced else strobe[:n_sb]
            yield n_ev, traj[:n_tr], sb, int(ist[K.I_EVENTS]), t_now
        if status in (K.ST_CHUNK, K.ST_NEED_TRAJ, K.ST_NEED_STROBE):
            continue
        if status in (K.ST_NEED_CONTACT, K.ST_NUMERICAL):
            raise EngineError(
                f"{STATUS_TEXT[status]} (at t = {t_now:.9g}, after {ist[K.I_EVENTS]} events)",
                status,
            )
        return status, _final_state(cfg, st, ist, flg, t_now)


def _final_state(
    cfg: EngineConfig, st: np.ndarray, ist: np.ndarray, flg: np.ndarray, t_now: float
) -> dict:
    """The state at the end of a run (:func:`iterate`'s ``final_state``)."""
    final = {
        "t": float(t_now),
        "u": float(st[K.S_U]),
        "v": float(st[K.S_V]),
        "omega": float(st[K.S_OMEGA]),
        # the kernel marks a finished run MODE_DONE and keeps the mode it ended in
        "in_contact": float(ist[K.I_LASTMODE] == K.MODE_CONTACT),
        "omega_integral": float(st[K.S_OMEGA_INTEGRAL]),
        "phase": float(st[K.S_PHASE]),  # the stator phase, exact (t is rounded)
    }
    if flg[K.F_STATS]:
        final["audit"] = _audit_terms(cfg, st, ist, bool(final["in_contact"]))
    return final


def iterate_views(
    cfg: EngineConfig,
    init: InitialState | None = None,
    chunk_events: int = 1 << 16,
    chunk_samples: int = 1 << 16,
) -> Iterator[ChunkView]:
    """:func:`iterate` without copies: one :class:`ChunkView` per kernel call, valid until the
    next. The generator's return value is ``(status_code, final_state)``. ``chunk_events`` and
    ``chunk_samples`` must be whole numbers >= 1 (a buffer of none never fills: no call would
    end)."""
    for name, n in (("chunk_events", chunk_events), ("chunk_samples", chunk_samples)):
        if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1:
            raise InputError("iterate", name, f"must be a whole number >= 1, got {n!r}")
    # the kernel's event columns are the rows of one block; a view shows them as columns
    block = np.empty((K.EV_COLS, chunk_events))
    buffers = (tuple(block), np.empty(chunk_events, dtype=np.int8))
    calls = Returning(_kernel_calls(cfg, init or InitialState(), lambda: buffers, chunk_samples))
    for n_ev, traj, strobe, total, t_now in calls:
        yield ChunkView(block[:, :n_ev].T, buffers[1][:n_ev], traj, strobe, total, t_now)
    return calls.value


def iterate(
    cfg: EngineConfig,
    init: InitialState | None = None,
    chunk_events: int = 1 << 16,
    chunk_samples: int = 1 << 16,
) -> Iterator[Chunk]:
    """Run the simulation, yielding one :class:`Chunk` per kernel call.

    The generator's return value (``StopIteration.value``) is ``(status_code, final_state)``.

    Raises
    ------
    EngineError
        When the dynamics need an effect the configuration left out, or an event search fails.
    """
    raw = Returning(iterate_views(cfg, init, chunk_events, chunk_samples))
    for c in raw:
        ev = c.ev
        yield Chunk(
            t=ev[:, K.EV_T].copy(),
            phase=ev[:, K.EV_PHASE].copy(),
            v_rel=ev[:, K.EV_V_REL].copy(),
            omega_after=ev[:, K.EV_OMEGA_AFTER].copy(),
            u=ev[:, K.EV_U].copy(),
            omega_before=ev[:, K.EV_OMEGA_BEFORE].copy(),
            kind=c.evk.copy(),
            traj=c.traj.copy(),
            strobe=c.strobe.copy(),
            n_events_total=c.n_events_total,
            t_now=c.t_now,
        )
    return raw.value


def _audit_terms(cfg: EngineConfig, st: np.ndarray, ist: np.ndarray, in_contact: bool) -> dict:
    """The energy audit's accumulated terms over the window, with the energies at its ends."""
    if in_contact:
        th = st[K.S_PHASE]
        u, v = math.sin(th), cfg.omega_s * math.cos(th)
    else:  # a run ends in flight at an impact or at its end time: the flight's origin is now
        u, v = st[K.S_U], st[K.S_V]
    started = bool(ist[K.I_AUD_STARTED])
    axial = not cfg.clipped
    e0, e1 = (float(st[K.S_AUD_E0]), 0.5 * v * v + u) if started and axial else (0.0, 0.0)
    k0, k1 = (float(st[K.S_AUD_K0]), 0.5 * st[K.S_OMEGA] ** 2) if started else (0.0, 0.0)
    return {
        "work_axial": float(st[K.S_AUD_WAX]) if axial else math.nan,
        "loss_axial": float(st[K.S_AUD_DAX]) if axial else math.nan,
        "chatter_axial": float(st[K.S_AUD_CAX]) if axial else math.nan,
        "energy_axial_change": e1 - e0,
        "energy_axial_level": max(abs(e0), abs(e1)),
        "work_torsion": float(st[K.S_AUD_WT]),
        "loss_friction": float(st[K.S_AUD_DF]),
        "work_load": cfg.load_torque * float(st[K.S_OMEGA_INTEGRAL]),
        "energy_torsion_change": k1 - k0,
        "energy_torsion_level": max(k0, k1),
    }


def audit_balances(terms: dict) -> tuple[float, float]:
    """Relative residuals of the two energy balances (docs/model.md "Power and energy audit").

    Axial ``W_ax = ΔE_ax + D_ax (+ C_ax)``, torsional ``W_t = Δ(Ω²/2) + D_f + W_L``, each
    residual divided by the largest of its terms and of the energies at the window's ends
    (``energy_*_level``: the change is their difference, rounded at their size; a window with
    no work, a rotor in free flight, then reads round-off, not 1), and 0 when all are 0.
    ``C_ax`` is the axial energy left to summed chattering tails, reported apart
    (``terms["chatter_axial"]``). The axial residual is ``nan`` for the clipped model (no axial
    balance).
    """

    def rel(level: float, lhs: float, *rhs: float) -> float:
        if math.isnan(lhs) or any(math.isnan(x) for x in rhs):
            return math.nan
        scale = max(level, abs(lhs), *(abs(x) for x in rhs))
        return abs(lhs - sum(rhs)) / scale if scale > 0.0 else 0.0

    t = terms
    ax = rel(
        t["energy_axial_level"],
        t["work_axial"],
        t["energy_axial_change"],
        t["loss_axial"],
        t["chatter_axial"],
    )
    tor = rel(
        t["energy_torsion_level"],
        t["work_torsion"],
        t["energy_torsion_change"],
        t["loss_friction"],
        t["work_load"],
    )
    return ax, tor


#: Events and samples of one kernel call of :func:`simulate_arrays` (the sample buffers fit a
#: core's cache).
_COLLECT_CHUNK = 1 << 14
#: Largest event count :func:`simulate_arrays` allocates at once for a run that stops on events.
_COLLECT_PREALLOCATE = 1 << 22


class _Filling:
    """An array filled block by block, its capacity doubled in place (``ndarray.resize``:
    ``realloc``, no copy for a large block) and trimmed at the end: each value is written once,
    by :meth:`add` or in place into a :meth:`window`."""

    def __init__(self, cap: int, cols: int | None, dtype=float):
        self.a = np.empty((max(cap, 1),) if cols is None else (max(cap, 1), cols), dtype=dtype)
        self.n = 0

    def _reserve(self, m: int) -> None:
        if self.n + m > len(self.a):
            cap = max(2 * len(self.a), self.n + m)
            # no view is in use: a window is valid only until the next window or add
            self.a.resize((cap, *self.a.shape[1:]), refcheck=False)

    def add(self, block: np.ndarray) -> None:
        m = len(block)
        self._reserve(m)
        self.a[self.n : self.n + m] = block
        self.n += m

    def window(self, m: int) -> np.ndarray:
        """The next ``m`` rows, to be written in place; :meth:`take` counts those written."""
        self._reserve(m)
        return self.a[self.n : self.n + m]

    def take(self, m: int) -> None:
        self.n += m

    def done(self) -> np.ndarray:
        self.a.resize((self.n, *self.a.shape[1:]), refcheck=False)
        return self.a


#: The event columns of :attr:`RunResult.events` (``kind`` apart), by name.
_EVENT_COLUMNS = {
    "t": K.EV_T,
    "phase": K.EV_PHASE,
    "v_rel": K.EV_V_REL,
    "omega_after": K.EV_OMEGA_AFTER,
    "u": K.EV_U,
    "omega_before": K.EV_OMEGA_BEFORE,
}


def simulate_arrays(
    cfg: EngineConfig,
    init: InitialState | None = None,
    on_chunk: Callable[[Chunk], None] | None = None,
) -> RunResult:
    """Run to the end and collect events and samples in memory.

    The kernel writes the events straight into their output arrays, and each sample is copied
    once, from the kernel's buffer into its output array (the arrays of :func:`iterate`'s
    chunks, concatenated, are the same values).

    Raises
    ------
    EngineError
        As :func:`iterate`.
    """
    if on_chunk is not None:
        return _collect_chunks(cfg, init, on_chunk)
    stops_on_events = math.isinf(cfg.t_end)
    cap = cfg.max_events if stops_on_events else 1 << 16
    cap = min(cap, _COLLECT_PREALLOCATE)
    out = [_Filling(cap, None) for _ in range(K.EV_COLS)]  # by column index EV_*
    kind = _Filling(cap, None, np.int8)
    traj = _Filling(1 << 12 if cfg.traj_dt > 0 else 0, K.TRAJ_COLS)
    strobe = _Filling(1 << 12 if cfg.stroboscopic else 0, K.STROBE_COLS)

    def event_buffers() -> tuple[tuple[np.ndarray, ...], np.ndarray]:
        # the next rows of the outputs; no more than the run's remaining events
        m = min(_COLLECT_CHUNK, cfg.max_events - kind.n)
        return tuple(f.window(m) for f in out), kind.window(m)

    calls = Returning(_kernel_calls(cfg, init or InitialState(), event_buffers, _COLLECT_CHUNK))
    for n_ev, c_traj, c_strobe, _total, _t_now in calls:
        for f in (*out, kind):
            f.take(n_ev)
        traj.add(c_traj)
        strobe.add(c_strobe)
    status, final = calls.value
    events = {name: out[j].done() for name, j in _EVENT_COLUMNS.items()}
    events["kind"] = kind.done()
    return RunResult(events, traj.done(), strobe.done(), STATUS_TEXT[status], status, final)


def _collect_chunks(
    cfg: EngineConfig, init: InitialState | None, on_chunk: Callable[[Chunk], None]
) -> RunResult:
    """:func:`simulate_arrays` handing every chunk to ``on_chunk`` as it comes."""
    chunks: list[Chunk] = []
    gen = Returning(iterate(cfg, init))
    for c in gen:
        chunks.append(c)
        on_chunk(c)
    status, final = gen.value

    def cat(name: str, dtype=float) -> np.ndarray:
        parts = [getattr(c, name) for c in chunks]
        return np.concatenate(parts) if parts else np.empty(0, dtype=dtype)

    events = {
        "t": cat("t"),
        "phase": cat("phase"),
        "v_rel": cat("v_rel"),
        "omega_after": cat("omega_after"),
        "u": cat("u"),
        "omega_before": cat("omega_before"),
        "kind": cat("kind", np.int8),
    }
    traj = np.concatenate([c.traj for c in chunks]) if chunks else np.empty((0, K.TRAJ_COLS))
    strobe = np.concatenate([c.strobe for c in chunks]) if chunks else np.empty((0, K.STROBE_COLS))
    # the final state of a 'rest' run is the contact state at the last event
    return RunResult(events, traj, strobe, STATUS_TEXT[status], status, final)
