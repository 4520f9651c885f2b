"""The engine's records, named: run status, event kinds, trajectory and stroboscopic columns;
and the one rule for a number in a JSON summary (:func:`json_number`).

The compiled kernel (:mod:`bouncedisk.engine.kernel`) returns integer codes and plain array
columns; this module is the one public place that names them, with values taken from the
kernel's own constants (:mod:`bouncedisk.engine.layout`, which imports no numba), so that no
code outside the engine uses a raw code or a column number.

For example ``res.traj[:, TrajColumn.OMEGA]`` is the rotor angular velocity at the samples,
and ``res.status_code == RunStatus.REST`` says the rotor rides the stator for ever.
"""

from __future__ import annotations

import math
from enum import IntEnum

from ..engine import layout as _K
from ..engine.layout import OK_STATUSES, STATUS_TEXT

__all__ = [
    "KIND_NAMES",
    "json_number",
    "EventKind",
    "RunStatus",
    "StrobeColumn",
    "TrajColumn",
]


class RunStatus(IntEnum):
    """Why a run ended (``RunResult.status_code``; the text is the file's ``status``)."""

    EVENTS = _K.ST_EVENTS  # the requested number of events was reached
    TIME = _K.ST_TIME  # the requested end time was reached
    REST = _K.ST_REST  # the rotor stays in contact for ever: no further impact
    NEED_CONTACT = _K.ST_NEED_CONTACT  # the dynamics need the 'contact' effect, left out
    NUMERICAL = _K.ST_NUMERICAL  # an event search failed or made no progress

    @property
    def text(self) -> str:
        """The status as written to a file's ``status`` attribute."""
        return STATUS_TEXT[self.value]

    @property
    def ok(self) -> bool:
        """The run ended as asked: events or time reached, or the rotor at rest."""
        return self.value in OK_STATUSES


class EventKind(IntEnum):
    """Kind of an event row (docs/model.md "Events"); the netCDF ``kind`` flag values."""

    IMPACT = _K.KIND_IMPACT  # one impact
    CHATTER = _K.KIND_CHATTER  # the accumulated tail of a complete chattering sequence


#: CF ``flag_meanings`` of the ``kind`` variable, in :class:`EventKind` order.
KIND_NAMES = " ".join(k.name.lower() for k in EventKind)


class TrajColumn(IntEnum):
    """Columns of a dense trajectory (``RunResult.traj``, ``Chunk.traj``)."""

    T = _K.TR_T  # time t
    U = _K.TR_U  # rotor axial position u
    V = _K.TR_V  # rotor axial velocity v
    U_STATOR = _K.TR_U_STATOR  # stator axial position u_s (eq. 1)
    OMEGA = _K.TR_OMEGA  # rotor angular velocity Ω


class StrobeColumn(IntEnum):
    """Columns of the stroboscopic section (``RunResult.strobe``, ``Chunk.strobe``)."""

    PERIOD = _K.SB_PERIOD  # stator period index
    T = _K.SB_T  # time of the sample (phase 0)
    U = _K.SB_U  # rotor axial position
    V = _K.SB_V  # rotor axial velocity
    OMEGA = _K.SB_OMEGA  # rotor angular velocity


if len(TrajColumn) != _K.TRAJ_COLS or len(StrobeColumn) != _K.STROBE_COLS:  # pragma: no cover
    raise ImportError("bouncedisk.io.records is out of step with the kernel's column counts")


def json_number(value: object) -> float | None:
    """A number as a JSON summary holds it: a finite float, or ``None`` (JSON has no NaN or
    infinity) for NaN and infinities."""
    x = float(value)
    return x if math.isfinite(x) else None
