"""Errors a user can cause, reported as one clear line (docs/formats.md: exit status 2).

The class lives in the engine, the lowest layer, so that the engine's own entry points
(:class:`~bouncedisk.engine.EngineConfig`, :class:`~bouncedisk.engine.InitialState`) refuse bad
input with it; :mod:`bouncedisk.model.errors` is where the rest of the package imports it from.
"""

from __future__ import annotations

import math
from numbers import Integral, Real

import numpy as np


class InputError(ValueError):
    """Bad input: a file or value the user supplied is malformed or out of range.

    Parameters
    ----------
    source : str
        The file (or ``--set`` option, or ``<argument>``) the bad value came from.
    field : str
        Dotted name of the offending field (``parameters.e``), or a short description.
    message : str
        What is wrong, in one line.
    """

    def __init__(self, source: str, field: str, message: str):
        self.source = str(source)
        self.field = field
        self.message = message
        super().__init__(self.line())

    def line(self) -> str:
        """The one-line report ``SOURCE: FIELD: MESSAGE``."""
        where = f"{self.source}: " if self.source else ""
        fld = f"{self.field}: " if self.field else ""
        return f"{where}{fld}{self.message}"


def error_line(text: str) -> str:
    """The line every error a user can cause prints on stderr: ``bouncedisk: error: TEXT``
    (docs/formats.md), for the commands, the pipeline's jobs and the Snakefile alike."""
    return f"bouncedisk: error: {text}"


def plain(value: object) -> str:
    """``value`` as a message shows it: a number as the user would write it (``8e-05``, ``3``,
    ``1e+13``, ``nan``, ``True``; every digit when ``:g`` would round it), not its numpy type
    (``np.float64(8e-05)``); anything else by ``repr``."""
    if isinstance(value, bool | np.bool_):
        return str(bool(value))
    if isinstance(value, Integral):
        return str(int(value))
    if isinstance(value, Real):
        x = float(value)
        if not math.isfinite(x):
            return str(x)
        short = f"{x:g}"
        return short if float(short) == x else repr(x)
    return repr(value)
