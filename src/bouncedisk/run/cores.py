"""The cores this process may use (its CPU affinity), and work spread over them on threads."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

T = TypeVar("T")
R = TypeVar("R")


def available_cores() -> int:
    """Cores this process may use (its CPU affinity)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def checked_cores(cores: object, field: str = "cores") -> int:
    """A public function's ``cores``: a whole number >= 1, else one
    :class:`~bouncedisk.model.errors.InputError` naming the argument."""
    from ..model.params import whole_number

    return whole_number("<arguments>", field, cores)


def map_on_threads(
    fn: Callable[[T], R],
    items: Iterable[T],
    cores: int,
    on_done: Callable[[int, int], None] | None = None,
) -> list[R]:
    """``[fn(x) for x in items]`` on ``max(1, cores)`` threads, results in the items' order.

    Ensemble members and load points are independent runs whose compiled kernels release the
    GIL, so threads share the cores. ``on_done(done, total)`` is called as results arrive, in
    order (progress). The first exception of ``fn`` is raised once the running calls end.
    """
    items = list(items)
    out: list[R] = []
    with ThreadPoolExecutor(max_workers=max(1, cores)) as pool:
        for r in pool.map(fn, items):  # map keeps the items' order, whatever order threads end
            out.append(r)
            if on_done is not None:
                on_done(len(out), len(items))
    return out
