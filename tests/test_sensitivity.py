"""The global sensitivity study (SALib): sampling, sharded evaluation, joining, analysis, config."""

import copy
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
    st = settings(ranges=ISHIGAMI_RANGES, base_samples=2048, shards=3, resamples=200)
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
    assert np.all(ind["resolved"].values == 1)
    assert "RBD-FAST" in ind.attrs["estimators"]


def test_rbd_fast_first_order_intervals_are_narrower_than_saltellis_at_the_same_points():
    from SALib.analyze import sobol

    st = settings(ranges=ISHIGAMI_RANGES, base_samples=256, shards=1, resamples=200)
    points = run_sharded(st, sens.IshigamiModel(list(ISHIGAMI_RANGES)))
    ours = sens.analyse(points, st.ranges, st.resamples, st.seed).sel(output="ishigami")
    y = points["ishigami"].values
    prob = sens.problem(st.ranges)
    saltelli = sobol.analyze(prob, y, calc_second_order=False, num_resamples=200, seed=1)
    assert np.all(ours["S1_conf"].values < 0.6 * np.asarray(saltelli["S1_conf"]))
    assert np.allclose(ours["ST"].values, saltelli["ST"])  # ST stays Jansen's (SALib sobol)
    s1, _ = ishigami_indices()
    assert np.all(np.abs(ours["S1"].values - s1) <= ours["S1_conf"].values)


def test_an_output_undefined_at_a_few_points_is_analysed_without_their_base_samples():
    """A point where the output is undefined takes its base sample's D + 2 points out of the
    analysis: the indices are SALib's on the remaining Saltelli design, and still hold the closed
    form; undefined at more than UNDEFINED_MAX_SHARE of the base samples, there are none."""
    from SALib.analyze import sobol

    st = settings(ranges=ISHIGAMI_RANGES, base_samples=1024, shards=1, resamples=100)
    points = run_sharded(st, sens.IshigamiModel(list(ISHIGAMI_RANGES)))
    block = len(ISHIGAMI_RANGES) + 2
    y = points["ishigami"].values.copy()
    y[[3, 7 * block + 1]] = np.nan  # base samples 0 and 7
    gappy = points.assign(ishigami=("point", y))
    ind = sens.analyse(gappy, st.ranges, st.resamples, st.seed).sel(output="ishigami")
    assert int(ind["n_undefined"]) == 2
    keep = np.ones(len(y), bool)
    keep[:block] = keep[7 * block : 8 * block] = False
    salib = sobol.analyze(sens.problem(st.ranges), y[keep], calc_second_order=False,
                          num_resamples=100, seed=st.seed)  # fmt: skip
    np.testing.assert_allclose(ind["ST"].values, salib["ST"])
    s1, st_ = ishigami_indices()
    assert np.all(np.abs(ind["ST"].values - st_) <= ind["ST_conf"].values)
    assert np.all(np.abs(ind["S1"].values - s1) <= ind["S1_conf"].values)
    # undefined in 11 of 1024 base samples (> 1 %): no indices
    y[block * np.arange(11)] = np.nan
    none = sens.analyse(points.assign(ishigami=("point", y)), st.ranges, 20, st.seed)
    assert np.isnan(none["ST"].values).all() and np.isnan(none["S1"].values).all()


def test_a_smoke_sized_study_falls_back_to_saltellis_first_order_estimator():
    st = settings(ranges=ISHIGAMI_RANGES, base_samples=8, shards=1, resamples=20)
    points = run_sharded(st, sens.IshigamiModel(list(ISHIGAMI_RANGES)))
    assert points.sizes["point"] < sens.RBD_FAST_MIN_POINTS
    ind = sens.analyse(points, st.ranges, st.resamples, st.seed)
    assert "Saltelli" in ind.attrs["estimators"]
    assert np.all(np.isfinite(ind["S1_conf"].values)) and np.all(ind["S1_conf"].values > 0)


class _Curve:
    """A load curve's up branch from given (member, load) matrices (the attributes
    :func:`bouncedisk.studies.sensitivity.load_figures` reads)."""

    def __init__(self, loads, speed, torsion):
        self.loads = np.asarray(loads, float)
        self._m = {"mean_omega": speed, "power_torsion_in": torsion,
                   "power_out": self.loads * speed}  # fmt: skip

    def matrix(self, branch, name):
        assert branch == "up"
        return self._m[name]

    def power(self, branch):
        return self.matrix(branch, "power_out")


def test_load_figures_are_the_mean_curves_with_bootstrap_errors():
    # speed_m(tau) = c_m - tau: the mean curve's root is mean(c) (linear: exact between loads),
    # and the bootstrap's error of a mean, corrected by sqrt(K/(K-1)), is s / sqrt(K)
    loads = np.array([0.0, 0.25, 0.5, 0.75, 1.0, 2.0])
    c = np.array([0.55, 0.61, 0.58, 0.66])
    speed = c[:, None] - loads[None, :]
    torsion = np.tile(np.linspace(1.0, 2.0, len(loads)), (len(c), 1))
    got = sens.load_figures(_Curve(loads, speed, torsion), r=0.1)
    value, low, high, se = got["stall_torque"]
    assert value == pytest.approx(c.mean(), abs=1e-12)
    assert se == pytest.approx(np.std(c, ddof=1) / 2.0, rel=0.05)
    assert low < value < high
    # the power tau (cbar - tau) is largest on the grid at tau = 0.25: R_phi times it
    power = 0.25 * (c.mean() - 0.25)
    assert got["max_power"][0] == pytest.approx(0.1 * power, rel=1e-12)
    assert got["efficiency_at_max_power"][0] == pytest.approx(power / 1.2, rel=1e-12)
    # the efficiency is W_L / W_t of the members' summed works: a member whose torsional input
    # is nearly 0 there does not make it diverge (its own ratio is ~1e8), and one without a
    # reading is left out of the efficiency, not the whole point
    tiny = torsion.copy()
    tiny[0, 1] = 1e-9
    eta = sens.load_figures(_Curve(loads, speed, tiny), r=0.1)["efficiency_at_max_power"]
    assert eta[0] == pytest.approx(power / ((1e-9 + 3 * 1.2) / 4), rel=1e-12)
    assert eta[0] < 1.0 and np.isfinite(eta[3])
    gap = torsion.copy()
    gap[0, 1] = np.nan  # both means over the other three members
    eta = sens.load_figures(_Curve(loads, speed, gap), r=0.1)["efficiency_at_max_power"]
    assert eta[0] == pytest.approx(0.25 * (c[1:].mean() - 0.25) / 1.2, rel=1e-12)
    assert np.isfinite(eta[3])
    # runs backwards at no load: stall torque 0, no power, no efficiency
    back = sens.load_figures(_Curve(loads, speed - 1.0, torsion), r=0.1)
    assert back["stall_torque"][0] == 0.0 and back["max_power"][0] == 0.0
    assert back["efficiency_at_max_power"][0] == 0.0


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
    st = settings(base_samples=4, members=2, duration=5.0, discard=5.0, loads=(0.0, 0.7, 2.0))
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
    assert np.all((stall >= 0.0) & (stall <= 2.0))  # the speed is <= 0 by tau_L = 2 > 1
    # the axial motion does not see psi: in Saltelli's rows (A, A_B^e, A_B^w, A_B^R, A_B^psi, B)
    # the chatter rate of A is that of A_B^psi to the bit (R_phi sets the run's length: not so)
    rate = one["chatter_rate"].values.reshape(4, 6)
    assert np.array_equal(rate[:, 0], rate[:, 4]) and not np.array_equal(rate[:, 0], rate[:, 5])
    # the load figures are in the running direction: a motor that turns at no load, either
    # way, holds a positive load against its motion
    assert np.all((stall > 0.0) | (one["no_load_speed"].values == 0.0))


def _backward_point(model) -> dict:
    """A cheap point (R_phi = 0.1) of ``model`` that runs backwards at no load."""
    for psi in (-2.0, -1.0, 1.0, 2.0):
        point = {"e": 0.6, "omega_s": 1.5, "log10_r_phi": -1.0, "psi": psi}
        if model(point).values["no_load_speed"][0] < 0.0:
            return point
    raise AssertionError("no backward point among the candidates")


def test_a_backward_motor_is_loaded_against_its_own_motion_as_its_mirror_at_psi_plus_pi():
    st = settings(members=2, loads=(0.0, 0.3, 0.6, 1.0, 2.0))
    running = sens.MotorModel(st)
    signed = sens.MotorModel(dataclasses.replace(st, running=False))
    point = _backward_point(signed)
    back = signed(point).values
    assert back["stall_torque"][0] == 0.0 and back["max_power"][0] == 0.0  # the sign convention
    got = running(point).values
    mirror = signed({**point, "psi": point["psi"] + PI}).values  # docs/model.md: Omega -> -Omega
    assert mirror["no_load_speed"][0] > 0.0
    assert got["no_load_speed"][0] == pytest.approx(-mirror["no_load_speed"][0], rel=1e-9)
    for name in ("stall_torque", "max_power", "efficiency_at_max_power", "log10_tau"):
        assert got[name][0] == pytest.approx(mirror[name][0], rel=1e-9), name
        assert got[name][3] == pytest.approx(mirror[name][3], rel=1e-6, abs=1e-12), name
    assert 0.0 < got["stall_torque"][0] <= 2.0 and got["max_power"][0] > 0.0
    # the design maps keep the torque-speed curves' sign convention
    assert sens.map_settings(st).running is False


def test_the_run_up_is_the_load_curves_first_run_bit_for_bit():
    from bouncedisk.analysis.bands import member_speeds
    from bouncedisk.studies.torque_speed import torque_speed

    st = settings(members=2, loads=(0.0, 0.5, 2.0))
    model = sens.MotorModel(st)
    point = {"e": 0.3, "omega_s": 1.5, "log10_r_phi": -1.0, "psi": 0.4}
    free, curve, (t, om) = sens._load_curve(model.scene(point, load=True), st)
    assert free.column("mean_omega").mean() > 0.0  # a forward motor: nothing mirrored
    # one run per member gives the run-up a separate ensemble without the load effect gave
    t0, om0 = member_speeds(model.scene(point), st.members, st.seed)
    assert np.array_equal(t, t0) and np.array_equal(om, om0)
    # and the curve continues from it as torque_speed does
    ref = torque_speed(model.scene(point, load=True), list(st.loads), branches=("up",))
    for name in ("mean_omega", "power_out", "efficiency_torsion", "chatter_rate"):
        assert np.array_equal(curve.matrix("up", name), ref.matrix("up", name)), name


def test_the_design_maps_read_their_curves_every_0_05_past_the_momentum_bound():
    st = sens.map_settings(settings())
    assert st.loads[-1] == settings().loads[-1] == 2.0  # still brackets every stall
    inner = np.array(st.loads[:-1])
    assert inner[0] == 0.0 and inner[-1] == pytest.approx(sens.MAP_LOAD_TOP) and inner[-1] > 1.0
    assert np.allclose(np.diff(inner), sens.MAP_LOAD_STEP)
    assert set(settings().loads) <= set(st.loads)
    assert sens.map_settings(settings(loads=())).loads == ()
    assert st.members == max(settings().members, sens.MAP_MIN_MEMBERS)


def test_joining_refuses_missing_points():
    model = sens.IshigamiModel(list(ISHIGAMI_RANGES))
    st = settings(ranges=ISHIGAMI_RANGES, base_samples=8, shards=3)
    shards = [sens.run_shard(st, model, i) for i in range(3)]
    with pytest.raises(ValueError, match="every point must appear once"):
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
        ("sensitivity_study.sizes.small.loads", [0.2, 0.5], "sizes.small.loads"),
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


def test_the_indices_figure_greys_out_what_is_not_resolved_and_states_the_sample():
    from matplotlib.colors import to_hex

    from bouncedisk.figures.sensitivity import fig_sensitivity_indices

    st = settings(ranges=ISHIGAMI_RANGES, base_samples=256, shards=1, resamples=50)
    ind = sens.analyse(run_sharded(st, sens.IshigamiModel(list(ISHIGAMI_RANGES))), st.ranges, 50, 1)
    ind["S1_conf"][:] = 0.05
    ind["ST_conf"][:] = 0.05
    ind["ST_conf"][0, 2] = 0.3  # x3's total index: an interval wider than +-0.10
    fig = fig_sensitivity_indices(ind)
    ax = fig.axes[0]
    bars = [p for p in ax.patches if p.get_width() == pytest.approx(0.38)]
    colors = [to_hex(b.get_facecolor()) for b in bars]  # S1 x1..x3, then ST x1..x3
    assert colors[:3] == ["#1f77b4"] * 3
    assert colors[3:] == ["#ff7f0e", "#ff7f0e", "#bbbbbb"]
    title = fig._suptitle.get_text()
    assert f"{256 * 5} points" in title and "N = 256" in title
    assert "noise: 0.0 %" in ax.get_title()


def test_an_unknown_key_of_the_study_is_one_line_naming_it():
    """Before: the config schema's error, 89 lines of the schema."""
    from bouncedisk.model.errors import InputError

    config = copy.deepcopy(CONFIG)
    config["sensitivity_study"]["bogus"] = 1
    with pytest.raises(InputError, match="sensitivity_study.bogus: unknown key"):
        sc.study_settings(config)
    config["sensitivity_study"].pop("bogus")
    config["sensitivity_study"]["design_map"]["psi"] = 0.0
    with pytest.raises(InputError, match="sensitivity_study.design_map.psi"):
        sc.study_settings(config)
