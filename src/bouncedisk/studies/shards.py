"""Shards of a study joined back into one dataset: the one rule both sharded studies (basins of
attraction, the parameter study) follow."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

#: Attributes that add up over the shards (each shard's own cost).
SUMMED = ("wall_time_s", "cpu_time_s")


def join_indexed(shards: Sequence[xr.Dataset], dim: str, total: int, what: str) -> xr.Dataset:
    """The shards concatenated along ``dim`` in index order, every index ``0 … total − 1``
    exactly once; the :data:`SUMMED` costs added up and the ``shard`` attribute dropped.

    Parameters
    ----------
    shards : sequence of Dataset
        Each with an integer coordinate ``dim`` (its share of the indices), in any order.
    dim : str
        The dimension the shards split.
    total : int
        How many indices the whole computation has.
    what : str
        What one index is, for the error (``"start"``, ``"point"``).

    Raises
    ------
    ValueError
        An index missing or repeated (the first five of each named).
    """
    if not shards:
        raise ValueError(f"no shards to join: every {what} is missing")
    raw = np.concatenate([s[dim].values for s in shards])
    index = raw.astype(np.int64)
    if not np.array_equal(index, raw):
        raise ValueError(f"every {what} must be a whole number")
    if index.size and (index.min() < 0 or index.max() >= total):
        raise ValueError(
            f"every {what} must lie in 0..{total - 1}: got {index.min()}..{index.max()}"
        )
    counts = np.bincount(index, minlength=total)
    if np.any(counts != 1):
        missing = np.nonzero(counts == 0)[0][:5].tolist()
        repeated = np.nonzero(counts > 1)[0][:5].tolist()
        raise ValueError(f"every {what} must appear once: missing {missing}, repeated {repeated}")
    ds = xr.concat(list(shards), dim=dim, combine_attrs="drop_conflicts").sortby(dim)
    ds.attrs.pop("shard", None)
    for key in SUMMED:
        if any(key in s.attrs for s in shards):
            ds.attrs[key] = float(sum(float(s.attrs.get(key, 0.0)) for s in shards))
    return ds
