"""Errors a user can cause, reported as one clear line (docs/formats.md: exit status 2)."""

from __future__ import annotations


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
