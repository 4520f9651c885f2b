"""The load curve's share of the joint likelihood: readings from rest under each load.

A measured load curve (:mod:`bouncedisk.io.load_curves`, docs/formats.md) holds at every load torque
``T_j`` (N·m) the mean rotor speed ``y_j`` (rad/s) over ``window_s = [t0, t1]`` after a start
from rest under that load. At a parameter point ``θ = (e, ω_s, R_φ, ψ)`` the model predicts it
exactly (docs/model.md "The motor under load", "Physical conversion"): with the drive ``(f, Φ0)`` and
the rotor known, ``t_c = ω_s / (2π f)``, the speed scale ``R_φ Φ0 / t_c`` and the torque scale
``μ m_r g_eff r_eff`` (:meth:`bouncedisk.model.params.PhysicalParameters.scales`) turn ``T_j`` into the
nondimensional ``τ_L`` and the window into ``[t0, t1] / t_c``; member ``m`` runs the engine from
rest in contact at ``t = 0`` under ``τ_L`` with restitution noise on its own stream and reads
``∫Ω dt`` over the window (the kernel's exact integral, no sampling). The axial motion does not
depend on the load, so one member's readings at all loads share one axial trajectory
(:mod:`bouncedisk.engine.loads`): a curve of 16 loads costs a few runs, not 16.

The residual of the load part is ``μ(θ) − y`` with ``μ`` the mean of ``K`` members, whose
covariance is the data's own spread plus the model's Monte-Carlo error:

    Σ = D + C_L / K,   D_j = max(s_j², C_L,jj) / n_rep,

``C_L`` the members' covariance across loads (common random numbers: member ``m`` uses the same
noise stream at every load, so its readings are correlated), ``s_j`` the data's spread of
repeated readings (``speed_sd_rad_s``) and ``n_rep`` the readings averaged per load (sidecar
``repeats``, default 1: each row one reading). ``C_L`` is held at its value near the optimum, as
the run-ups' ``C`` (:mod:`.objective`); the readings of different loads are independent runs in
the lab, so ``D`` is diagonal. The joint ``χ²`` is the run-ups' plus this part's (independent
experiments: block-diagonal covariance).

**Conditions.** The load curves of one motor may differ in drive frequency ``f``, torsional
amplitude ``Φ0``, rotor and preload: each is a condition of the same motor. Its axial amplitude
``U0``, friction ``μ``, restitution (``e``, ``σ_e``) and phase ``ψ`` are shared, and the point's
nondimensional ``ω_s = 2π f t_c`` (``t_c = √(U0/g_eff)``, ``g_eff = g + F/m_r``) and ``R_φ = μ U0
r_eff / (r_g² Φ0)`` are those of the reference condition, the run-ups' drive and ``Φ0`` with the
rotor and preload of the load curves run at them (:func:`reference_setup`; docs/model.md
"Physical conversion"; :meth:`LoadPart.condition`). The stator's amplitude is a condition too:
where the curves state different axial amplitudes (sidecar ``motor.U0_m``, the run-ups' and
every load curve's, :func:`amplitudes`), a curve's ``U0`` is the reference's times the ratio of
the stated amplitudes (``ω_s ∝ √U0``, ``R_φ ∝ U0``); the absolute ``U0`` stays the fit's (its
``ω_s`` at the reference drive). Where they all state one amplitude, or none does, ``U0`` is held
across conditions (some stating it and some not is one line naming the first that does not),
which assumes the lab holds the stator's amplitude (a driver with amplitude feedback);
``ψ`` is held, which assumes the stator's phase does not move.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..engine import InitialState
from ..engine.loads import omega_integrals
from ..io.curve_files import stated_u0
from ..io.load_curves import LoadCurveData
from ..model.engine_config import motor_config
from ..model.errors import InputError
from ..model.params import Parameters, PhysicalParameters
from . import detlinalg
from .members import restitution_noise, thread_map

#: Load members per evaluation of the load part (local search, profiles).
LOAD_MEMBERS = 8
#: Load members when the run-ups are evaluated on one member (the scan's candidates).
LOAD_SCAN = 4
#: Members measuring the load part's covariance ``C_L`` (the pilot).
LOAD_PILOT = 32
#: Members of the fitted load curve's band.
LOAD_BAND = 16
#: Load members run on the streams ``(seed, LOAD_STREAM + m)``, apart from the run-ups' ``(seed, m)``.
LOAD_STREAM = 1_000_000
#: Resolution floor of a reading's standard deviation, as a fraction of the largest |speed|: a
#: periodic motor's readings repeat exactly (members and repeats identical), and a reading is not
#: known better than a tachometer resolves it.
LOAD_FLOOR = 1e-2
#: An evaluation of the load part that runs longer than this (s) reports its progress.
PROGRESS_S = 10.0
#: Event budget of one reading (a start from rest to the window's end).
MAX_EVENTS = 50_000_000


def _physical(
    theta: dict[str, float], f: float, phi0: float, rotor: dict, preload: float
) -> PhysicalParameters:
    """The motor of parameter point ``θ`` driven at ``(f, Φ0)`` with ``rotor`` and ``preload``,
    in SI units (:meth:`~bouncedisk.model.params.PhysicalParameters.from_nondimensional`; ``U0``
    follows from ``ω_s``, ``f`` and ``g_eff``)."""
    p = Parameters(
        e=theta["e"], omega_s=theta["omega_s"], r_phi=10.0 ** theta["log10_r_phi"], psi=theta["psi"]
    )
    r = rotor
    return PhysicalParameters.from_nondimensional(
        p, f, phi0, r["m_r_kg"], r["r_g_m"], r["r_c_m"], F_preload=preload
    )


class Setup(NamedTuple):
    """What a curve states of how the motor ran: drive ``f`` (Hz), ``Φ0`` (rad), the rotor
    (``m_r_kg``, ``r_g_m``, ``r_c_m``), the preload (N) and the axial amplitude ``u0`` (m;
    ``None`` where not stated or where every curve states the same, module docstring)."""

    f: float
    phi0: float
    rotor: dict
    preload: float
    u0: float | None = None


def amplitudes(curves: list[LoadCurveData], runups_u0: float | None, runups: str) -> bool:
    """Whether the amplitudes are conditions (module docstring): ``True`` when the run-ups
    (``runups_u0``, stated in the sidecar of ``runups``) and the load curves state different
    ``U0_m``; ``False`` when they all state one amplitude, or none does (``U0`` held across
    conditions). Where some state it and some do not, one line names the first that does not: an
    amplitude stated for one curve only would otherwise be held without a word."""
    stated = [runups_u0] + [stated_u0(d.sidecar) for d in curves]
    given = {u for u in stated if u is not None}
    if not given:
        return False
    paths = [runups] + [str(Path(d.path).with_suffix(".yaml")) for d in curves]
    for path, u in zip(paths, stated, strict=True):
        if u is None:
            raise InputError(
                path,
                "motor.U0_m",
                "is required: another of the motor's curves states its axial amplitude, and "
                "each curve's amplitude is a condition of the motor; state it in every sidecar, "
                "or in none to hold it (docs/user_guide/fitting.md, Conditions)",
            )
    return len(given) > 1


def setup(d: LoadCurveData, with_u0: bool = False) -> Setup:
    """The condition load curve ``d`` states (its amplitude when ``with_u0``, :func:`amplitudes`)."""
    u0 = stated_u0(d.sidecar) if with_u0 else None
    return Setup(d.drive_frequency_hz, d.phi0_rad, d.rotor, d.preload_n, u0)


def reference_setup(
    curves: list[LoadCurveData],
    drive_hz: float | None,
    phi0_rad: float | None,
    u0: float | None = None,
) -> Setup:
    """The condition a fit's parameter point is stated at (module docstring, "Conditions"): the
    run-ups' drive ``drive_hz`` and ``phi0_rad`` (the first curve's where ``None``) with the
    rotor and preload of the load curves run at that drive and ``Φ0`` (of every curve when none
    is): the run-ups' sidecars state no rotor. Those curves must agree on it (one line naming
    the first that does not, otherwise), so the order of the curves changes nothing. ``u0``: the
    run-ups' stated amplitude where the amplitudes are conditions (:func:`amplitudes`)."""
    f = curves[0].drive_frequency_hz if drive_hz is None else drive_hz
    phi0 = curves[0].phi0_rad if phi0_rad is None else phi0_rad
    same = [d for d in curves if (d.drive_frequency_hz, d.phi0_rad) == (f, phi0)] or curves
    for d in same[1:]:
        if (d.rotor, d.preload_n) != (same[0].rotor, same[0].preload_n):
            raise InputError(
                str(Path(d.path).with_suffix(".yaml")),
                "rotor" if d.rotor != same[0].rotor else "preload_N",
                f"differs from {same[0].path}'s, at the same drive and Phi0: the run-ups' rotor "
                "and preload are ambiguous (docs/user_guide/fitting.md, Conditions)",
            )
    return Setup(f, phi0, same[0].rotor, same[0].preload_n, u0)


def convert(theta: dict[str, float], src: Setup, dst: Setup) -> dict[str, float]:
    """Parameter point ``θ`` of the motor run as ``src`` states, for the same motor run as
    ``dst`` states (module docstring, "Conditions"): the motor in SI units
    (:meth:`~bouncedisk.model.params.PhysicalParameters.from_nondimensional`), driven and loaded
    as ``dst`` says, made nondimensional again; ``μ``, ``e`` and ``ψ`` are kept, and ``U0``
    too unless both state an amplitude (then scaled by ``dst.u0 / src.u0``)."""
    if src == dst:
        return theta
    r = dst.rotor
    p = _physical(theta, src.f, src.phi0, src.rotor, src.preload)
    p = dataclasses.replace(
        p,
        U0=p.U0 * (dst.u0 / src.u0) if src.u0 and dst.u0 else p.U0,
        f=dst.f,
        Phi0=dst.phi0,
        m_r=r["m_r_kg"],
        r_g=r["r_g_m"],
        r_c=r["r_c_m"],
        F_preload=dst.preload,
    ).to_nondimensional()
    return {**theta, "omega_s": p.omega_s, "log10_r_phi": math.log10(p.r_phi)}


def motor_scales(theta: dict[str, float], data: LoadCurveData) -> tuple[float, float, float]:
    """``(t_c [s], speed scale [rad/s], torque scale [N·m])`` of a parameter point for a motor
    (docs/model.md "Physical conversion"; the torque scale ``μ m_r g_eff r_eff`` of "The motor under
    load"), by :meth:`~bouncedisk.model.params.PhysicalParameters.from_nondimensional`."""
    phys = _physical(theta, data.drive_frequency_hz, data.phi0_rad, data.rotor, data.preload_n)
    sc = phys.scales()
    return sc.t_c, sc.omega_scale, sc.torque


def curve_readings(
    theta: dict[str, float], data: LoadCurveData, member: int, e_sigma: float, seed: int
) -> np.ndarray:
    """One member's mean speed (rad/s) over the curve's window after a start from rest under each
    of its loads (module docstring): one axial trajectory carries every load's rotation
    (:func:`bouncedisk.engine.loads.omega_integrals`, bit-identical to a run per load)."""
    t_c, speed, torque = motor_scales(theta, data)
    t0, t1 = (w / t_c for w in data.window_s)
    cfg = motor_config(
        theta["e"],
        theta["omega_s"],
        10.0 ** theta["log10_r_phi"],
        theta["psi"],
        t_end=t1,
        max_events=MAX_EVENTS,
        e_sigma=restitution_noise(theta, e_sigma),
        seed=seed,
        member=LOAD_STREAM + member,
        stats_from=t0,
    )
    # a run stopped by the event budget before t1 has not read the window: NaN, never the part
    # it reached divided by the whole window (the objective rejects the point)
    integrals = omega_integrals(
        cfg, data.torque / torque, InitialState(t=0.0, omega=0.0), reached_only=True
    )
    return integrals / (t1 - t0) * speed


def check_window(data: LoadCurveData) -> None:
    """Refuse a window the members cannot reach within their event budget (before any work).

    A member runs from rest to ``t1``: ``t1 f`` drive periods, of which a bouncing rotor impacts
    about once each. A window of more periods than :data:`MAX_EVENTS` would stop at the budget
    on any such motor, and its reading would not be the mean over the window.
    """
    t1 = data.window_s[1]
    periods = t1 * data.drive_frequency_hz
    if periods > MAX_EVENTS:
        side = str(Path(data.path).with_suffix(".yaml"))
        raise InputError(
            side,
            "window_s",
            f"ends at {t1:g} s = {periods:.3g} drive periods "
            f"after the start; a reading can follow at most {MAX_EVENTS:.3g} "
            "impacts, so the model cannot read that window",
        )


@dataclass
class LoadPart:
    """The load curves' residuals at a parameter point (module docstring), with a cache.

    Parameters
    ----------
    curves : list of LoadCurveData
        The measured load curves (one or more, of the run-ups' motor).
    e_sigma, seed : float, int
        Restitution noise and seed of the members (the run-ups' ``EnsembleSpec``).
    members : int
        Members per evaluation ``K`` (the scan evaluates with one).
    cores : int
        Threads running the readings of one evaluation.
    progress : callable or None
        Receives a line every :data:`PROGRESS_S` seconds of a long evaluation.
    drive_hz, phi0_rad : float or None
        The drive frequency and ``Φ0`` of the reference condition (the run-ups'), the condition
        ``θ`` is stated at (:func:`reference_setup`); a curve of another condition is read at its
        own (:meth:`condition`). ``None``: the first curve's.
    u0 : float or None
        The run-ups' stated axial amplitude (m) where the amplitudes are conditions
        (:func:`amplitudes`), else ``None`` (``U0`` held across conditions).
    given_reference : Setup or None
        The reference condition itself, when known whole (``drive_hz`` and ``phi0_rad`` are then
        not used).
    """

    curves: list[LoadCurveData]
    e_sigma: float
    seed: int
    members: int = LOAD_MEMBERS
    cores: int = 1
    progress: Callable[[str], None] | None = None  # long evaluations report through it
    drive_hz: float | None = None
    phi0_rad: float | None = None
    u0: float | None = None
    given_reference: Setup | None = None
    cache: dict = field(default_factory=dict)
    cov_model: np.ndarray | None = None
    _white: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.y = np.concatenate([d.speed for d in self.curves])
        sd = [
            d.speed_sd if d.speed_sd is not None else np.full(len(d.torque), np.nan)
            for d in self.curves
        ]
        self.sd = np.concatenate(sd)
        self.repeats = np.concatenate([np.full(len(d.torque), _repeats(d)) for d in self.curves])
        self.floor = LOAD_FLOOR * max(float(np.max(np.abs(self.y))), 1e-12)
        #: The reference condition (``given_reference``, else :func:`reference_setup`).
        self.reference = self.given_reference or reference_setup(
            self.curves, self.drive_hz, self.phi0_rad, self.u0
        )

    def condition(self, theta: dict[str, float], d: LoadCurveData) -> dict[str, float]:
        """``θ`` (stated at the reference condition) at curve ``d``'s (:func:`convert`)."""
        return convert(theta, self.reference, setup(d, self.reference.u0 is not None))

    def slices(self) -> list[tuple[np.ndarray, slice]]:
        """Every curve's torques (N·m) and where its readings sit in the flattened vectors."""
        out, k = [], 0
        for d in self.curves:
            out.append((d.torque, slice(k, k + len(d.torque))))
            k += len(d.torque)
        return out

    @property
    def n(self) -> int:
        """Readings fitted."""
        return len(self.y)

    def values(
        self, theta: dict[str, float], x: np.ndarray, k: int, serial: bool = False
    ) -> np.ndarray:
        """Readings ``(k, n)`` of members ``0 … k−1`` at ``x`` (cached; a larger cached set is
        reused, its first ``k`` members being the same streams)."""
        key = tuple(x)
        have = self.cache.get(key)
        if have is None or len(have) < k:
            start = 0 if have is None else len(have)
            # at sigma_e = 0 every member reads the same, bit for bit (their streams draw only
            # the restitution noise): one member's curves, repeated
            same = restitution_noise(theta, self.e_sigma) == 0.0
            tasks = [(m, d) for m in range(start, start + 1 if same else k) for d in self.curves]

            def one(task):
                d = task[1]
                return curve_readings(self.condition(theta, d), d, task[0], self.e_sigma, self.seed)

            started = time.perf_counter()
            last = [started]

            def done(j: int) -> None:  # a long curve reports its progress (PROGRESS_S)
                now = time.perf_counter()
                if self.progress is not None and now - last[0] >= PROGRESS_S:
                    last[0] = now
                    self.progress(
                        f"load curve: {j}/{len(tasks)} member curves read at this "
                        f"point ({now - started:.0f} s)"
                    )

            if serial or self.cores <= 1 or len(tasks) < 2:
                flat = []
                for t in tasks:
                    flat.append(one(t))
                    done(len(flat))
            else:
                flat = thread_map(one, tasks, self.cores, done)
            new = np.concatenate(flat).reshape(-1, self.n)
            new = np.repeat(new, k - start, axis=0) if same else new
            have = new if have is None else np.vstack([have, new])
            self.cache[key] = have
        return have[:k]

    def set_cov(self, values: np.ndarray) -> None:
        """Hold the members' covariance across loads at that of ``values`` ``(K, n)``,
        shrunk toward its diagonal (:meth:`members_cov`)."""
        self.cov_model = self.members_cov(values)
        self._white = {}

    def members_cov(self, values: np.ndarray) -> np.ndarray:
        """The members' covariance across loads of ``values`` ``(K, n)``, shrunk toward its
        diagonal (as the run-ups', :func:`.summary_stats.regularized_cov`)."""
        from .summary_stats import EnsembleStats, regularized_cov

        ens = EnsembleStats.from_values(values)
        return regularized_cov(ens.cov, np.full(self.n, self.floor))

    def data_var(self, cov: np.ndarray | None = None) -> np.ndarray:
        """``D``: the data's variance of each reading (module docstring), with the members'
        covariance ``cov`` (the held one when ``None``)."""
        cov = self.cov_model if cov is None else cov
        model = np.diag(cov) if cov is not None else np.zeros(self.n)
        spread = np.where(np.isfinite(self.sd), self.sd**2, model)
        return np.maximum(np.maximum(spread, model), self.floor**2) / self.repeats

    def factor(self, k: int, cov: np.ndarray | None = None) -> np.ndarray:
        """``L`` with ``L Lᵀ = D + C_L / k``, ``C_L`` the members' covariance ``cov`` (the
        held one when ``None``; BLAS-free, :mod:`.detlinalg`)."""
        cov = self.cov_model if cov is None else cov
        c = cov if cov is not None else np.zeros((self.n, self.n))
        return detlinalg.cholesky(np.diag(self.data_var(cov)) + c / k)

    def whitener(self, k: int) -> np.ndarray:
        """``L⁻¹`` of :meth:`factor` with the held covariance (cached per ``k``)."""
        if k not in self._white:
            self._white[k] = detlinalg.lower_inverse(self.factor(k))
        return self._white[k]

    def own_loglik(self, theta: dict[str, float], x: np.ndarray, k: int) -> float:
        """``−2 log L`` of the readings, up to a constant, with the members' covariance measured
        at ``x`` itself on its ``k`` members: ``rᵀ Σ⁻¹ r + log det Σ``, ``Σ = D + C_L(x)/k``
        (:meth:`.objective.Objective.own_loglik`); ``inf`` where a member did not reach a reading."""
        values = self.values(theta, x, k)
        if not np.isfinite(values).all():
            return math.inf
        low = self.factor(k, self.members_cov(values))
        r = detlinalg.matvec(detlinalg.lower_inverse(low), self.mean(theta, x, k) - self.y)
        return detlinalg.dot(r, r) + detlinalg.log_det(low)

    def mean(
        self, theta: dict[str, float], x: np.ndarray, k: int, serial: bool = False, first: int = 0
    ) -> np.ndarray:
        """Mean reading of members ``first … first+k−1``, summed in member order (the same bits
        everywhere)."""
        return np.add.reduce(self.values(theta, x, first + k, serial)[first:], axis=0) / k

    def residuals(
        self, theta: dict[str, float], x: np.ndarray, k: int, serial: bool = False, first: int = 0
    ) -> np.ndarray:
        """Whitened residuals ``L⁻¹ (μ(θ) − y)`` of members ``first … first+k−1``."""
        mean = self.mean(theta, x, k, serial, first)
        return detlinalg.matvec(self.whitener(k), mean - self.y)


def _repeats(d: LoadCurveData) -> int:
    """Readings averaged per load (sidecar ``repeats``; 1: each row one reading)."""
    return int(d.sidecar.get("repeats", 1))


def members_for(k: int) -> int:
    """Load members for an evaluation of the run-ups with ``k`` members: :data:`LOAD_SCAN` for
    the scan's one member, :data:`LOAD_MEMBERS` otherwise. A member's whole load curve costs
    about one run (:mod:`bouncedisk.engine.loads`), so the load part gets more members than its
    share of the cost would suggest: its Monte-Carlo error is what blurs the narrow joint valley."""
    return LOAD_SCAN if k <= 1 else LOAD_MEMBERS


def band(part: LoadPart, theta: dict[str, float], x: np.ndarray, members: int = LOAD_BAND) -> dict:
    """The fitted model's load curve: mean of ``members`` members, the 95 % interval of the mean
    (Student) and the members' 2.5–97.5 % band, at every measured load."""
    from .summary_stats import member_band

    return member_band(part.values(theta, x, members))
