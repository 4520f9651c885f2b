"""Shards of a study joined back: index order, each index once, costs summed."""

import numpy as np
import pytest
import xarray as xr

from bouncedisk.studies.shards import join_indexed


def _shard(lo: int, hi: int, k: int) -> xr.Dataset:
    i = np.arange(lo, hi)
    return xr.Dataset({"v": ("point", i * 10.0)}, coords={"point": i},
                      attrs={"shard": k, "wall_time_s": 1.5, "cpu_time_s": 2.0, "seed": 3})  # fmt: skip


def test_shards_in_any_order_join_in_index_order_with_their_costs_summed():
    parts = [_shard(4, 7, 1), _shard(0, 4, 0), _shard(7, 9, 2)]
    ds = join_indexed(parts, "point", 9, "point")
    np.testing.assert_array_equal(ds["point"], np.arange(9))
    np.testing.assert_array_equal(ds["v"], np.arange(9) * 10.0)
    assert ds.attrs["wall_time_s"] == 4.5 and ds.attrs["cpu_time_s"] == 6.0
    assert "shard" not in ds.attrs and ds.attrs["seed"] == 3


@pytest.mark.parametrize(
    "parts,needle",
    [
        ([_shard(0, 4, 0), _shard(7, 9, 2)], "missing [4, 5, 6], repeated []"),
        ([_shard(0, 5, 0), _shard(4, 9, 1)], "missing [], repeated [4]"),
        ([_shard(0, 9, 0), _shard(9, 10, 1)], "must lie in 0..8"),
    ],
)
def test_a_missing_repeated_or_foreign_index_is_named(parts, needle):
    with pytest.raises(ValueError) as ex:
        join_indexed(parts, "point", 9, "point")
    assert needle in str(ex.value)


def test_no_shards_or_fractional_indices_are_refused():
    with pytest.raises(ValueError, match="no shards"):
        join_indexed([], "point", 3, "point")
    bad = _shard(0, 3, 0).assign_coords(point=[0.0, 1.5, 2.0])
    with pytest.raises(ValueError, match="whole number"):
        join_indexed([bad], "point", 3, "point")
