"""The global sensitivity study (SALib): sampling, sharded evaluation, joining, analysis, config."""

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from bouncedisk.io.netcdf import write_dataset
from bouncedisk.model.errors import InputError
from bouncedisk.studies import sensitivity as sens
from bouncedisk.studies import sensitivity_settings as sc

ROOT = Path(__file__).resolve().parents[1]
CONFIG = yaml.safe_load((ROOT / "workflow" / "config" / "config.yaml").read_text())
PI = math.pi
ISHIGAMI_RANGES = {"x1": (-PI, PI), "x2": (-PI, PI), "x3": (-PI, PI)}


def ishigami_indices(a: float = 7.0, b: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form first-order and total indices of Ishigami's function (Sobol' & Levitan 1999)."""
    v1 = 0.5 * (1 + b * PI**4 / 5) ** 2
    v2 = a**2 / 8
    v13 = b**2 * PI**8 * (1 / 18 - 1 / 50)  # = 8 b² π⁸ / 225
    v = v1 + v2 + v13
    return np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v


def settings(size: str = "small", **changes) -> sc.StudySettings:
    cfg = {**CONFIG, "sensitivity": size}
    return dataclasses.replace(sc.study_settings(cfg), **changes)


def run_sharded(st: sc.StudySettings, model) -> xr.Dataset:
    return sens.join_shards([sens.run_shard(st, model, i) for i in range(st.shards)])


def test_ishigami_through_the_sharded_path_recovers_the_analytic_indices():
    st = settings(ranges=ISHIGAMI_RANGES, base_samples=2048, shards=3, resamples=500)
    model = sens.IshigamiModel(list(ISHIGAMI_RANGES))
    points = run_sharded(st, model)
    assert points.sizes["point"] == 2048 * 5
    ind = sens.analyse(points, st.ranges, st.resamples, st.seed).sel(output="ishigami")
    s1, st_ = ishigami_indices()
    for key, exact in (("S1", s1), ("ST", st_)):
        est, conf = ind[key].values, ind[f"{key}_conf"].values
        assert np.all(conf > 0) and np.all(conf < 0.1), (key, conf)
        assert np.all(np.abs(est - exact) <= conf), (key, est, exact, conf)
    assert float(ind["noise_share"]) == 0.0  # a deterministic function has no ensemble noise


def test_noise_share_is_the_noise_variance_over_the_output_variance():
    sigma = 2.0
    st = settings(ranges=ISHIGAMI_RANGES, base_samples=1024, shards=2)
    model = sens.IshigamiModel(list(ISHIGAMI_RANGES), noise=sigma)
    points = run_sharded(st, model)
    share = float(sens.analyse(points, st.ranges, 50, 1)["noise_share"].sel(output="ishigami"))
    s1, _ = ishigami_indices()
    v = 0.5 * (1 + 0.1 * PI**4 / 5) ** 2 / s1[0]  # the function's variance
    assert share == pytest.approx(sigma**2 / (v + sigma**2), rel=0.05)


def test_ishigami_shards_join_to_the_one_job_result_bit_for_bit(tmp_path):
    model = sens.IshigamiModel(list(ISHIGAMI_RANGES), noise=0.1)
    one = run_sharded(settings(ranges=ISHIGAMI_RANGES, base_samples=64, shards=1), model)
    many = run_sharded(settings(ranges=ISHIGAMI_RANGES, base_samples=64, shards=7), model)
    write_dataset(one, tmp_path / "one.nc")
    write_dataset(many, tmp_path / "many.nc")
    with xr.open_dataset(tmp_path / "one.nc") as a, xr.open_dataset(tmp_path / "many.nc") as b:
        assert set(a.data_vars) == set(b.data_vars)
        for k in a.data_vars:
            assert a[k].values.tobytes() == b[k].values.tobytes(), k


def test_motor_shards_join_to_the_one_job_result_bit_for_bit():
    st = settings(base_samples=4, members=2, duration=5.0, discard=5.0, loads=(0.0, 0.7, 1.3))
    model = sens.MotorModel(st)
    assert model.outputs == tuple(sens.OUTPUTS)  # the load figures too
    one = run_sharded(dataclasses.replace(st, shards=1), model)
    many = run_sharded(dataclasses.replace(st, shards=3), model)
    assert one.sizes["point"] == 4 * 6
    for k in one.data_vars:
        assert one[k].values.tobytes() == many[k].values.tobytes(), k
    # every point is an ensemble statistic with an interval around its mean
    y, lo, hi = (one[f"no_load_speed{s}"].values for s in ("", "_ci_low", "_ci_high"))
    assert np.all(lo <= y) and np.all(y <= hi)
    assert np.all(np.isfinite(one["log10_tau"].values))
    # the loads start at 0, where the power is 0: the largest power over them is never negative
    assert np.all(one["max_power"].values >= 0.0)
    stall = one["stall_torque"].values
    # the speed is <= 0 by tau_L = 1.3 > 1; a motor that runs backwards at no load has no stall
    # torque (NaN, not 0: bouncedisk.studies.load_summary)
    found = np.isfinite(stall)
    assert found.any() and np.all((stall[found] > 0.0) & (stall[found] <= 1.3))


def test_joining_refuses_missing_points():
    model = sens.IshigamiModel(list(ISHIGAMI_RANGES))
    st = settings(ranges=ISHIGAMI_RANGES, base_samples=8, shards=3)
    shards = [sens.run_shard(st, model, i) for i in range(3)]
    with pytest.raises(ValueError, match="once each"):
        sens.join_shards(shards[:2])


def test_the_design_map_marks_the_largest_value_and_the_points_within_its_interval():
    ds = xr.Dataset(
        {
            "x": (("point", "parameter"), np.zeros((4, 4))),
            "no_load_speed": ("point", [1.0, 3.0, 2.9, 0.5]),
            "no_load_speed_ci_low": ("point", [0.9, 2.8, 2.85, 0.4]),
            "no_load_speed_ci_high": ("point", [1.1, 3.2, 2.95, 0.6]),
        },
        coords={"parameter": list(sc.PARAMETERS)},
    )
    best = sens.best_point(ds, "no_load_speed")
    assert best["index"] == 1 and best["ci95"] == [2.8, 3.2]
    assert best["indistinguishable"] == [1, 2]


# ----------------------------------------------------------------------------- the config
def bad(path: str, value) -> dict:
    cfg = yaml.safe_load((ROOT / "workflow" / "config" / "config.yaml").read_text())
    node = cfg
    keys = path.split(".")
    for k in keys[:-1]:
        node = node[k]
    node[keys[-1]] = value
    return cfg


@pytest.mark.parametrize(
    ("path", "value", "field"),
    [
        ("sensitivity", "huge", "sensitivity"),
        ("sensitivity_study.ranges.e", [0.9, 0.1], "sensitivity_study.ranges.e"),
        ("sensitivity_study.ranges.e", [0.1, 1.5], "sensitivity_study.ranges.e"),
        ("sensitivity_study.ranges.omega_s", [0.5, 3.0], "sensitivity_study.ranges.omega_s"),
        ("sensitivity_study.ranges.psi", [1.0], "sensitivity_study.ranges.psi"),
        ("sensitivity_study.ranges", {"e": [0.1, 0.9]}, "sensitivity_study.ranges"),
        ("sensitivity_study.sizes.small.base_samples", 24, "sizes.small.base_samples"),
        ("sensitivity_study.sizes.small.base_samples", 2, "sizes.small.base_samples"),
        ("sensitivity_study.sizes.small.shards", 100000, "sizes.small.shards"),
        ("sensitivity_study.sizes.small.shards", 1000, "sizes.small.shards"),
        ("sensitivity_study.sizes.small.members", 1, "sizes.small.members"),
        ("sensitivity_study.sizes.small.duration", -1, "sizes.small.duration"),
        ("sensitivity_study.sizes.small.loads", [0.5, 0.2], "sizes.small.loads"),
        ("sensitivity_study.sizes.small.map_points", [1, 3], "sizes.small.map_points"),
        ("sensitivity_study.design_map.e", [], "sensitivity_study.design_map.e"),
        ("sensitivity_study.e_sigma", 0, "sensitivity_study.e_sigma"),
    ],
)
def test_bad_ranges_and_sizes_name_the_field(path, value, field):
    with pytest.raises(InputError) as ex:
        sc.study_settings(bad(path, value))
    line = ex.value.line()
    assert "\n" not in line and field in line, line


def test_the_full_study_has_at_least_1024_base_samples():
    cfg = bad("sensitivity_study.sizes.full.base_samples", 512)
    assert sc.study_settings({**cfg, "sensitivity": "small"}).size == "small"
    with pytest.raises(InputError, match=r"sizes\.full\.base_samples: must be >= 1024"):
        sc.study_settings({**cfg, "sensitivity": "full"})
    full = sc.study_settings({**CONFIG, "sensitivity": "full"})
    assert full.base_samples >= 1024 and full.n_points == full.base_samples * 6


def test_the_schema_repeats_the_package_bounds():
    schema = yaml.safe_load((ROOT / "workflow" / "schemas" / "config.schema.yaml").read_text())
    ranges = schema["properties"]["sensitivity_study"]["properties"]["ranges"]["properties"]
    for name, (lo, hi) in sc.DOMAIN.items():
        items = ranges[name]["items"]
        assert (items["minimum"], items["maximum"]) == pytest.approx((lo, hi)), name
    size = schema["$defs"]["sensitivity_size"]["properties"]
    for name in ("base_samples", "shards", "members", "duration", "discard", "resamples"):
        assert (size[name]["minimum"], size[name]["maximum"]) == sc.LIMITS[name], name
    assert (size["loads"]["items"]["minimum"], size["loads"]["items"]["maximum"]) == sc.LIMITS[
        "load"
    ]
    mp = size["map_points"]["items"]
    assert (mp["minimum"], mp["maximum"]) == sc.LIMITS["map_points"]
    assert schema["properties"]["sensitivity"]["enum"] == list(sc.SIZES)


def test_settings_survive_the_rule_params_round_trip():
    st = settings()
    assert sc.StudySettings.from_params(dataclasses.asdict(st)) == st
    assert re.fullmatch(r"[a-z_,0-9]+", ",".join(sens.OUTPUTS))
