"""Measured velocity–time curves: CSV + YAML sidecar, read and validated.

CSV columns: ``time_s`` (strictly increasing, seconds), ``omega_rad_s`` (rotor angular velocity,
rad/s), optional ``sigma_rad_s`` (measurement standard deviation). The sidecar (same name,
``.yaml``) states units, the source, and the motor constants that are known::

    source: "bench test of prototype #2, encoder at 50 kHz"
    synthetic: false
    units: {time: s, omega: rad/s}
    motor:
      drive_frequency_hz: 20000.0   # required: sets omega_s = 2π f t_c
      Phi0_rad: 2.0e-4              # optional: torsional amplitude; fixes the speed scale
    noise_sigma_rad_s: 0.1          # optional, if the CSV has no sigma_rad_s column
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..model.errors import InputError
from ..model.params import number
from ..model.scene import read_yaml
from .output_checks import sidecar_of

MIN_ROWS = 20
#: Largest torsional amplitude Φ0 (rad) a sidecar may state: half a turn (docs/model.md's Φ0 is a
#: small torsion angle of the stator; anything larger is a unit mistake).
MAX_PHI0_RAD = 3.141592653589793
#: The measurement noise may not exceed this multiple of the data's own standard deviation (the
#: data are signal plus noise: their variance is at least the noise's).
MAX_NOISE_OVER_SPREAD = 2.0
UNIT_ALIASES = {
    "time": {"s", "second", "seconds", "sec"},
    "omega": {"rad/s", "rad s-1", "rad.s-1", "rad s^-1"},
}


@dataclass(frozen=True)
class MotorCurve:
    """A validated measured curve and what is known about the motor."""

    time: np.ndarray  # s
    omega: np.ndarray  # rad/s
    sigma: float  # measurement noise standard deviation, rad/s (0 if unknown)
    drive_frequency_hz: float
    phi0_rad: float | None
    source: str
    synthetic: bool
    path: str
    sidecar: dict = field(default_factory=dict, compare=False)
    sidecar_path: str = field(default="", compare=False)

    @property
    def dt(self) -> float:
        """Sampling interval (s): the median step, or the mean step ``(t_last − t_first)/(n − 1)``
        when the stamps are uniform but quantized (median and mean differ by more than 1e-9 but
        less than 1 %).

        Epoch-like stamps (1e9 s) carry their steps only to their last bit (1.2e-7 s), which moves
        the median step by up to a percent; the mean does not depend on the time origin. Stamps
        written from ``k·dt`` keep their median step (the shipped curve's generator used it).
        """
        t = self.time
        mean = float(t[-1] - t[0]) / (len(t) - 1)
        median = float(np.median(np.diff(t)))
        return mean if 1e-9 * mean < abs(median - mean) <= 0.01 * mean else median


def read_sidecar(path: str | Path) -> dict:
    """Read and validate a curve's YAML sidecar."""
    src = str(path)
    data = read_yaml(path, "curve sidecar")
    known = {
        "source",
        "synthetic",
        "units",
        "motor",
        "noise_sigma_rad_s",
        "description",
        "generating_parameters",
        "generator",
    }
    for k in data:
        if k not in known:
            raise InputError(src, str(k), f"unknown key (known: {', '.join(sorted(known))})")
    units = data.get("units")
    if not isinstance(units, dict):
        raise InputError(src, "units", "is required: {time: s, omega: rad/s}")
    for key, allowed in UNIT_ALIASES.items():
        u = units.get(key)
        if not isinstance(u, str) or u.strip().lower() not in allowed:
            hint = "convert to seconds" if key == "time" else "convert to rad/s (rpm × 2π/60)"
            raise InputError(
                src, f"units.{key}", f"must be {sorted(allowed)[0]!r}, got {u!r}; {hint}"
            )
    motor = data.get("motor")
    if not isinstance(motor, dict):
        raise InputError(src, "motor", "is required, with at least drive_frequency_hz")
    for k in motor:
        if k not in ("drive_frequency_hz", "Phi0_rad", "U0_m"):
            raise InputError(
                src, f"motor.{k}", "unknown key (known: drive_frequency_hz, Phi0_rad, U0_m)"
            )
    if "drive_frequency_hz" not in motor:
        raise InputError(src, "motor.drive_frequency_hz", "is required")
    number(src, "motor.drive_frequency_hz", motor["drive_frequency_hz"], positive=True)
    if motor.get("Phi0_rad") is not None:
        phi0 = number(src, "motor.Phi0_rad", motor["Phi0_rad"], positive=True)
        if phi0 > MAX_PHI0_RAD:
            raise InputError(src, "motor.Phi0_rad", f"must be at most pi rad (a torsional "
                             f"amplitude), got {phi0:g}; is it in radians?")  # fmt: skip
    if motor.get("U0_m") is not None:
        number(src, "motor.U0_m", motor["U0_m"], positive=True)
    if data.get("noise_sigma_rad_s") is not None:
        number(src, "noise_sigma_rad_s", data["noise_sigma_rad_s"], nonneg=True)
    if "synthetic" in data and not isinstance(data["synthetic"], bool):
        raise InputError(src, "synthetic", f"must be true or false, got {data['synthetic']!r}")
    if not isinstance(data.get("source", ""), str):
        raise InputError(src, "source", "must be text")
    return data


def read_curve(path: str | Path, sidecar: str | Path | None = None) -> MotorCurve:
    """Read and validate a curve CSV and its sidecar.

    Raises
    ------
    InputError
        Missing file or column, text in a number column, NaN, non-increasing time, fewer than 20
        rows, negative sigma, wrong units in the sidecar.
    """
    p = Path(path)
    src = str(path)
    side = Path(sidecar) if sidecar else sidecar_of(p)
    if not p.is_file():
        raise InputError(src, "", "file not found")
    if not side.is_file():
        raise InputError(str(side), "", "sidecar not found (units, source and motor constants)")
    meta = read_sidecar(side)
    try:
        df = pd.read_csv(p, comment="#", skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as ex:
        raise InputError(src, "", f"not a readable CSV: {str(ex).splitlines()[0]}") from None
    df.columns = [str(c).strip() for c in df.columns]
    _check_header(src, list(df.columns))
    for col in ("time_s", "omega_rad_s"):
        if col not in df.columns:
            raise InputError(src, col, f"missing column (have: {', '.join(df.columns)})")
    cols = ["time_s", "omega_rad_s"] + (["sigma_rad_s"] if "sigma_rad_s" in df.columns else [])
    for col in cols:
        if df[col].dtype == bool or df[col].map(lambda v: isinstance(v, bool)).any():
            row = int(np.argmax(df[col].map(lambda v: isinstance(v, bool)).to_numpy()))
            raise InputError(src, col, f"row {row + 2}: not a number: {df[col].iloc[row]!r}")
        values = pd.to_numeric(df[col], errors="coerce")
        bad = values.isna() & df[col].notna()
        if bad.any():
            row = int(np.argmax(bad.values))
            raise InputError(src, col, f"row {row + 2}: not a number: {df[col].iloc[row]!r}")
        if values.isna().any() or not np.isfinite(values.values).all():
            row = int(np.argmax(~np.isfinite(values.values)))
            raise InputError(src, col, f"row {row + 2}: missing or non-finite value")
        df[col] = values.astype(float)
    if len(df) < MIN_ROWS:
        raise InputError(src, "", f"has {len(df)} rows; at least {MIN_ROWS} are needed")
    t = df["time_s"].to_numpy()
    dt = np.diff(t)
    if np.any(dt <= 0):
        row = int(np.argmax(dt <= 0))
        raise InputError(src, "time_s", f"row {row + 3}: time must increase strictly")
    sigma = 0.0
    if "sigma_rad_s" in df.columns:
        s = df["sigma_rad_s"].to_numpy()
        if np.any(s < 0):
            raise InputError(src, "sigma_rad_s", "must be >= 0")
        sigma = float(np.mean(s))
    elif meta.get("noise_sigma_rad_s") is not None:
        sigma = float(meta["noise_sigma_rad_s"])
    omega = df["omega_rad_s"].to_numpy()
    spread = float(np.std(omega))
    if sigma > MAX_NOISE_OVER_SPREAD * spread:
        where = (
            (src, "sigma_rad_s")
            if "sigma_rad_s" in df.columns
            else (str(side), "noise_sigma_rad_s")
        )
        raise InputError(*where, f"measurement noise {sigma:g} rad/s exceeds {MAX_NOISE_OVER_SPREAD:g} "
                         f"times the spread of the data themselves ({spread:g} rad/s)")  # fmt: skip
    motor = meta["motor"]
    return MotorCurve(
        time=t,
        omega=omega,
        sigma=sigma,
        drive_frequency_hz=float(motor["drive_frequency_hz"]),
        phi0_rad=float(motor["Phi0_rad"]) if motor.get("Phi0_rad") is not None else None,
        source=str(meta.get("source", "")),
        synthetic=bool(meta.get("synthetic", False)),
        path=src,
        sidecar=meta,
        sidecar_path=str(side),
    )


def _check_header(src: str, columns: list[str]) -> None:
    """Refuse a column the reader would otherwise pick one of several of (pandas renames a
    repeated ``omega_rad_s`` to ``omega_rad_s.1`` and the first would be used silently)."""
    for c in columns:
        base, dot, tail = c.rpartition(".")
        if (
            dot
            and tail.isdigit()
            and base in columns
            and base in ("time_s", "omega_rad_s", "sigma_rad_s")
        ):
            raise InputError(src, base, "the column appears more than once; keep one")


def write_curve(df: pd.DataFrame, path: str | Path, sidecar: dict) -> None:
    """Write a curve CSV (full precision) and its YAML sidecar, each atomically."""
    import yaml

    from .atomic import atomic_path, write_text_atomic

    p = Path(path)
    with atomic_path(p, suffix=".csv") as tmp:
        df.to_csv(tmp, index=False, float_format="%.17g", lineterminator="\n")
    write_text_atomic(p.with_suffix(".yaml"), yaml.safe_dump(sidecar, sort_keys=False))
