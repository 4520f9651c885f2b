"""The ``bouncedisk`` command: one module per subcommand.

The only place that parses argv and prints; :mod:`.command` holds the entry point, :func:`main`.
"""

from __future__ import annotations

from .command import main

__all__ = ["main"]
