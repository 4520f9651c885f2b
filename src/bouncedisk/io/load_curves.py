"""Measured load curves: speed against load torque, CSV + YAML sidecar, read and validated.

docs/formats.md: CSV columns ``torque_Nm`` (load torque, N·m, >= 0, no repeats), ``speed_rad_s``
(mean rotor speed, rad/s) and optional ``speed_sd_rad_s`` (spread of repeated readings). The
sidecar (same stem, ``.yaml``) holds the drive as a run-up's does, the rotor and the window::

    source: "bench test of prototype #2, brake at constant current"
    synthetic: false
    units: {torque: N m, speed: rad/s}
    motor: {drive_frequency_hz: 20000.0, Phi0_rad: 2.0e-4}
    rotor: {m_r_kg: 0.01, r_g_m: 0.004, r_c_m: 0.002}
    preload_N: 0.77                  # optional (a spring preload acts as extra gravity)
    window_s: [0.06, 0.12]           # each reading: mean speed over [t0, t1] after a start from rest
    repeats: 5                       # optional: readings averaged per row (default 1)
    protocol: "5 repeats per load"   # informative

The torque scale ``μ m_r g_eff r_eff`` follows from the rotor and the fitted ``R_φ``
(docs/model.md: ``R_φ = (r_eff/r_g)² μ / R_d``; :meth:`bouncedisk.model.params.PhysicalParameters.
from_nondimensional`), so a load curve is predicted by the model at any ``(e, ω_s, R_φ, ψ)``:
:func:`bouncedisk.studies.torque_speed.readings_from_rest`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..model import limits
from ..model.errors import InputError, plain
from ..model.params import number, whole_number
from ..model.scene import read_yaml
from .curve_files import (
    check_sidecar_keys,
    check_units,
    column,
    group_keys,
    read_motor,
    read_table,
    row_label,
)
from .output_checks import sidecar_of

COLUMNS = ("torque_Nm", "speed_rad_s")
OPTIONAL_COLUMNS = ("speed_sd_rad_s",)
#: The rotor's fields, each with its bound.
ROTOR_FIELDS = {
    "m_r_kg": limits.ROTOR_MASS_KG,
    "r_g_m": limits.ROTOR_RADIUS_M,
    "r_c_m": limits.ROTOR_RADIUS_M,
}
ROTOR_KEYS = tuple(ROTOR_FIELDS)
MIN_LOADS = 3
#: Most loads (rows) a curve may hold: as many as the samples of a fitted run-up.
MAX_LOADS = 12_000
#: Latest end of the window, in drive periods: as long as a fitted run-up
#: (each reading is a run of the model from rest to ``window_s[1]``).
MAX_WINDOW_PERIODS = 20_000


@dataclass(frozen=True)
class LoadCurveData:
    """A validated measured load curve and the motor constants it states (SI units)."""

    torque: np.ndarray  # N·m, increasing
    speed: np.ndarray  # rad/s
    speed_sd: np.ndarray | None  # rad/s, spread of repeated readings
    drive_frequency_hz: float
    phi0_rad: float
    rotor: dict[str, float]
    preload_n: float
    window_s: tuple[float, float]
    synthetic: bool
    path: str
    sidecar: dict = field(default_factory=dict, compare=False)


def _sidecar(path: Path) -> dict:
    """Read and check a load curve's sidecar (one line naming the file and field); ``motor``,
    ``rotor``, ``preload_N`` and ``window_s`` come back as floats."""
    src = str(path)
    data = read_yaml(path, "load curve sidecar")
    check_sidecar_keys(src, data, "load curve")
    check_units(src, data.get("units"), ("torque", "speed"))
    data["motor"] = read_motor(src, data.get("motor"), ("drive_frequency_hz", "Phi0_rad"))
    data["rotor"] = _rotor(src, data.get("rotor"))
    preload = number(src, "preload_N", data.get("preload_N", 0.0), nonneg=True)
    data["preload_N"] = limits.PRELOAD_N.check(src, "preload_N", preload)
    data["window_s"] = _window(src, data.get("window_s"), data["motor"]["drive_frequency_hz"])
    if isinstance(data.get("repeats"), str):  # a quoted '5' is text, as a scene's members
        raise InputError(
            src, "repeats", f"must be a whole number, got the text {data['repeats']!r}"
        )
    if "repeats" in data:  # 5.0 reads as 5, as a scene's members
        repeats = whole_number(src, "repeats", data["repeats"], minimum=1)
        data["repeats"] = limits.REPEATS.check(src, "repeats", repeats)
    if not isinstance(data.get("synthetic", False), bool):
        raise InputError(src, "synthetic", f"must be true or false, got {data['synthetic']!r}")
    return data


def _rotor(src: str, rotor: object) -> dict[str, float]:
    """The sidecar's ``rotor``: every field of :data:`ROTOR_FIELDS`, each within its bound."""
    group_keys(src, "rotor", rotor, ROTOR_FIELDS, f"is required: {{{', '.join(ROTOR_KEYS)}}}")
    out = {}
    for k, bound in ROTOR_FIELDS.items():
        if k not in rotor:
            raise InputError(src, f"rotor.{k}", "is required")
        out[k] = bound.check(src, f"rotor.{k}", number(src, f"rotor.{k}", rotor[k]))
    return out


def _window(src: str, win: object, drive_frequency_hz: float) -> tuple[float, float]:
    """The sidecar's ``window_s``: ``[t0, t1]``, ``t1 > t0 >= 0``, ending within
    :data:`MAX_WINDOW_PERIODS` drive periods."""
    if not isinstance(win, list) or len(win) != 2:
        raise InputError(src, "window_s", "is required: [t0, t1] in seconds after the start")
    t0 = number(src, "window_s[0]", win[0], nonneg=True)
    t1 = number(src, "window_s[1]", win[1], positive=True)
    if not t1 > t0:
        raise InputError(src, "window_s", f"must have t1 > t0, got {win}")
    periods = t1 * drive_frequency_hz
    if periods > MAX_WINDOW_PERIODS:
        raise InputError(
            src,
            "window_s[1]",
            f"{t1:g} s is {periods:.4g} drive periods; a reading may last at most "
            f"{MAX_WINDOW_PERIODS:,} periods ({MAX_WINDOW_PERIODS / drive_frequency_hz:.4g} s "
            "at this drive), as a fitted run-up",
        )
    return t0, t1


def _bounds(meta: dict, torque: np.ndarray | None = None) -> tuple[float, str]:
    """The largest load torque the rotor allows or, given the torques, the largest speed (each
    with why: :mod:`bouncedisk.model.limits`)."""
    rotor, motor, t1 = meta["rotor"], meta["motor"], meta["window_s"][1]
    if torque is None:
        largest = limits.max_load_torque(rotor["m_r_kg"], meta["preload_N"], rotor["r_c_m"])
        why = (
            f"{limits.MAX_LOAD:g} friction torques mu m_r g_eff r_eff of this rotor at "
            f"mu = {limits.MAX_FRICTION_COEFFICIENT:g}"
        )
        return largest, why
    inertia = rotor["m_r_kg"] * rotor["r_g_m"] ** 2
    f, phi0, most = (
        motor["drive_frequency_hz"],
        motor["Phi0_rad"],
        float(np.max(torque, initial=0.0)),
    )
    why = (
        f"{limits.SPEED_MARGIN:g} times the stator's peak angular speed 2 pi f Phi0 at "
        f"f = {f:g} Hz, Phi0 = {phi0:g} rad, plus what the largest load torque turns the rotor "
        f"backwards within window_s, {most:g} N m x {t1:g} s / J_r"
    )
    return limits.max_speed(f, phi0, most, t1, inertia), why


def read_load_curve(path: str | Path) -> LoadCurveData:
    """Read and validate a load curve CSV and its sidecar (module docstring).

    Raises
    ------
    InputError
        One line naming the file, row and column: a missing file, sidecar, column or rotor key;
        text, NaN or a negative value where a torque or spread is due; a torque or speed beyond
        what the rotor and drive allow (:mod:`bouncedisk.model.limits`); a repeated torque;
        fewer than :data:`MIN_LOADS` or more than :data:`MAX_LOADS` loads; a bad window (ending
        past :data:`MAX_WINDOW_PERIODS` drive periods) or unit.
    """
    p = Path(path)
    src = str(path)
    side = sidecar_of(p)
    if not p.is_file():
        raise InputError(src, "", "file not found")
    if not side.is_file():
        raise InputError(str(side), "", "sidecar not found (motor, rotor and window_s)")
    meta = _sidecar(side)
    df = read_table(p, (*COLUMNS, *OPTIONAL_COLUMNS))
    for col in COLUMNS:
        if col not in df.columns:
            raise InputError(src, col, f"missing column (have: {', '.join(df.columns)})")
    torque = column(df, src, "torque_Nm", _bounds(meta))
    speed_bound = _bounds(meta, torque)
    speed = column(df, src, "speed_rad_s", speed_bound)
    sd = column(df, src, "speed_sd_rad_s", speed_bound) if "speed_sd_rad_s" in df.columns else None
    for name, values in (("torque_Nm", torque), ("speed_sd_rad_s", sd)):
        if values is not None and np.any(values < 0):
            row = int(np.argmax(values < 0))
            raise InputError(
                src, name, f"{row_label(src, df, row)}: must be >= 0, got {plain(values[row])}"
            )
    _, first = np.unique(torque, return_index=True)
    if len(first) < len(torque):
        row = int(np.setdiff1d(np.arange(len(torque)), first)[0])
        raise InputError(
            src,
            "torque_Nm",
            f"{row_label(src, df, row)}: repeats the load torque {plain(torque[row])}",
        )
    if len(torque) < MIN_LOADS:
        raise InputError(src, "", f"has {len(torque)} loads; at least {MIN_LOADS} are needed")
    if len(torque) > MAX_LOADS:
        raise InputError(
            src,
            "",
            f"has {len(torque):,} loads; at most {MAX_LOADS:,} (as the samples of a run-up)",
        )
    order = np.argsort(torque)
    return LoadCurveData(
        torque=torque[order],
        speed=speed[order],
        speed_sd=None if sd is None else sd[order],
        drive_frequency_hz=meta["motor"]["drive_frequency_hz"],
        phi0_rad=meta["motor"]["Phi0_rad"],
        rotor=dict(meta["rotor"]),
        preload_n=meta["preload_N"],
        window_s=meta["window_s"],
        synthetic=bool(meta.get("synthetic", False)),
        path=src,
        sidecar=meta,
    )
