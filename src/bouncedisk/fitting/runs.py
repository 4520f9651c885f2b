"""Repeated run-ups of one motor, fitted together.

One run-up of a chaotic motor is one realization of the model (docs/model.md "Long-run statistics of
chaotic motion"): its own steady speed and time constant scatter between realizations by more
than a useful fit may be off (7.6 % and tens of percent for the chaotic recovery case of
``tests/test_fitting.py``, 0.06 s records). An experimenter repeats the run-up; ``M`` run-ups of
one motor are ``M`` independent realizations, and the mean of their statistics scatters ``√M``
times less. The fit then compares the runs' mean statistics with the model's ensemble mean, with
covariance ``C (1/M + 1/K)`` (:mod:`.objective`).

The runs must be the same experiment: the same motor constants (drive frequency, Φ0, U0), the same
measurement noise and the same sampling (interval and length), each starting from rest.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from ..io.curve_files import stated_u0
from ..io.runup_curves import MotorCurve
from ..model.errors import InputError


def _same(a: float | None, b: float | None) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return math.isclose(a, b, rel_tol=1e-9, abs_tol=0.0)


def _text(v: float | None) -> str:
    return "unknown" if v is None else f"{v:.6g}"


def check_runs(curves: Sequence[MotorCurve]) -> None:
    """Raise :class:`InputError` naming the first run that differs from the first run (its
    sidecar for a ``motor`` field, its CSV otherwise).

    Compared: ``drive_frequency_hz``, ``Phi0_rad`` and ``U0_m`` (the sidecar's ``motor``), the measurement
    noise ``sigma``, the sampling interval, the number of samples and the start time.
    """
    first = curves[0]

    def where(c: MotorCurve, name: str) -> str:
        return (c.sidecar_path or c.path) if name.startswith("motor.") else c.path

    for c in curves[1:]:
        checks = (
            ("motor.drive_frequency_hz", first.drive_frequency_hz, c.drive_frequency_hz),
            ("motor.Phi0_rad", first.phi0_rad, c.phi0_rad),
            ("motor.U0_m", stated_u0(first.sidecar), stated_u0(c.sidecar)),
            ("sigma_rad_s", first.sigma, c.sigma),
            ("time_s (sampling interval)", first.dt, c.dt),
            ("time_s (start)", float(first.time[0]), float(c.time[0])),
        )
        for name, want, got in checks:
            if not _same(want, got):
                raise InputError(
                    where(c, name),
                    name,
                    f"is {_text(got)}, but {_text(want)} in {where(first, name)}: "
                    "the run-ups of one fit must come from one motor and one "
                    "measurement set-up",
                )
        if len(c.time) != len(first.time):
            raise InputError(
                c.path,
                "time_s",
                f"has {len(c.time)} samples, {first.path} has "
                f"{len(first.time)}: the run-ups of one fit must be equally long",
            )


def mean_curve(curves: Sequence[MotorCurve]) -> MotorCurve:
    """The runs' mean speed on the first run's time (``sigma`` stays the noise of one run)."""
    if len(curves) == 1:
        return curves[0]
    omega = np.mean([c.omega for c in curves], axis=0)
    return dataclasses.replace(curves[0], omega=omega)
