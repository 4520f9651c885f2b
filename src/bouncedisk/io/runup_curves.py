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
      U0_m: 1.0e-6                  # optional: axial amplitude (a fit's curves: all or none)
    noise_sigma_rad_s: 0.1          # optional: the noise, if the CSV has no sigma_rad_s column

The units, the motor fields and each column are checked as a load curve's
(:mod:`bouncedisk.io.curve_files`), within the bounds of :mod:`bouncedisk.model.limits`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..model import limits
from ..model.errors import InputError
from ..model.params import number
from ..model.scene import read_yaml
from .curve_files import check_sidecar_keys, check_units, column, read_motor, read_table, row_label
from .output_checks import sidecar_of

#: Fewest rows of a run-up: as many as the fit's statistics need.
MIN_ROWS = limits.MIN_RUNUP_SAMPLES
#: The measurement noise may not exceed this multiple of the data's own standard deviation (the
#: data are signal plus noise: their variance is at least the noise's).
MAX_NOISE_OVER_SPREAD = 2.0
#: The columns a run-up CSV may hold.
COLUMNS = ("time_s", "omega_rad_s", "sigma_rad_s")


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
    """Read and validate a curve's YAML sidecar (units, motor and noise within their bounds)."""
    src = str(path)
    data = read_yaml(path, "curve sidecar")
    check_sidecar_keys(src, data, "run-up")
    check_units(src, data.get("units"), ("time", "omega"))
    motor = read_motor(src, data.get("motor"), required=("drive_frequency_hz",))
    if data.get("noise_sigma_rad_s") is not None:
        sigma = number(src, "noise_sigma_rad_s", data["noise_sigma_rad_s"], nonneg=True)
        largest, why = _speed_bound(motor)
        if sigma > largest:
            message = f"{sigma:g} rad/s exceeds {largest:.4g} ({why}); check the units"
            raise InputError(src, "noise_sigma_rad_s", message)
    if "synthetic" in data and not isinstance(data["synthetic"], bool):
        raise InputError(src, "synthetic", f"must be true or false, got {data['synthetic']!r}")
    if not isinstance(data.get("source", ""), str):
        raise InputError(src, "source", "must be text")
    return data


def _speed_bound(motor: dict[str, float]) -> tuple[float, str]:
    """The largest speed a run-up may hold (:func:`bouncedisk.model.limits.max_speed`) and why."""
    f, phi0 = motor["drive_frequency_hz"], motor.get("Phi0_rad")
    stated = f"Phi0 = {phi0:g} rad" if phi0 is not None else "Phi0 unknown, taken at pi rad"
    why = (
        f"{limits.SPEED_MARGIN:g} times the stator's peak angular speed 2 pi f Phi0 at "
        f"f = {f:g} Hz, {stated}: the fastest friction can turn the rotor"
    )
    return limits.max_speed(f, phi0), why


def _measurement_noise(src: str, side: str, column: np.ndarray | None, stated) -> float:
    """The curve's one measurement noise (rad/s): the mean of its ``sigma_rad_s`` column, else
    the sidecar's ``noise_sigma_rad_s``, else 0. Given both, they must agree to 1 %: the noise is
    one fact, and a sidecar that disagrees with its CSV is refused rather than ignored."""
    if column is None:
        return 0.0 if stated is None else float(stated)
    if np.any(column < 0):
        raise InputError(src, "sigma_rad_s", "must be >= 0")
    sigma = float(np.mean(column))
    if stated is not None and not np.isclose(stated, sigma, rtol=0.01, atol=0.0):
        raise InputError(
            side,
            "noise_sigma_rad_s",
            f"{stated:g} rad/s disagrees with the mean of {src}'s sigma_rad_s column "
            f"({sigma:g} rad/s): state the noise once, or the same in both",
        )
    return sigma


def read_curve(path: str | Path, sidecar: str | Path | None = None) -> MotorCurve:
    """Read and validate a curve CSV and its sidecar.

    Raises
    ------
    InputError
        Missing file or column, text in a number column, NaN, a time or speed beyond its bound
        (:mod:`bouncedisk.model.limits`), non-increasing time, fewer than :data:`MIN_ROWS` rows,
        negative sigma, wrong units in the sidecar.
    """
    p = Path(path)
    src = str(path)
    side = Path(sidecar) if sidecar else sidecar_of(p)
    if not p.is_file():
        raise InputError(src, "", "file not found")
    if not side.is_file():
        raise InputError(str(side), "", "sidecar not found (units, source and motor constants)")
    meta = read_sidecar(side)
    df = read_table(p, COLUMNS)
    for col in ("time_s", "omega_rad_s"):
        if col not in df.columns:
            raise InputError(src, col, f"missing column (have: {', '.join(df.columns)})")
    motor = meta["motor"]
    speed = _speed_bound(motor)
    t = column(df, src, "time_s", (limits.TIME_S.high, "time stamps within about 300 years"))
    omega = column(df, src, "omega_rad_s", speed)
    s = column(df, src, "sigma_rad_s", speed) if "sigma_rad_s" in df.columns else None
    dt = np.diff(t)
    if np.any(dt <= 0):
        row = int(np.argmax(dt <= 0))
        raise InputError(
            src, "time_s", f"{row_label(src, df, row + 1)}: time must increase strictly"
        )
    if len(t) < MIN_ROWS:
        raise InputError(src, "time_s", f"has {len(t)} rows; the fit needs at least {MIN_ROWS}")
    sigma = _measurement_noise(src, str(side), s, meta.get("noise_sigma_rad_s"))
    spread = float(np.std(omega))
    if sigma > MAX_NOISE_OVER_SPREAD * spread:
        where = (src, "sigma_rad_s") if s is not None else (str(side), "noise_sigma_rad_s")
        raise InputError(
            *where,
            f"measurement noise {sigma:g} rad/s exceeds {MAX_NOISE_OVER_SPREAD:g} "
            f"times the spread of the data themselves ({spread:g} rad/s)",
        )
    return MotorCurve(
        time=t,
        omega=omega,
        sigma=sigma,
        drive_frequency_hz=motor["drive_frequency_hz"],
        phi0_rad=motor.get("Phi0_rad"),
        source=str(meta.get("source", "")),
        synthetic=bool(meta.get("synthetic", False)),
        path=src,
        sidecar=meta,
        sidecar_path=str(side),
    )


def write_curve(df: pd.DataFrame, path: str | Path, sidecar: dict) -> None:
    """Write a curve CSV (full precision) and its YAML sidecar, each atomically."""
    import yaml

    from .atomic import atomic_path, write_text_atomic

    p = Path(path)
    with atomic_path(p, suffix=".csv") as tmp:
        df.to_csv(tmp, index=False, float_format="%.17g", lineterminator="\n")
    write_text_atomic(p.with_suffix(".yaml"), yaml.safe_dump(sidecar, sort_keys=False))
