"""Bounds of the values a user states: one definition of each rule, read by the command line, the
files' readers and schemas and the library.

A :class:`Bound` checks a number that has been read (:func:`bouncedisk.model.params.number`
refuses text, NaN and infinities first) and names where it came from: the option on the command
line (``--e-sigma``), the field in a file (``parameters.e_sigma``, ``motor.Phi0_rad``).

The bounds of measured curves (docs/formats.md "Run-up curves", "Load curves") are physical: far
beyond any motor the model describes, so that a value past them is a unit or typing mistake, and
well inside the floating-point range, so that the fit's sums of squares stay finite.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..engine.bounds import MAX_E_SIGMA
from .errors import InputError, plain


def _text(x: float) -> str:
    """A bound's end as written: ``0.5``, ``10,000``, ``1e+09``."""
    if float(x).is_integer() and abs(x) < 1e7:
        return f"{int(x):,}"
    return f"{x:g}"


@dataclass(frozen=True)
class Bound:
    """The interval ``[low, high]`` (an end ``open`` excludes it) a stated value must lie in."""

    low: float
    high: float
    low_open: bool = False
    high_open: bool = False

    def __contains__(self, x: float) -> bool:
        above = x > self.low if self.low_open else x >= self.low
        below = x < self.high if self.high_open else x <= self.high
        return bool(above and below)

    def text(self) -> str:
        """``in [0, 0.5]``, ``in (0, 1)``, ``in [40, 10,000]``."""
        left, right = "(" if self.low_open else "[", ")" if self.high_open else "]"
        return f"in {left}{_text(self.low)}, {_text(self.high)}{right}"

    def check(self, source: str, name: str, value: float) -> float:
        """``value`` itself when it lies in the bound.

        Raises
        ------
        InputError
            Naming ``source`` and ``name`` (the option or the file's field).
        """
        if value not in self:
            raise InputError(source, name, f"must be {self.text()}, got {plain(value)}")
        return value


# ---------------------------------------------------------------- model and fit settings

#: Restitution noise ``σ_e`` of the per-impact restitution ``e + σ_e ξ``: the engine's bound.
E_SIGMA = Bound(0.0, MAX_E_SIGMA)
#: Block-bootstrap resamples of a fit: a 95 % percentile interval needs a 2.5 % tail of at least
#: one resample (40); 10,000 resolve its ends to well under a percent.
BOOTSTRAP_RANGE = Bound(40, 10_000)
#: The basins' settle tolerance, a fraction of the largest mean speed (docs/formats.md "Basins").
SETTLE_RANGE = Bound(0.0, 1.0, low_open=True, high_open=True)
#: Fewest samples of a run-up: the fit's statistics (trend, ripple, a block bootstrap of blocks
#: of at least 20 samples, at least 10 blocks) need 200.
MIN_RUNUP_SAMPLES = 200

# ---------------------------------------------------------------- measured curves (SI units)

#: Drive frequency (Hz): above it no mechanical resonator drives a rotor by friction (ultrasonic
#: motors run at 20 kHz to a few MHz); below it a stator of amplitude at most :data:`U0_M` cannot
#: lift its rotor off (peak acceleration ``(2π f)² U0 < g``: no impacts, docs/model.md).
DRIVE_FREQUENCY_HZ = Bound(0.1, 1e9)
#: Torsional amplitude Φ0 (rad) of the stator: a small angle, at most half a turn.
PHI0_RAD = Bound(0.0, math.pi, low_open=True)
#: Axial amplitude U0 (m) of the stator: at most a metre.
U0_M = Bound(0.0, 1.0, low_open=True)
#: Rotor mass (kg): from a nanogram to ten tonnes.
ROTOR_MASS_KG = Bound(1e-12, 1e4)
#: Rotor radius of gyration and contact radius (m): from a nanometre to ten metres.
ROTOR_RADIUS_M = Bound(1e-9, 10.0)
#: Spring preload (N), acting as extra gravity.
PRELOAD_N = Bound(0.0, 1e6)
#: Readings averaged in one row of a load curve.
REPEATS = Bound(1, 1_000_000)
#: Time stamps (s) of a run-up: epoch-like stamps (1.7e9 s) are accepted, centuries are not.
TIME_S = Bound(-1e10, 1e10)
#: Largest friction coefficient a contact may have: beyond any dry-friction pair (about 1-2).
MAX_FRICTION_COEFFICIENT = 10.0
#: Largest load torque in units of the friction torque ``μ m_r g_eff r_eff``: a hundred times the
#: momentum bound on the stall torque (docs/model.md "The motor under load").
MAX_LOAD = 100.0
#: A measured speed may exceed the fastest the stator can drive the rotor (:func:`max_speed`) by
#: noise, not by this factor.
SPEED_MARGIN = 10.0
#: Gravity (m/s²) on a curve's rotor, as :meth:`~bouncedisk.model.params.PhysicalParameters.
#: from_nondimensional` takes it.
GRAVITY = 9.81


def max_speed(
    drive_frequency_hz: float,
    phi0_rad: float | None,
    load_torque_nm: float = 0.0,
    duration_s: float = 0.0,
    inertia_kg_m2: float = math.inf,
) -> float:
    """The largest rotor speed (rad/s) a measured curve may hold: :data:`SPEED_MARGIN` times the
    fastest the motor can turn its rotor.

    Friction drives the rotor towards the stator's angular velocity, whose peak is
    ``2π f Φ0`` (docs/model.md), so a rotor started from rest turns at most about that fast (an
    impact's friction impulse may overshoot the slip it removes: hence the margin); a constant
    load torque ``T`` can turn it backwards at most ``T t / J_r`` faster within ``t``. An unknown
    ``Φ0`` (``None``) is taken at its bound :data:`PHI0_RAD`.
    """
    phi0 = PHI0_RAD.high if phi0_rad is None else phi0_rad
    drive = 2.0 * math.pi * drive_frequency_hz * phi0
    return SPEED_MARGIN * (drive + load_torque_nm * duration_s / inertia_kg_m2)


def max_load_torque(mass_kg: float, preload_n: float, contact_radius_m: float) -> float:
    """The largest load torque (N·m) a load curve may state: :data:`MAX_LOAD` friction torques
    ``μ m_r g_eff r_eff`` at the friction coefficient :data:`MAX_FRICTION_COEFFICIENT`
    (``g_eff = g + F/m_r``, ``r_eff = 2 r_c / 3``; docs/model.md "The motor under load")."""
    g_eff = GRAVITY + preload_n / mass_kg
    friction = MAX_FRICTION_COEFFICIENT * mass_kg * g_eff * 2.0 * contact_radius_m / 3.0
    return MAX_LOAD * friction
