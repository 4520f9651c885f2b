"""The engine's array layouts and codes: plain integers, no numba.

The compiled kernel (:mod:`bouncedisk.engine.kernel`, which re-exports every name here) keeps a
run's whole state in small arrays, reads its parameters and flags from two more and writes its
outputs to row buffers; these are their indices, and the codes of modes, statuses, event and
segment kinds. Kept apart from the kernel so that code that only names the records (netCDF
writing and reading, :mod:`bouncedisk.io.records`; figures) does not import numba.
"""

# --- parameter vector (float64) ---------------------------------------------------------------
P_E = 0  # restitution e
P_W = 1  # stator frequency w
P_R = 2  # angular amplitude ratio R
P_PSI = 3  # torsional phase psi
P_TOL = 4  # root tolerance
P_INERTIA = 5  # J_s/(J_s + J_r) of the stator_inertia effect (1: eq. 19)
P_MU_RATIO = 6  # static/kinetic friction ratio of the kinetic_static effect
P_TEND = 7  # end time
P_DT, P_T0, P_T1 = 8, 9, 10  # trajectory grid: step, first and last sample time
P_ESIG = 11  # restitution noise σ_e (effect `restitution_noise`)
P_TSTAT = 12  # time from which ∫Ω dt and the energy audit are accumulated
P_LOAD = 13  # load torque τ_L (effect `load`; docs/model.md "The motor under load")
N_PRM = 14
# --- flags (int64) ----------------------------------------------------------------------------
F_CONTACT, F_TORSION, F_CAP, F_TRAJ, F_STROBE, F_MAXEV, F_CLIPPED = range(7)
F_NOISE, F_SEED, F_MEMBER, F_STATS = range(7, 11)  # restitution noise stream; accumulate ∫Ω dt
F_AXIAL_AUDIT = 11  # accumulate the axial energy audit too (not in the clipped model)
N_FLG = 12
# --- float state ------------------------------------------------------------------------------
S_PHASE = 0  # stator phase θ in [0, 2π) (with I_PERIOD: t = (2π n + θ)/w)
S_U, S_V = 1, 2  # rotor position and velocity at the flight's origin
S_OMEGA = 3  # rotor angular velocity Ω
S_ANCHOR_TAU = 4  # flight: time after the origin where the impact search starts
S_ANCHOR_GAP = 5  # flight: the gap at that time
S_CHATTER_PHASE = 6  # contact: stator phase of a chattering sequence's accumulation point
S_OMEGA_INTEGRAL = 7  # ∫Ω dt since prm[P_TSTAT] (when flg[F_STATS])
# energy audit since prm[P_TSTAT] (when flg[F_STATS]; docs/model.md "Power and energy audit"):
S_AUD_WAX = 8  # stator's axial work W_ax (impacts and contact)
S_AUD_DAX = 9  # axial impact loss D_ax
S_AUD_CAX = 10  # axial energy of summed chattering tails (their approximation, kept apart)
S_AUD_WT = 11  # stator's torsional input W_t (friction in contact and angular impulses)
S_AUD_DF = 12  # friction loss D_f
S_AUD_E0 = 13  # axial energy v²/2 + u where the audit window starts
S_AUD_K0 = 14  # rotational energy Ω²/2 where the audit window starts
# sin and cos of the phase S_SC_PHASE, kept by the impact that starts a flight for its impact
# search; read only when S_SC_PHASE equals the flight's phase (so any state array is valid)
S_SC_PHASE, S_SC_SIN, S_SC_COS = 15, 16, 17
N_ST = 18
# --- int state --------------------------------------------------------------------------------
I_PERIOD = 0  # stator period count n
I_MODE = 1  # MODE_FLIGHT, MODE_CONTACT or MODE_DONE
I_SLIP_SIGN = 2  # contact: sgn(s), 0 while sticking
I_SLIP_GUARD = 3  # contact: leaving s = 0, search the slip's zero only once it has grown
I_CHATTERING = 4  # contact: a chattering sequence accumulates at I_CHATTER_PERIOD, S_CHATTER_PHASE
I_CHATTER_PERIOD = 5
I_EVENTS = 6  # events so far (impacts and chattering tails)
I_NEXT_SAMPLE = 7  # index of the next trajectory sample
I_NEXT_STROBE = 8  # period of the next stroboscopic sample
I_ZERO_STEPS = 9  # consecutive contact segments of zero length (a stall guard)
I_STATUS = 10  # status of a finished run
I_UNLOADED = 11  # clipped model: riding the stator without load
I_LASTMODE = 12  # the mode (flight or contact) the run ended in
I_AUD_STARTED = 13  # the audit window has started (S_AUD_E0, S_AUD_K0 are set)
N_IST = 14
# --- modes ------------------------------------------------------------------------------------
MODE_FLIGHT, MODE_CONTACT, MODE_DONE = 0, 1, 2
# --- statuses ---------------------------------------------------------------------------------
ST_CHUNK = 0  # a buffer is full; call again
ST_EVENTS = 1  # the requested number of events was reached
ST_TIME = 2  # the requested end time was reached
ST_REST = 3  # the rotor stays in contact for ever: no further impact can occur
ST_NEED_CONTACT = 4  # the dynamics need the `contact` effect, which the scene left out
ST_NUMERICAL = 5  # a root search failed or made no progress
ST_NEED_TRAJ = 6  # trajectory buffer full inside a segment (info[O_NEED], info[O_*_PARTIAL])
ST_NEED_STROBE = 7  # stroboscopic buffer full inside a segment (as ST_NEED_TRAJ)
# --- event kinds ------------------------------------------------------------------------------
KIND_IMPACT, KIND_CHATTER = 0, 1
# --- segment kinds for sampling ---------------------------------------------------------------
SEG_FLIGHT, SEG_CONTACT, SEG_SLIP, SEG_STICK = 0, 1, 2, 3

# --- output counters of one call (int64 ``info``) ---------------------------------------------
O_STATUS = 0  # status of the call (ST_*)
O_EVENTS, O_TRAJ, O_STROBE = 1, 2, 3  # rows of ev, traj and strobe written by the call
O_NEED = 4  # ST_NEED_*: rows the segment still needs
O_TRAJ_PARTIAL, O_STROBE_PARTIAL = 5, 6  # ST_NEED_*: rows written, with the segment's first ones
N_OUT = 7
ST_CONTINUE = -1  # a mode function's return value when the event loop goes on
# --- columns of the output buffers ------------------------------------------------------------
# the event buffer is a tuple of EV_COLS column arrays (kernel.run_chunk), indexed by EV_*; a
# ChunkView's ``ev`` shows them as rows (n, EV_COLS) with these columns
EV_T, EV_PHASE, EV_V_REL, EV_OMEGA_AFTER, EV_U, EV_OMEGA_BEFORE = range(6)
EV_COLS = 6
TR_T, TR_U, TR_V, TR_U_STATOR, TR_OMEGA = range(5)
TRAJ_COLS = 5
SB_PERIOD, SB_T, SB_U, SB_V, SB_OMEGA = range(5)
STROBE_COLS = 5

#: The text of a finished run's status (a file's ``status`` attribute).
STATUS_TEXT = {
    ST_EVENTS: "completed",
    ST_TIME: "completed",
    ST_REST: "rest: the rotor stays in contact with the stator for ever (no further impact)",
    ST_NEED_CONTACT: (
        "missing effect 'contact': the rotor lands softly or chatters and must ride the stator, "
        "which needs the 'contact' effect"
    ),
    ST_NUMERICAL: "numerical failure: an event search failed or made no progress",
}
#: The statuses of a run that ended as asked: events or time reached, or the rotor at rest.
OK_STATUSES = frozenset({ST_EVENTS, ST_TIME, ST_REST})
