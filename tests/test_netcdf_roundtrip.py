"""netCDF files round-trip: what the package writes, xarray reads back bit for bit (hypothesis)."""

from __future__ import annotations

import numpy as np
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from bouncedisk.engine.driver import Chunk
from bouncedisk.io.netcdf import SimulationWriter, open_simulation, write_dataset

floats = st.floats(allow_nan=True, allow_infinity=True, width=64)
names = st.from_regex(r"[a-z][a-z0-9_]{0,11}", fullmatch=True)


@settings(max_examples=40, deadline=None)
@given(
    data=st.dictionaries(
        names,
        arrays(np.float64, st.integers(0, 40), elements=floats),
        min_size=1,
        max_size=4,
    ),
    ints=arrays(np.int64, st.integers(0, 40), elements=st.integers(-(2**62), 2**62)),
    attr=st.floats(allow_nan=False, allow_infinity=False),
)
def test_write_dataset_round_trips(tmp_path_factory, data, ints, attr):
    d = tmp_path_factory.mktemp("rt")
    ds = xr.Dataset({k: (f"dim_{k}", v) for k, v in data.items()})
    ds["counts"] = ("N", ints)  # a dimension no generated (lower-case) variable name can be
    ds.attrs["value"] = attr
    path = d / "x.nc"
    write_dataset(ds, path)
    with xr.open_dataset(path) as back:
        for k, v in data.items():
            assert back[k].values.tobytes() == v.tobytes(), k
            assert back[k].attrs["units"] and back[k].attrs["long_name"]
        assert back["counts"].values.tobytes() == ints.tobytes()
        assert back.attrs["value"] == attr


@settings(max_examples=25, deadline=None)
@given(
    sizes=st.lists(st.integers(0, 300), min_size=1, max_size=4),
    seed=st.integers(0, 2**32 - 1),
)
def test_simulation_writer_streams_chunks_losslessly(tmp_path_factory, sizes, seed):
    rng = np.random.default_rng(seed)
    chunks = []
    for n in sizes:

        def col(n=n):
            return rng.normal(size=n) * 10 ** rng.uniform(-300, 300)

        chunks.append(
            Chunk(
                t=np.sort(rng.uniform(0, 1e6, n)),
                phase=rng.uniform(0, 2 * np.pi, n),
                v_rel=np.abs(col()),
                omega_after=col(),
                u=rng.uniform(-1, 1, n),
                omega_before=col(),
                kind=rng.integers(0, 2, n).astype(np.int8),
                traj=np.empty((0, 5)),
                strobe=np.empty((0, 5)),
                n_events_total=0,
                t_now=0.0,
            )
        )
    path = tmp_path_factory.mktemp("sim") / "s.nc"
    with SimulationWriter(path, torsion=True, events=True, trajectory=False, strobe=False) as w:
        for c in chunks:
            w.append(c)
        w.set_attrs({"e": 0.5, "omega_s": 1.5, "status": "completed"})
    ds = open_simulation(path)
    for name, field in (
        ("t_impact", "t"),
        ("phase", "phase"),
        ("v_rel", "v_rel"),
        ("omega_after", "omega_after"),
        ("omega_before", "omega_before"),
        ("kind", "kind"),
    ):
        expected = np.concatenate([getattr(c, field) for c in chunks])
        assert ds[name].values.tobytes() == expected.tobytes(), name
    assert w.n_events == sum(sizes)
