"""The exact event-driven engine (numba): no I/O, no xarray.

Public entry points: :class:`EngineConfig`, :class:`InitialState`, :func:`iterate` (chunked,
streaming) and :func:`simulate_arrays` (in memory).
"""

from .driver import (
    Chunk,
    EngineConfig,
    EngineError,
    InitialState,
    RunResult,
    iterate,
    simulate_arrays,
)
from .kernel import KIND_CHATTER, KIND_IMPACT

__all__ = [
    "Chunk",
    "EngineConfig",
    "EngineError",
    "InitialState",
    "RunResult",
    "iterate",
    "simulate_arrays",
    "KIND_IMPACT",
    "KIND_CHATTER",
]
