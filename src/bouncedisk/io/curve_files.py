"""What the run-up and load-curve files share (docs/formats.md): the sidecar's ``units`` and
``motor`` fields, the CSV header's column names and a numeric column's checks, one rule each.

Every problem raises :class:`~bouncedisk.model.errors.InputError` naming the file and the field
(``units.speed``, ``motor.Phi0_rad``) or the column and its row (``speed_rad_s: row 5``).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pandas as pd

from ..model import limits
from ..model.errors import InputError, plain
from ..model.params import number

#: The unit each quantity of a curve is stated in, with the spellings accepted for it.
UNITS = {
    "time": ("s", {"s", "second", "seconds", "sec"}),
    "omega": ("rad/s", {"rad/s", "rad s-1", "rad.s-1", "rad s^-1"}),
    "speed": ("rad/s", {"rad/s", "rad s-1", "rad.s-1", "rad s^-1"}),
    "torque": ("N m", {"n m", "nm", "n.m", "n*m", "n·m", "newton metre", "newton meter"}),
}
#: How to convert a quantity given in another unit.
_HINTS = {
    "time": "convert to seconds",
    "omega": "convert to rad/s (rpm × 2π/60)",
    "speed": "convert to rad/s (rpm × 2π/60)",
    "torque": "convert to N m (mN m × 1e-3)",
}
#: The motor constants a sidecar may state, each with its bound.
MOTOR_FIELDS = {
    "drive_frequency_hz": limits.DRIVE_FREQUENCY_HZ,
    "Phi0_rad": limits.PHI0_RAD,
    "U0_m": limits.U0_M,
}


def check_units(src: str, units: object, quantities: tuple[str, ...]) -> None:
    """A sidecar's ``units``: each of ``quantities`` stated in its unit of :data:`UNITS`."""
    wanted = ", ".join(f"{q}: {UNITS[q][0]}" for q in quantities)
    if not isinstance(units, dict):
        raise InputError(src, "units", f"is required: {{{wanted}}}")
    for key in units:
        if key not in quantities:
            raise InputError(src, f"units.{key}", f"unknown key (known: {', '.join(quantities)})")
    for key in quantities:
        unit, allowed = UNITS[key]
        u = units.get(key)
        if not isinstance(u, str) or " ".join(u.lower().split()) not in allowed:
            raise InputError(src, f"units.{key}", f"must be {unit!r}, got {u!r}; {_HINTS[key]}")


def group_keys(src: str, name: str, group: object, fields: dict, absent: str) -> None:
    """Check that a sidecar's group ``name`` (``motor``, ``rotor``) is a mapping of known keys.

    Raises
    ------
    InputError
        ``name`` not a mapping (message ``absent``), or a key not among ``fields``.
    """
    if not isinstance(group, dict):
        raise InputError(src, name, absent)
    for k in group:
        if k not in fields:
            raise InputError(src, f"{name}.{k}", f"unknown key (known: {', '.join(fields)})")


def read_motor(src: str, motor: object, required: tuple[str, ...]) -> dict[str, float]:
    """A sidecar's ``motor``: the constants of :data:`MOTOR_FIELDS` it states, each within its
    bound, ``required`` among them; returned as floats."""
    group_keys(src, "motor", motor, MOTOR_FIELDS, f"is required, with {', '.join(required)}")
    out = {}
    for k, bound in MOTOR_FIELDS.items():
        if motor.get(k) is None:
            if k in required:
                raise InputError(src, f"motor.{k}", "is required")
            continue
        out[k] = bound.check(src, f"motor.{k}", number(src, f"motor.{k}", motor[k]))
    return out


#: The keys of each kind of curve's sidecar (docs/formats.md, "Run-up curves", "Load curves").
SIDECAR_KEYS = {
    "run-up": ("source", "synthetic", "units", "motor", "noise_sigma_rad_s", "description",
               "generating_parameters", "generator"),
    "load curve": ("source", "synthetic", "units", "motor", "rotor", "preload_N", "window_s",
                   "protocol", "description", "generating_parameters", "generator", "repeats"),
}  # fmt: skip
#: How ``bouncedisk fit`` takes a curve of each kind.
GIVEN_AS = {"run-up": "before the options", "load curve": "after a --load"}


def check_sidecar_keys(src: str, data: dict, kind: str) -> None:
    """Refuse a key the sidecar of a ``kind`` curve does not know, in one line; a key of the
    other kind's says which kind the file looks like and how to give it."""
    known = SIDECAR_KEYS[kind]
    for k in data:
        if k in known:
            continue
        other = next((o for o, keys in SIDECAR_KEYS.items() if o != kind and k in keys), None)
        hint = f"; it is a {other}'s key: give that curve {GIVEN_AS[other]}" if other else ""
        raise InputError(src, str(k), f"unknown key (known: {', '.join(known)}){hint}")


def read_table(path: Path, columns: tuple[str, ...]) -> pd.DataFrame:
    """A curve's CSV with its header's names stripped; a column of ``columns`` given twice is
    refused (read from the header itself: ``note.1`` is a column of its own)."""
    src = str(path)
    try:
        df = pd.read_csv(path, comment="#", skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as ex:
        raise InputError(src, "", f"not a readable CSV: {str(ex).splitlines()[0]}") from None
    names, _ = _layout(path)
    for name in columns:
        if names.count(name) > 1:
            raise InputError(src, name, "the column appears more than once; keep one")
    df.columns = [str(c).strip() for c in df.columns]
    return df


def _layout(path: str | Path) -> tuple[list[str], list[int]]:
    """The column names of a CSV's header (its first line that is not blank or a comment), as
    written, and the file's line numbers (from 1) of the lines after it that pandas reads as
    rows: every line but a blank one and one that starts with ``#``."""
    names: list[str] | None = None
    lines = []
    with open(path, encoding="utf-8-sig", newline="") as fh:
        for number, line in enumerate(fh, start=1):
            if not line.strip() or line.startswith("#"):
                continue
            if names is None:
                names = [c.strip() for c in next(csv.reader([line.split("#", 1)[0]]))]
            else:
                lines.append(number)
    return names or [], lines


def row_label(src: str, df: pd.DataFrame, row: int) -> str:
    """Where data row ``row`` (from 0) of ``df``, the table :func:`read_table` read from
    ``src``, is, for an error: ``row N``, N the file's line (comment and blank lines counted),
    or ``data row N`` where the lines cannot be matched to the rows (a quoted field over two
    lines). Read only when an error is raised."""
    lines = _layout(src)[1]
    return f"row {lines[row]}" if len(lines) == len(df) else f"data row {row + 1}"


def column(
    df: pd.DataFrame, src: str, col: str, largest: tuple[float, str] | None = None
) -> np.ndarray:
    """A numeric column: every row a finite number, in magnitude at most ``largest[0]`` (which
    ``largest[1]`` explains) when given; one line naming the row otherwise."""
    raw = df[col]
    is_bool = raw.map(lambda x: isinstance(x, bool)).to_numpy()
    if raw.dtype == bool or is_bool.any():
        row = int(np.argmax(is_bool))
        raise InputError(
            src, col, f"{row_label(src, df, row)}: not a number: {plain(raw.iloc[row])}"
        )
    values = pd.to_numeric(raw, errors="coerce")
    bad = values.isna() & raw.notna()
    if bad.any():
        row = int(np.argmax(bad.values))
        raise InputError(
            src, col, f"{row_label(src, df, row)}: not a number: {plain(raw.iloc[row])}"
        )
    x = values.to_numpy(dtype=float)
    finite = np.isfinite(x)
    if not finite.all():
        row = int(np.argmax(~finite))
        raise InputError(src, col, f"{row_label(src, df, row)}: missing or non-finite value")
    if largest is not None and np.any(np.abs(x) > largest[0]):
        row = int(np.argmax(np.abs(x) > largest[0]))
        message = f"{row_label(src, df, row)}: {x[row]:g} exceeds {largest[0]:.4g} ({largest[1]})"
        raise InputError(src, col, message + "; check the units")
    return x


def stated_u0(sidecar: dict) -> float | None:
    """The axial amplitude ``motor.U0_m`` (m) a curve's sidecar states (checked by
    :func:`read_motor`), ``None`` if none."""
    value = (sidecar.get("motor") or {}).get("U0_m")
    return None if value is None else float(value)
