"""netCDF files to share: the time coordinate and ACDD attributes, seconds and scales of a
physical scene, joined sweep shards.
"""

import numpy as np
import xarray as xr
from cli_checks import SMALL

from bouncedisk.cli import main
from bouncedisk.model.scene import scene_from_mapping


# --------------------------------------------------------------------------- netCDF for sharing
def test_time_coordinate_and_acdd(tmp_path):
    scene = tmp_path / "s.yaml"
    scene.write_text(SMALL)
    out = tmp_path / "out.nc"
    assert main(["simulate", str(scene), "-o", str(out), "-q"]) == 0
    with xr.open_dataset(out, decode_times=False) as ds:
        assert "standard_name" not in ds["time"].attrs and "axis" not in ds["time"].attrs
        assert ds["time"].attrs["units"] == "1"
        assert ds.attrs["summary"] and "chattering" in ds.attrs["keywords"]


def test_physical_scene_gives_seconds_and_scales(tmp_path):
    scene = tmp_path / "p.yaml"
    scene.write_text(
        "name: phys\nphysical: {m_r: 0.01, r_g: 0.004, r_c: 0.001, mu: 0.2, e: 0.5, g: 9.81,\n"
        "  f: 2.0e+2, U0: 1.0e-4, Phi0: 1.0e-3}\neffects: [impacts, contact, torsion]\n"
        "stop: {impacts: 20}\noutputs: {events: true, trajectory: {dt: 0.1}}\n"
    )
    out = tmp_path / "out.nc"
    assert main(["simulate", str(scene), "-o", str(out), "-q"]) == 0
    with xr.open_dataset(out, decode_times=False) as ds:
        t_c = ds.attrs["t_c_s"]
        assert ds["time_s"].attrs["units"] == "s"
        # CF-1.10 §4.4 keeps standard_name "time" for "UNIT since DATE"
        assert "standard_name" not in ds["time_s"].attrs and "axis" not in ds["time_s"].attrs
        assert np.allclose(ds["time_s"].values, ds["time"].values * t_c)
        assert np.allclose(ds["t_impact_s"].values, ds["t_impact"].values * t_c)
        for key in ("t_c_s", "U0_m", "omega_scale_rad_s"):
            assert key in ds.attrs


def test_joined_shards_report_the_whole_sweep(tmp_path):
    from bouncedisk.analysis.sweeps import combine_shards, run_sweep
    from bouncedisk.io.netcdf import write_dataset

    base = scene_from_mapping(
        {"name": "sw", "parameters": {"e": 0.3, "omega_s": 1.5}, "stop": {"time": 800.0}}
    )
    axes = [("e", np.linspace(0.1, 0.7, 4))]
    shards = [run_sweep(base, axes, shard=i, n_shards=2, tail=10) for i in range(2)]
    paths = []
    for i, sh in enumerate(shards):
        paths.append(tmp_path / f"shard-{i}.nc")
        write_dataset(sh, paths[-1])
    total = combine_shards(shards).attrs["n_impacts"]
    with xr.open_mfdataset(paths, combine="by_coords") as mf:
        assert int(mf["n_events"].sum()) == total
        assert mf.attrs.get("n_impacts", total) == total
    assert total == sum(int(s["n_events"].sum()) for s in shards)
    # the join by hand the pipeline guide shows: the files' own creation times differ
    by_hand = combine_shards([xr.open_dataset(p) for p in sorted(paths)])
    plain = xr.combine_by_coords(
        [xr.open_dataset(p) for p in sorted(paths)], combine_attrs="drop_conflicts"
    )
    for name in ("n_events", "phase", "regime"):
        np.testing.assert_array_equal(by_hand[name].values, plain[name].values)
    assert by_hand.attrs["n_impacts"] == total


def test_shards_join_and_stats_write_without_dask(tmp_path):
    """The package needs no dask (docs/formats.md; the tests install it for ``open_mfdataset``):
    a sweep's shards joined and written, and an ensemble's statistics made and written, in a
    process where dask cannot be imported; the joined file is the one-job sweep's."""
    import subprocess
    import sys

    code = f"""
import sys
sys.modules["dask"] = None
import numpy as np
from bouncedisk.analysis.statistics import run_stats, to_dataset
from bouncedisk.analysis.sweeps import combine_shards, run_sweep
from bouncedisk.io.netcdf import open_checked, write_dataset
from bouncedisk.model.scene import scene_from_mapping

base = scene_from_mapping(
    {{"name": "sw", "parameters": {{"e": 0.3, "omega_s": 1.5}}, "stop": {{"time": 400.0}}}}
)
axes = [("e", np.linspace(0.1, 0.7, 4))]
paths = []
for i in range(2):
    paths.append(r"{tmp_path}" + f"/shard-{{i}}.nc")
    write_dataset(run_sweep(base, axes, shard=i, n_shards=2, tail=5), paths[-1])
joined = combine_shards([open_checked(p, required=("regime",)) for p in paths])
write_dataset(joined, r"{tmp_path}/joined.nc")
whole = run_sweep(base, axes, tail=5)
assert np.array_equal(joined["regime"].values, whole["regime"].values)
stats = scene_from_mapping({{"name": "st", "parameters": {{"e": 0.3, "omega_s": 1.5,
    "e_sigma": 1e-3}}, "effects": ["impacts", "contact", "restitution_noise"], "stop": {{"time": 200.0}},
    "ensemble": {{"members": 2, "seed": 1}}, "stats": {{"discard": 50.0}}}})
write_dataset(to_dataset(stats, run_stats(stats, cores=1), 0.0), r"{tmp_path}/stats.nc")
assert "dask" not in [m.split(".")[0] for m in sys.modules if sys.modules[m] is not None]
"""
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    with xr.open_dataset(tmp_path / "joined.nc") as ds:
        assert ds.sizes["e"] == 4
