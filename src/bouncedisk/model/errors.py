"""Errors a user can cause, reported as one clear line (docs/formats.md: exit status 2).

:class:`InputError` is defined with the engine (:mod:`bouncedisk.engine.errors`), whose entry
points refuse bad input with it too; this is the name the rest of the package uses.
"""

from __future__ import annotations

from ..engine.errors import InputError, error_line, plain

__all__ = ["InputError", "error_line", "plain"]
