"""``python -m bouncedisk.cli``: the command, as the console script runs it."""

from __future__ import annotations

import sys

from .command import main

if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
