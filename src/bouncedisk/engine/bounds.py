"""The bounds of every state and configuration the engine runs, checked before the kernel runs.

One place for the rule, used by the engine's entry points (:class:`~.driver.EngineConfig`,
:class:`~.driver.InitialState`, :func:`~.driver.simulate_arrays`, :func:`~.driver.iterate`) and
by the scene files (:mod:`bouncedisk.model.scene`, :mod:`bouncedisk.model.params`); every
violation is an :class:`~.errors.InputError` naming the field (docs/formats.md "State bounds").

Where the bounds come from (docs/model.md "Things that are easy to get wrong"):

- **The phase accumulator.** The kernel keeps time as a whole number of stator periods ``n``
  (int64) and a phase ``θ ∈ [0, 2π)``, exact however long the run. A phase it derives from a
  time, ``ω_s t`` (the start, the stop, the trajectory's first sample) or ``ω_s τ`` (a flight
  of length ``τ``), is one floating-point product reduced modulo ``2π``, rounded by up to
  ``2⁻⁵³ ω_s t``. :data:`PHASE_MAX` ``= 2⁴²`` rad keeps that below ``2⁻¹¹`` rad (5e-4 rad,
  1e-4 of a period): the stator's position ``sin(ω_s t)`` right to 5e-4 of its amplitude, and
  an event time ``t = (2πn + θ)/ω_s`` written as a double resolves 1e-4 of a period. Near
  ``2⁵²`` rad a double no longer tells one period from the next: impact times stop increasing
  and the reduced phase leaves ``[0, 2π)`` (a flight from ``v = 1e50``), and beyond ``2⁶³``
  the period count overflows (``t = 1e300``).
- **The longest flight.** A rotor at height ``u >= -1`` with velocity ``v`` has the energy of a
  flight that leaves the band ``|u| <= 1`` at ``sqrt(v² + 2(u + 1))`` and lasts
  ``τ = 2 sqrt(v² + 2(u + 1))`` (gravity is 1); the kernel crosses it in one phase step, so
  ``ω_s τ <= PHASE_MAX``. The stator itself launches the rotor at up to ``(1 + e) ω_s <= 2 ω_s``
  (its velocity amplitude is ``ω_s``), a flight of up to ``4 ω_s``: ``4 ω_s² <= PHASE_MAX``
  gives :data:`OMEGA_S_MAX` ``= 2²⁰`` (about 1e6).
- **The energies.** The energy audit squares ``v`` and ``Ω`` (``v²/2``, ``Ω²/2``) and sums
  them over a run: :data:`MAX_SPEED` ``= 1e100`` keeps the squares (1e200) far from overflow
  (1.8e308, reached at 1.3e154).
- **The stator's scales.** ``ω_s²`` (the stator's peak acceleration in ``g``) and ``1/ω_s²``
  (the stator position where contact ends, docs/model.md "Events") must be normal doubles:
  :data:`OMEGA_S_MIN` ``= 2⁻⁵⁰⁰`` (3e-151; at 1e-300, ``ω_s²`` is 0 and ``1/ω_s²`` a division
  by zero).
- **Counts.** ``max_events`` is the kernel's int64 counter: a whole number in
  ``[1, 2⁶³ − 1]``, not a boolean; the trajectory's sample index too.
"""

from __future__ import annotations

import math
from numbers import Integral, Real
from typing import Any

import numpy as np

from .errors import InputError, plain

#: Largest stator phase ``ω_s t`` (rad) the engine derives from a time in one rounding.
PHASE_MAX = 2.0**42
#: Largest ``omega_s``: the longest flight the stator launches, ``4 ω_s``, within PHASE_MAX.
OMEGA_S_MAX = 2.0**20
#: Smallest ``omega_s``: ``ω_s²`` and ``1/ω_s²`` normal doubles.
OMEGA_S_MIN = 2.0**-500
#: Largest ``|u|``, ``|v|`` and ``|Ω|``: their squares in the energy audit far from overflow.
MAX_SPEED = 1e100
#: Largest ``max_events``: the kernel's int64 event counter.
MAX_EVENTS = 2**63 - 1
#: Largest ``|psi|``: the torsional phase enters ``sin(omega_s t + psi)``, so it must keep the
#: phase's precision like a time does; 1e3 rad is far beyond any angle a user means.
MAX_PSI = 1e3
#: Largest restitution noise ``σ_e`` of ``e + σ_e ξ`` (docs/model.md): half the whole range of
#: ``e`` is the most a noise can mean (0 is the deterministic limit).
MAX_E_SIGMA = 0.5
#: Largest trajectory sample index (int64, with room for the kernel's sums).
MAX_SAMPLE_INDEX = 2.0**62


def is_real(x: Any) -> bool:
    """A real number (Python or numpy), not a boolean."""
    t = type(x)
    if t is float or t is int:  # the common case, without the slower checks of the ABCs
        return True
    return isinstance(x, Real) and not isinstance(x, bool | np.bool_)


def is_count(x: Any, low: int, high: int) -> bool:
    """A whole number (Python or numpy int, not a boolean) in ``[low, high]``."""
    if type(x) is int or (isinstance(x, Integral) and not isinstance(x, bool)):
        return low <= x <= high
    return False


def finite(source: str, field: str, x: Any, limit: float = math.inf) -> float:
    """``x`` as a float when it is a finite real number with ``|x| <= limit``."""
    if type(x) is float and math.isfinite(x) and abs(x) <= limit:  # the common case
        return x
    if not is_real(x) or not math.isfinite(x):
        raise InputError(source, field, f"must be a finite number, got {plain(x)}")
    if abs(x) > limit:
        raise InputError(
            source,
            field,
            f"must be within ±{limit:g} (its square in the energy audit stays far from "
            f'overflow; docs/formats.md "State bounds"), got {plain(x)}',
        )
    return float(x)


def check_omega_s(source: str, field: str, w: Any) -> float:
    """``omega_s`` in ``[OMEGA_S_MIN, OMEGA_S_MAX]`` (module docstring)."""
    if not is_real(w) or not OMEGA_S_MIN <= w <= OMEGA_S_MAX:
        raise InputError(
            source,
            field,
            f"must be a number in [2**-500, 2**20] (about [3e-151, 1.05e6]), got {plain(w)}: "
            "outside, the stator's acceleration omega_s**2 underflows, or the flights it "
            "launches (4 omega_s long) sweep more stator phase than a double resolves",
        )
    return float(w)


def check_time(source: str, field: str, t: Any, w: float, inf_ok: bool = False) -> float:
    """A time whose stator phase ``|ω_s t| <= PHASE_MAX`` (``inf`` too when ``inf_ok``)."""
    if not is_real(t) or math.isnan(t) or (math.isinf(t) and not inf_ok):
        what = "a number or inf" if inf_ok else "a finite number"
        raise InputError(source, field, f"must be {what}, got {plain(t)}")
    if math.isfinite(t) and abs(w * t) > PHASE_MAX:
        raise InputError(
            source,
            field,
            f"{plain(t)} is beyond the times a run resolves at omega_s = {plain(w)}: "
            f"|t| <= 2**42/omega_s = {PHASE_MAX / w:.4g} (the stator phase omega_s*t to 5e-4 "
            'rad; docs/formats.md "State bounds")' + ("; inf for no time stop" if inf_ok else ""),
        )
    return float(t)


def flight_length(u: float, v: float) -> float:
    """The longest flight the rotor's energy allows from height ``u`` and velocity ``v``
    (module docstring): ``2 sqrt(v² + 2(u + 1))``."""
    return 2.0 * math.sqrt(v * v + 2.0 * max(u + 1.0, 0.0))


#: How far below the stator's surface (units of U0) a start in flight may be: a millionth of the
#: stator's amplitude, a start on the surface given to a few digits (it lands at once); a start
#: inside the stator is a mistake.
SURFACE_TOLERANCE = 1e-6


def check_state(
    source: str,
    prefix: str,
    w: float,
    state: tuple[Any, Any, Any, Any],
) -> None:
    """A state ``(t, omega, u, v)`` (``u, v`` ``None`` for a start in contact) the engine can
    run at ``omega_s = w``: every value finite, ``|t|`` within the phase bound, ``|Ω|``, ``|u|``,
    ``|v|`` within :data:`MAX_SPEED`, a start in flight given both ``u`` and ``v`` with the rotor
    on or above the stator (``u >= u_s(t) = sin(w t)`` to :data:`SURFACE_TOLERANCE`, eq. 1), and
    the flight the rotor's energy allows within the phase bound.

    ``prefix`` leads the field names (``initial.`` in a scene, empty for the API).
    """
    t, omega, u, v = state
    check_time(source, f"{prefix}t", t, w)
    finite(source, f"{prefix}omega", omega, MAX_SPEED)
    if u is None and v is None:
        return
    if u is None or v is None:
        name = "u" if u is None else "v"
        raise InputError(source, f"{prefix}{name}", "give both u and v to start in flight")
    finite(source, f"{prefix}u", u, MAX_SPEED)
    finite(source, f"{prefix}v", v, MAX_SPEED)
    us = math.sin(w * t)
    if u < us - SURFACE_TOLERANCE:
        raise InputError(
            source, f"{prefix}u", f"must be >= u_s(t) = {us:.12g} (rotor above the stator)"
        )
    tau = flight_length(u, v)
    if w * tau > PHASE_MAX:
        half = PHASE_MAX / (2.0 * w)  # the largest sqrt(v**2 + 2(u + 1))
        if v * v > 2.0 * abs(u + 1.0):
            name, value = "v", v
            most = f"|v| <= {math.sqrt(max(half * half - 2.0 * max(u + 1.0, 0.0), 0.0)):.4g}"
        else:
            name, value = "u", u
            most = f"u <= {max(0.5 * (half * half - v * v) - 1.0, -1.0):.4g}"
        raise InputError(
            source,
            f"{prefix}{name}",
            f"{plain(value)} starts a flight of about {tau:.3g} time units, "
            f"{w * tau / (2.0 * math.pi):.3g} stator periods at omega_s = {plain(w)}, more than "
            f"a run resolves (the stator phase omega_s*tau <= 2**42 rad): {most} here "
            '(docs/formats.md "State bounds")',
        )


#: The ranges of :class:`~.driver.EngineConfig`'s fields other than ``omega_s`` and its times
#: (:func:`check_config`), with what each must be.
_RANGES: dict[str, tuple[Any, str]] = {
    "e": (lambda x: is_real(x) and 0.0 <= x <= 1.0, "must be a number in [0, 1]"),
    "r_phi": (lambda x: is_real(x) and 0.0 < x < math.inf, "must be a finite number > 0"),
    "psi": (
        lambda x: is_real(x) and abs(x) <= MAX_PSI,
        f"must be an angle in radians, |psi| <= {MAX_PSI:g}",
    ),
    "inertia_ratio": (
        lambda x: is_real(x) and x > 0.0,
        "must be > 0 (inf for a stator not moved by impacts)",
    ),
    "mu_ratio": (lambda x: is_real(x) and 1.0 <= x < math.inf, "must be a finite number >= 1"),
    "tol": (lambda x: is_real(x) and 0.0 < x < math.inf, "must be a finite number > 0"),
    "max_events": (
        lambda x: is_count(x, 1, MAX_EVENTS),
        "must be a whole number in [1, 2**63 - 1] (not a boolean)",
    ),
    "traj_dt": (lambda x: is_real(x) and 0.0 <= x < math.inf, "must be a finite number >= 0"),
    "e_sigma": (
        lambda x: is_real(x) and 0.0 <= x <= MAX_E_SIGMA,
        f"must be in [0, {MAX_E_SIGMA:g}]",
    ),
    "seed": (lambda x: is_count(x, 0, 2**63 - 1), "must be a whole number in [0, 2**63)"),
    "member": (lambda x: is_count(x, 0, 2**63 - 1), "must be a whole number in [0, 2**63)"),
    # the engine also runs a driving torque (< 0)
    "load_torque": (lambda x: is_real(x) and math.isfinite(x), "must be a finite number"),
}
#: The switches of :class:`~.driver.EngineConfig`.
_FLAGS = ("contact", "torsion", "impulse_cap", "stroboscopic", "clipped")


def check_config(cfg: Any, source: str = "EngineConfig") -> None:
    """Refuse a configuration the kernel cannot run (:class:`~.driver.EngineConfig`): a ``nan``
    or an out-of-range value would make its event searches spin without end (``e = nan``,
    ``omega_s = 1e300``) or return garbage, instead of failing."""
    for name, (ok, text) in _RANGES.items():
        value = getattr(cfg, name)
        if not ok(value):
            raise InputError(source, name, f"{text}, got {plain(value)}")
    for name in _FLAGS:
        value = getattr(cfg, name)
        if not (value is True or value is False or isinstance(value, np.bool_) or value in (0, 1)):
            raise InputError(source, name, f"must be true or false, got {plain(value)}")
    w = check_omega_s(source, "omega_s", cfg.omega_s)
    check_time(source, "t_end", cfg.t_end, w, inf_ok=True)
    check_time(source, "traj_t0", cfg.traj_t0, w)
    check_time(source, "traj_t1", cfg.traj_t1, w, inf_ok=True)
    check_time(source, "stats_from", cfg.stats_from, w, inf_ok=True)


def check_run(cfg: Any, init: Any, source: str = "InitialState") -> None:
    """The initial state ``init`` can run under ``cfg`` (:func:`check_state`), and the
    trajectory's first sample index fits the kernel's counter."""
    check_state(source, "", cfg.omega_s, (init.t, init.omega, init.u, init.v))
    if cfg.traj_dt > 0.0 and abs(init.t - cfg.traj_t0) / cfg.traj_dt > MAX_SAMPLE_INDEX:
        raise InputError(
            "EngineConfig",
            "traj_dt",
            f"{plain(cfg.traj_dt)} puts more than 2**62 samples between traj_t0 = "
            f"{plain(cfg.traj_t0)} and the start t = {plain(init.t)}",
        )
