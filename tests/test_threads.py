"""Work spread on threads (``bouncedisk.run.cores.map_on_threads``): order, progress, failures."""

from __future__ import annotations

import time

import pytest

from bouncedisk.run.cores import map_on_threads


def test_results_keep_the_items_order_when_threads_end_out_of_order():
    def slow_first(k: int) -> int:
        time.sleep(0.02 * (4 - k))  # the first one ends last
        return k * k

    done = []
    out = map_on_threads(slow_first, range(5), 3, lambda d, n: done.append((d, n)))
    assert out == [0, 1, 4, 9, 16]
    assert done == [(1, 5), (2, 5), (3, 5), (4, 5), (5, 5)]


@pytest.mark.parametrize("cores", [0, 1, 2])
def test_a_failing_item_raises_and_no_cores_means_one_thread(cores):
    assert map_on_threads(str, [1, 2], cores) == ["1", "2"]
    with pytest.raises(ZeroDivisionError):
        map_on_threads(lambda k: 1 / k, [2, 1, 0, 3], cores)
