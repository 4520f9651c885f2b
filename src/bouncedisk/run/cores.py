"""The cores this process may use (its CPU affinity)."""

from __future__ import annotations

import os


def available_cores() -> int:
    """Cores this process may use (its CPU affinity)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1
