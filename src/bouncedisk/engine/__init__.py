"""The exact event-driven engine (numba): no I/O, no xarray.

Public entry points: :class:`EngineConfig`, :class:`InitialState`, :func:`iterate` (chunked,
streaming) and :func:`simulate_arrays` (in memory). They refuse a configuration or state out of
the bounds of :mod:`bouncedisk.engine.bounds` with an :class:`InputError` before the kernel runs.

The compiled functions are cached on disk by numba, keyed on all of the engine's sources
(:mod:`bouncedisk.engine._cache`, which every compiled module imports before it decorates
anything). The entry points are loaded on first use: code that only names the engine's records
(:mod:`bouncedisk.engine.layout`, plain integers) imports no numba.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

from .errors import InputError
from .layout import KIND_CHATTER, KIND_IMPACT

if TYPE_CHECKING:  # pragma: no cover - for type checkers and IDEs only
    from .driver import (
        Chunk,
        EngineConfig,
        EngineError,
        InitialState,
        RunResult,
        iterate,
        simulate_arrays,
    )

__all__ = [
    "Chunk",
    "EngineConfig",
    "EngineError",
    "InitialState",
    "InputError",
    "RunResult",
    "iterate",
    "simulate_arrays",
    "KIND_IMPACT",
    "KIND_CHATTER",
]
#: The entry points that live in :mod:`bouncedisk.engine.driver` (imported on first use).
_FROM_DRIVER = frozenset(__all__) - {"KIND_IMPACT", "KIND_CHATTER", "InputError"}


def __getattr__(name: str) -> Any:
    """An entry point of the driver, or a submodule (``engine.kernel``), on first use."""
    if name in _FROM_DRIVER:
        value = getattr(import_module(".driver", __name__), name)
    elif name.isidentifier() and not name.startswith("__"):
        try:
            value = import_module(f".{name}", __name__)
        except ModuleNotFoundError as ex:
            if ex.name != f"{__name__}.{name}":
                raise
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value
