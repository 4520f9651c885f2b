"""The exact event-driven engine (numba): no I/O, no xarray.

Public entry points: :class:`EngineConfig`, :class:`InitialState`, :func:`iterate` (chunked,
streaming) and :func:`simulate_arrays` (in memory).

The compiled functions are cached on disk by numba, keyed on all of the engine's sources
(:mod:`bouncedisk.engine._cache`, imported first so that it applies to every one of them).
"""

from . import _cache  # noqa: F401  (registers the cache locators before anything compiles)
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
