"""``python -m bouncedisk``: the ``bouncedisk`` command (:mod:`bouncedisk.cli`), as the console
script runs it."""

from __future__ import annotations

import sys

from .cli.command import main

if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
