"""The model side of the fit: parameter space, physical scales, members on the curve's grid.

Physical conversion (docs/model.md "Physical conversion"): with the drive frequency ``f`` known,
``omega_s = 2π f t_c`` gives the time scale ``t_c = omega_s / (2π f)``; time in seconds is
``t · t_c`` and the rotor speed in rad/s is ``Ω · R_φ Φ0 / t_c``. With ``Φ0`` unknown the speed
scale ``R_φ Φ0 / t_c`` is a free parameter of its own (``log10_speed_scale``).

An ensemble member (docs/model.md "Long-run statistics of chaotic motion") is one run of the engine
from the rotor at rest in contact at ``t = 0`` with restitution noise ``σ_e`` on its own stream
``(seed, member)``, sampled on the measured curve's uniform time grid, plus Gaussian measurement
noise of the curve's ``σ`` from a fixed stream per member (common random numbers: the same draw at
every parameter point, so the objective is a smooth function of the parameters wherever the
ensemble mean is).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..engine import EngineConfig, InitialState, simulate_arrays
from ..engine.loads import row_trajectories
from ..io.records import TrajColumn
from ..io.runup_curves import MotorCurve
from ..model.engine_config import motor_config

#: Search range of every search coordinate.
BOUNDS: dict[str, tuple[float, float]] = {
    "e": (0.05, 0.95),
    "log10_r_phi": (-4.0, -1.0),
    "psi": (-math.pi, math.pi),
    "omega_s": (1.05, 4.0),
    "log10_speed_scale": (-4.0, 3.0),
    # the restitution noise, when fitted: from the deterministic limit (members coincide) to 10 %
    "e_sigma": (0.0, 0.1),
}

#: Noise stream offset of the measurement noise added to members (independent of the engine's).
_NOISE_STREAM = 0x5EED

#: The model's restitution noise ``σ_e`` (docs/model.md "Long-run statistics of chaotic motion")
#: where the fit does not read it from the point: the search's scan (the noise is fitted from
#: there on), a synthetic curve's and a fit that states it. Real impacts scatter their
#: restitution by percent; at 3 % the members of a chaotic ensemble mix within a few
#: milliseconds of a motor's run-up, so one measured curve is a typical member and the
#: ensemble statistics are smooth in the parameters (at ``σ_e = 1e-9`` a 0.12 s run stays on
#: its round-off-chosen orbit: a 1e-6 change of ``e`` moved its steady speed by 6 %).
MODEL_E_SIGMA = 0.03

#: A synthetic curve's restitution-noise seed is its measurement-noise seed plus this offset, so
#: the two noise streams of one curve differ.
RESTITUTION_SEED_OFFSET = 1_000_000

#: Every member's start: at rest in contact at ``t = 0`` (docs/model.md "Initial condition").
START = InitialState(t=0.0, omega=0.0)


def param_names(curve: MotorCurve, fit_e_sigma: bool = False) -> list[str]:
    """Search coordinates: ``e, log10 R_φ, ψ, omega_s`` (+ ``log10`` speed scale if Φ0 is unknown,
    + the restitution noise ``e_sigma`` when it is fitted rather than stated)."""
    names = ["e", "log10_r_phi", "psi", "omega_s"]
    if curve.phi0_rad is None:
        names.append("log10_speed_scale")
    if fit_e_sigma:
        names.append("e_sigma")
    return names


def restitution_noise(theta: dict[str, float], stated: float) -> float:
    """``σ_e`` of a parameter point: its own when fitted (``theta["e_sigma"]``), else ``stated``."""
    return float(theta.get("e_sigma", stated))


def physical(theta: dict[str, float], curve: MotorCurve) -> dict[str, float]:
    """Nondimensional parameters and SI scales of a parameter point (docs/model.md, conversion).

    Returns ``e, r_phi, psi, omega_s``, the time scale ``t_c`` (s) and ``speed_scale`` (rad/s
    per unit of nondimensional ``Ω``).
    """
    w = theta["omega_s"]
    r_phi = 10.0 ** theta["log10_r_phi"]
    t_c = w / (2.0 * math.pi * curve.drive_frequency_hz)
    if curve.phi0_rad is not None:
        scale = r_phi * curve.phi0_rad / t_c
    else:
        scale = 10.0 ** theta["log10_speed_scale"]
    return {
        "e": theta["e"],
        "r_phi": r_phi,
        "psi": theta["psi"],
        "omega_s": w,
        "t_c": t_c,
        "speed_scale": scale,
    }


def uniform_grid(curve: MotorCurve) -> np.ndarray:
    """The uniform time grid (s) the statistics are computed on: ``t0 + k·dt`` up to the end."""
    dt = curve.dt
    n = int(math.floor((curve.time[-1] - curve.time[0]) / dt + 1e-9)) + 1
    return curve.time[0] + dt * np.arange(n)


@dataclass(frozen=True)
class EnsembleSpec:
    """How model members are made: restitution noise, seed and the measurement noise added."""

    e_sigma: float = MODEL_E_SIGMA  # stated; a fitted point's own ``e_sigma`` overrides it
    seed: int = 0
    cores: int = 1


def thread_map(
    fn: Callable, items: Sequence, cores: int, on_done: Callable[[int], None] | None = None
) -> list:
    """``[fn(item) …]`` on ``cores`` threads, in order; stops promptly when interrupted.

    On any exception in the caller's thread (a SIGINT or SIGTERM arrives as
    ``KeyboardInterrupt``, or an item's error) the items not started are cancelled and the
    pool is not waited for, so a stopped fit ends after the members already running, not after
    every member queued. ``on_done(k)`` is called in the caller's thread after the ``k``-th
    result (progress of a long evaluation).
    """
    pool = ThreadPoolExecutor(max_workers=cores)
    out = []
    try:
        for k, value in enumerate(pool.map(fn, items), start=1):
            out.append(value)
            if on_done is not None:
                on_done(k)
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)
    return out


def _member_config(
    theta: dict[str, float],
    curve: MotorCurve,
    member: int,
    e_sigma: float,
    seed: int,
    grid: np.ndarray,
) -> EngineConfig:
    """The engine configuration of one member at ``theta`` sampled on the curve's ``grid``."""
    p = physical(theta, curve)
    t_c = p["t_c"]
    dt_nd = curve.dt / t_c
    span_nd = (grid[-1] - grid[0]) / t_c
    return motor_config(
        p["e"],
        p["omega_s"],
        p["r_phi"],
        p["psi"],
        t_end=span_nd + 0.5 * dt_nd,
        max_events=50_000_000,
        traj_dt=dt_nd,
        traj_t0=0.0,
        traj_t1=span_nd + 0.5 * dt_nd,
        e_sigma=e_sigma,
        seed=seed,
        member=member,
    )


def _on_grid(traj: np.ndarray, theta: dict[str, float], curve: MotorCurve, n: int) -> np.ndarray:
    """A run's ``Ω`` samples in rad/s on the curve's grid of ``n`` times (the last held if the
    run ended)."""
    om = traj[:n, TrajColumn.OMEGA] * physical(theta, curve)["speed_scale"]
    if len(om) < n:
        om = np.concatenate([om, np.full(n - len(om), om[-1] if len(om) else 0.0)])
    return om


def simulate_curve(
    theta: dict[str, float],
    curve: MotorCurve,
    member: int = 0,
    e_sigma: float = 0.0,
    seed: int = 0,
) -> np.ndarray:
    """Noise-free model rotor speed (rad/s) of one member on the curve's uniform grid.

    The run starts at ``t = 0`` with the rotor at rest in contact (docs/model.md "Initial
    condition") and samples ``Ω`` at ``(grid − grid[0]) / t_c``; ``e_sigma = 0`` is the single
    deterministic run.
    """
    return _simulated([theta], curve, member, e_sigma, seed, uniform_grid(curve))[0]


def _simulated(
    thetas: Sequence[dict[str, float]],
    curve: MotorCurve,
    member: int,
    e_sigma: float,
    seed: int,
    grid: np.ndarray,
) -> list[np.ndarray]:
    """:func:`simulate_curve` of each of ``thetas`` on the curve's ``grid``, bit for bit.

    Several points must share ``e``, ``omega_s`` and ``σ_e``: they differ in ``R_φ``, ``ψ`` and
    the speed scale, none of which the axial motion uses (docs/model.md "Events"), so one impact
    search serves them all (:func:`bouncedisk.engine.loads.row_trajectories`); one point is its
    own run.
    """
    cfgs = [_member_config(th, curve, member, e_sigma, seed, grid) for th in thetas]
    if len(cfgs) == 1:
        trajs = [simulate_arrays(cfgs[0], START).traj]
    else:
        trajs = row_trajectories(cfgs, START)
    return [_on_grid(tr, th, curve, len(grid)) for tr, th in zip(trajs, thetas, strict=True)]


@functools.lru_cache(maxsize=512)
def measurement_noise(n: int, sigma: float, seed: int, member: int) -> np.ndarray:
    """The fixed measurement-noise draw of member ``member`` (standard deviation ``sigma``),
    drawn once (read-only: the same draw at every parameter point)."""
    if sigma <= 0:
        out = np.zeros(n)
    else:
        out = np.random.default_rng([_NOISE_STREAM, seed, member]).normal(0.0, sigma, n)
    out.flags.writeable = False
    return out


def member_records(
    theta: dict[str, float], curve: MotorCurve, members: range, spec: EnsembleSpec, reduce=None
) -> list:
    """Members ``members`` at ``theta`` as measured records (model + measurement noise).

    ``reduce(record)`` (if given) is applied to each record on the worker thread, so only the
    reduced values are kept. Members run on ``spec.cores`` threads (the kernel releases the GIL).
    """
    return [rows[0] for rows in rows_records([theta], curve, members, spec, reduce)]


def rows_records(
    thetas: Sequence[dict[str, float]],
    curve: MotorCurve,
    members: range,
    spec: EnsembleSpec,
    reduce=None,
) -> list[list]:
    """:func:`member_records` of points that share ``e``, ``omega_s`` and ``σ_e``, by member
    (``out[m][i]``: member ``members[m]`` at ``thetas[i]``), each member one axial run
    (:func:`_simulated`).

    At ``σ_e = 0`` (the deterministic limit) the members' runs are the same, bit for bit: a
    member's stream only draws the restitution noise (docs/model.md, "Long-run statistics of
    chaotic motion"), and its measurement noise is added after the run. So one run serves every
    member there.
    """
    grid = uniform_grid(curve)
    e_sigma = restitution_noise(thetas[0], spec.e_sigma)
    shared = None
    if e_sigma == 0.0 and len(members) > 0:
        shared = _simulated(thetas, curve, members[0], 0.0, spec.seed, grid)

    def one(m: int) -> list:
        noise = measurement_noise(len(grid), curve.sigma, spec.seed, m)
        oms = (
            shared if shared is not None else _simulated(thetas, curve, m, e_sigma, spec.seed, grid)
        )
        return [reduce(om + noise) if reduce is not None else om + noise for om in oms]

    if spec.cores <= 1 or len(members) == 1:
        return [one(m) for m in members]
    return thread_map(one, members, spec.cores)


def synthesize_curve(
    true: dict[str, float],
    drive_frequency_hz: float,
    phi0_rad: float,
    span_s: float,
    dt_s: float,
    sigma: float,
    seed: int,
    member: int | None = None,
    e_sigma: float = MODEL_E_SIGMA,
) -> pd.DataFrame:
    """A synthetic measured curve: one model run at ``true`` plus Gaussian noise ``sigma`` (rad/s).

    Parameters
    ----------
    true : dict
        ``e, r_phi, psi, omega_s`` (docs/model.md "Variables and scales").
    drive_frequency_hz, phi0_rad : float
        The motor constants of the physical conversion (docs/model.md).
    span_s, dt_s : float
        Record length and sampling interval (s); samples at ``k·dt_s`` from ``t = 0``.
    sigma : float
        Measurement noise (rad/s), drawn from ``default_rng(seed)``.
    seed : int
        Noise seed; the restitution-noise stream is ``(RESTITUTION_SEED_OFFSET + seed, member)``.
    member : int or None
        Ensemble member with restitution noise ``e_sigma`` (a realization of the model that a
        fit of ensemble statistics can reproduce); ``None``: the single deterministic run
        (``e_sigma`` ignored), a round-off-chosen orbit (docs/model.md "Long-run statistics").
    e_sigma : float
        Restitution noise ``σ_e`` of the member (default :data:`MODEL_E_SIGMA`).
    """
    n = int(math.floor(span_s / dt_s + 1e-9)) + 1
    t = dt_s * np.arange(n)
    dummy = MotorCurve(
        time=t,
        omega=np.zeros(n),
        sigma=0.0,
        drive_frequency_hz=drive_frequency_hz,
        phi0_rad=phi0_rad,
        source="",
        synthetic=True,
        path="",
    )
    theta = {
        "e": true["e"],
        "log10_r_phi": math.log10(true["r_phi"]),
        "psi": true["psi"],
        "omega_s": true["omega_s"],
    }
    # the curve's uniform grid, unless its step (the median of t's) rounds a sample in or out
    grid = uniform_grid(dummy)
    grid = grid if len(grid) == n else t
    if member is None:
        om = _simulated([theta], dummy, 0, 0.0, 0, grid)[0]
    else:
        om = _simulated([theta], dummy, member, e_sigma, RESTITUTION_SEED_OFFSET + seed, grid)[0]
    rng = np.random.default_rng(seed)
    om_noisy = om + rng.normal(0.0, sigma, n)
    return pd.DataFrame({"time_s": t, "omega_rad_s": om_noisy, "sigma_rad_s": np.full(n, sigma)})
