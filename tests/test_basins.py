"""Coexisting motions and their basins (``bouncedisk basins``, bouncedisk.studies.basins)."""

import dataclasses
import json
import math
import warnings

import numpy as np
import pytest
import xarray as xr

from bouncedisk.analysis.ensembles import run_member
from bouncedisk.analysis.observables import REGIME_CODES, REGIMES
from bouncedisk.analysis.statistics import Z95, wilson
from bouncedisk.cli import main
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.io.provenance import REQUIRED_ATTRS
from bouncedisk.model.engine_config import engine_config
from bouncedisk.model.errors import InputError
from bouncedisk.model.scene import load_scene
from bouncedisk.studies import basins as B

# the paper's Fig. 3 motor (e = 0.3, omega_s = 1.5) with torsion: run up by t = 4000
FIG3 = """
name: fig3_basins
parameters: {e: 0.3, omega_s: 1.5, r_phi: 0.01, psi: 0.0, load_torque: 0.0}
effects: [impacts, contact, torsion, load]
stop: {time: 8000.0}
stats: {discard: 4000.0}
"""
# e = 0.22: a period-1 orbit beside a locked chattering cycle (docs/model.md "Regimes")
TWO = """
name: two_attractors
parameters: {e: 0.22, omega_s: 1.5, r_phi: 0.01, psi: 0.0}
effects: [impacts, contact, torsion]
stop: {time: 600.0}
stats: {discard: 300.0}
"""


def test_wilson_interval_closed_forms():
    z = Z95
    n = 40
    assert wilson(n, n) == (pytest.approx(n / (n + z * z), rel=1e-14), 1.0)
    assert wilson(0, n) == (0.0, pytest.approx(z * z / (n + z * z), rel=1e-14))
    lo, hi = wilson(10, 40)
    # the score interval solves |p - 0.25| = z sqrt(p (1 - p) / n) at both ends
    for p in (lo, hi):
        assert abs(p - 0.25) == pytest.approx(z * math.sqrt(p * (1 - p) / n), rel=1e-12)


def test_every_start_from_rest_without_load_reaches_the_one_period_2_orbit(scene_file):
    scene = load_scene(scene_file(FIG3))
    grid = B.start_grid(8, [0.0], [0.0, 0.5])
    ds = B.basins(scene, grid, cores=2)
    out = B.summary(ds)
    assert len(out["attractors"]) == 1 and out["unsettled"]["starts"] == 0
    a = out["attractors"][0]
    assert a["regime"] == "periodic" and a["period"] == [2, 2]
    assert a["fraction"] == 1.0 and a["starts"] == 16
    assert a["fraction_ci95"] == [pytest.approx(16 / (16 + Z95**2)), 1.0]
    assert set(ds["label"].values) == {0}
    # the period-2 orbit's two impact phases, the same cycle from every start
    phases = ds["orbit_phases"].values[:, :2]
    assert np.ptp(phases, axis=0).max() < B.PHASE_TOL
    assert np.ptp(np.sort(phases[0])) > 0.5


def _independent(scene, grid):
    """One run over the whole window per start: (class, mean speed) by run_member directly."""
    cfg = engine_config(scene)
    discard, duration = B.check_scene(scene)
    out = []
    for ph, sp, h in zip(*grid.flat(), strict=True):
        init = B.start_state(scene, float(ph), float(sp), float(h))
        run = dataclasses.replace(cfg, t_end=init.t + duration)
        st, _, _ = run_member(run, init, 0, init.t + discard)
        out.append(((REGIMES[st.regime], st.period_p, st.period_q), st.mean_omega))
    return out


def test_two_attractors_fractions_match_an_independent_run_per_start(scene_file):
    scene = load_scene(scene_file(TWO))
    grid = B.start_grid(12, [0.0], [0.0, 0.5, 1.0, 2.0])
    ds = B.basins(scene, grid, cores=2)
    assert ds.sizes["attractor"] == 2 and ds.attrs["unsettled_starts"] == 0
    runs = _independent(scene, grid)
    for k in range(2):
        a = ds.sel(attractor=k)
        key = (REGIMES[int(a["attractor_regime"])], int(a["attractor_period_p"]),
               int(a["attractor_period_q"]))  # fmt: skip
        mine = [i for i, (cls, _) in enumerate(runs) if cls == key]
        assert float(a["attractor_fraction"]) == len(mine) / grid.size
        assert 0 < len(mine) < grid.size
        assert np.array_equal(np.nonzero(ds["label"].values == k)[0], mine)
        speeds = np.array([runs[i][1] for i in mine])
        assert np.allclose(speeds, float(a["attractor_mean_speed"]), rtol=1e-3)
    # the two attractors: a period-1 orbit and a locked chattering cycle, the faster first
    assert {int(r) for r in ds["attractor_regime"].values} == {
        REGIME_CODES["periodic"],
        REGIME_CODES["chattering-periodic"],
    }
    assert ds["attractor_mean_speed"].values[0] > ds["attractor_mean_speed"].values[1]


def test_labels_are_bit_identical_across_shards_and_cores(scene_file):
    scene = load_scene(
        scene_file(TWO), ["effects=impacts,contact,torsion,restitution_noise",
                          "parameters.e_sigma=1e-9"]
    )  # fmt: skip
    grid = B.start_grid(6, [0.0, 20.0], [0.0, 1.0])
    whole = B.group(B.run_starts(scene, grid, cores=2))
    parts = [B.run_starts(scene, grid, shard=s, n_shards=3, cores=1) for s in range(3)]
    joined = B.group(B.join_shards(parts[::-1]))
    for name in ("label", "mean_omega", "mean_omega_first_half", "regime", "orbit_phases"):
        assert whole[name].values.tobytes() == joined[name].values.tobytes(), name
    with pytest.raises(ValueError, match="every start must appear once"):
        B.join_shards(parts[:2])
    with pytest.raises(ValueError, match="every start must appear once"):
        B.join_shards([parts[0], parts[0], parts[1], parts[2]])


def test_a_drifting_start_is_labelled_unsettled_not_grouped():
    # by hand: two settled starts of one periodic class at 100, one drifting (halves 80 and 90),
    # one unresolved, and a chaotic cloud spread by its finite-time means (not split)
    n = 8
    half1 = np.array([100.0, 100.0, 80.0, 50.0, 60.0, 61.0, 62.5, 63.0])
    half2 = np.array([100.0, 100.0, 90.0, 50.0, 62.0, 60.0, 61.5, 64.5])
    ds = xr.Dataset(
        {
            "mean_omega": ("start", 0.5 * (half1 + half2)),
            "mean_omega_first_half": ("start", half1),
            "mean_omega_second_half": ("start", half2),
            "regime": ("start", np.array([1, 1, 1, 0, 4, 3, 4, 4])),
            "period_p": ("start", np.array([2, 2, 2, 0, 0, 0, 0, 0])),
            "period_q": ("start", np.array([2, 2, 2, 0, 0, 0, 0, 0])),
            "orbit_phases": (("start", "orbit_slot"), np.full((n, B.ORBIT_SLOTS), np.nan)),
        },
        attrs={"window": [4000.0, 8000.0], "omega_s": 1.5},
    )
    ds["orbit_phases"][:3, :2] = [0.5, 2.0]
    # the same cycle from two starts: one of its phases just after 0, the other just before 2 pi
    ds["orbit_phases"][1, :2] = [2.0, 2 * np.pi - 1e-6]
    ds["orbit_phases"][0, :2] = [1e-6, 2.0]
    labels, scale = B.labels(ds, settle=0.01)
    assert scale == 100.0
    assert labels.tolist() == [0, 0, -1, -1, 1, 1, 1, 1]


def _periodic_starts(half1, half2, window):
    n = len(half1)
    ds = xr.Dataset(
        {
            "mean_omega": ("start", 0.5 * (np.asarray(half1) + np.asarray(half2))),
            "mean_omega_first_half": ("start", np.asarray(half1, float)),
            "mean_omega_second_half": ("start", np.asarray(half2, float)),
            "regime": ("start", np.ones(n, np.int64)),
            "period_p": ("start", np.full(n, 2)),
            "period_q": ("start", np.full(n, 2)),
            "orbit_phases": (("start", "orbit_slot"), np.full((n, B.ORBIT_SLOTS), np.nan)),
        },
        attrs={"window": window, "omega_s": 1.5},
    )
    ds["orbit_phases"][:, :2] = [0.5, 2.0]
    return ds


def test_a_short_window_does_not_call_a_slow_drift_settled():
    """Fig. 3's motor at load 0.075 (measured): a start on the slow orbit has halves within
    0.022 of each other over halves of 200 (its ripple over part of a cycle), a start drifting
    at 2.3e-3 per unit time within 0.47; at 1 % of the speed scale (1.37) both looked settled,
    and each drifting start became an attractor of its own. The tolerance shrinks as 1/h."""
    ds = _periodic_starts([78.1, 81.3, 106.4], [78.122, 81.768, 106.868], [400.0, 800.0])
    labels, _ = B.labels(ds, settle=0.01)
    assert labels.tolist() == [0, -1, -1]
    # over the default window (halves of 2000) the same drift is 4.67 and the ripple 0.0044
    ds = _periodic_starts([78.1, 95.0], [78.1044, 99.67], [4000.0, 8000.0])
    assert B.labels(ds, settle=0.01)[0].tolist() == [0, -1]


def test_a_window_too_short_to_tell_drift_from_settling_is_refused(scene_file):
    scene = load_scene(scene_file(FIG3), ["stop.time=60", "stats.discard=0"])
    with pytest.raises(InputError, match="10 stator periods"):
        B.check_scene(scene)


def test_speeds_may_be_negative_heights_may_not():
    assert B.start_grid(2, [-5.0, 5.0]).size == 4
    with pytest.raises(InputError, match="--heights"):
        B.start_grid(2, [0.0], [-1.0])


@pytest.mark.parametrize("value", ["-50,0", "-50:0:3", "-.5", "-50"])
def test_a_negative_value_may_follow_its_option_with_a_space(value):
    from bouncedisk.cli.command import attach_negative_values, build_parser

    parser = build_parser()
    argv = attach_negative_values(parser, ["basins", "s.yaml", "--phases", "2", "--speeds", value])
    args = parser.parse_args(argv)
    assert args.speeds == value and args.phases == 2
    # a flag is never joined to what follows, and an option's own value is left alone
    argv = ["basins", "s.yaml", "--json", "--phases", "2", "--heights", "0,1"]
    assert attach_negative_values(parser, argv) == argv


@pytest.mark.parametrize(
    ("args", "field"),
    [
        (["--phases", "0"], "--phases"),
        (["--phases", "4", "--heights=-1"], "--heights"),
        (["--phases", "4", "--speeds", "0,fast"], "--speeds"),
        (["--phases", "4", "--set", "stats.discard=598"], "stats.discard"),
        (["--phases", "4", "--settle", "0"], "--settle"),
        (["--phases", "2", "--set", "stop.max_events=50"], "stop.max_events (from --set"),
        # the capped start is named by its place in the grid, not as an ensemble's member
        (
            ["--phases", "2", "--speeds", "5", "--set", "stop.max_events=50"],
            "start 0 of the basins (phase 0 rad, speed 5, height 0) stopped at the safety cap",
        ),
    ],
)
def test_bad_input_is_one_line_exit_2_and_no_file(scene_file, tmp_path, capsys, args, field):
    out = tmp_path / "b.nc"
    assert main(["basins", str(scene_file(TWO)), *args, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("bouncedisk: error: ") and field in err[0]
    assert not out.exists()


def test_command_writes_the_file_and_the_json(scene_file, tmp_path, capsys):
    out = tmp_path / "b.nc"
    args = ["basins", str(scene_file(TWO)), "--phases", "4", "--heights", "0,2"]
    assert main([*args, "-o", str(out), "--json"]) == 0
    js = json.loads(capsys.readouterr().out)
    ds = xr.open_dataset(out)
    assert js["starts"] == 8 == ds.sizes["start"]
    assert sum(a["fraction"] for a in js["attractors"]) + js["unsettled"]["fraction"] == 1.0
    for a in js["attractors"]:
        assert a["fraction_ci95"][0] <= a["fraction"] <= a["fraction_ci95"][1]
        assert {"mean_speed", "regime", "fraction", "fraction_ci95"} <= set(a)
    assert js["per_start"]["label"] == ds["label"].values.tolist()
    assert set(js["per_start"]) >= {"label", "mean_speed", "regime"}
    assert all(k in ds.attrs for k in REQUIRED_ATTRS)
    assert ds.attrs["history"].startswith(ds.attrs["created"])  # the command line that made it
    assert ds["regime"].attrs["flag_meanings"].split()[1] == "periodic"
    from bouncedisk.cli.basins import format_basins

    table = format_basins(js).splitlines()  # each attractor's speed with its interval
    assert table[1].split()[:4] == ["label", "mean", "speed", "95%"]
    for a, row in zip(js["attractors"], table[2:], strict=False):
        lo, hi = a["mean_speed_ci95"]
        assert lo <= a["mean_speed"] <= hi and f"[{lo:.5g}, {hi:.5g}]" in row


def test_the_reproduction_check_reads_the_start_up_file_and_can_fail(scene_file, tmp_path):
    scene = load_scene(scene_file(FIG3))
    ds = B.startup(scene, [0.0, 0.1], B.start_grid(4, [0.0], [0.0, 0.5]), 110.0, cores=2)
    assert ds["fast_fraction"].values.tolist() == [1.0, 0.0]  # fast (144) without load, 78 at 0.1
    assert ds["n_attractors"].values.tolist() == [1, 1]
    path = tmp_path / B.STARTUP_FILE
    path.parent.mkdir()
    write_dataset(ds, path)
    claim, measured, _, passed, source = B.closed_case(tmp_path, lambda: scene)
    assert passed and source == str(path) and "8 of 8 starts on period-2" in measured
    ds["label"][0, 3] = -1  # one start that has not settled
    write_dataset(ds, path)
    assert not B.closed_case(tmp_path, lambda: scene)[3]


def test_figures_draw_the_attractors_and_the_start_up_band(scene_file):
    from bouncedisk.figures.basins import fig_basin_map, fig_startup

    scene = load_scene(scene_file(TWO))
    ds = B.basins(scene, B.start_grid(6, [0.0, 40.0], [0.0]), cores=2)
    ax = fig_basin_map(ds).axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert len(labels) == ds.sizes["attractor"] + 1 and labels[-1].startswith("not settled")
    assert ax.get_ylabel().startswith("initial rotor speed")
    with pytest.raises(InputError, match="'load' effect"):
        B.startup(scene, [0.0, 0.05], B.start_grid(3, [0.0], [0.0]), 120.0)
    loaded = load_scene(scene_file(FIG3))
    up = B.startup(loaded, [0.0, 0.1], B.start_grid(3, [0.0], [0.0]), 120.0)
    ax = fig_startup(up).axes[0]
    assert len(ax.collections) == 3 and len(ax.lines) == 3  # three bands, three curves
    # without load every start reaches the fast branch (144), at 0.1 the slow one (78): both drawn
    drawn = {line.get_label().split(" (")[0]: line.get_ydata().tolist() for line in ax.lines}
    assert drawn["settled on the fast branch"] == [1.0, 0.0]
    assert drawn["settled on the slow branch"] == [0.0, 1.0]
    assert drawn["not settled within the longest window"] == [0.0, 0.0]


def test_a_chaotic_attractor_is_not_split_by_its_finite_time_means(scene_file):
    # e = 0.6 (Fig. 4) on the natural measure (noise 1e-9): chaotic, with chatter reinjection in
    # some tails; the starts' means spread by several units (halves of 6000: their differences
    # stay within the chaotic tolerance, 10% of the largest speed): one attractor all the same
    noisy = ["effects=impacts,contact,torsion,restitution_noise", "parameters.e_sigma=1e-9"]
    window = ["parameters.e=0.6", "stop.time=15000", "stats.discard=3000"]
    scene = load_scene(scene_file(TWO), noisy + window)
    ds = B.basins(scene, B.start_grid(12, [0.0]), cores=2)
    means = ds["mean_omega"].values
    assert np.ptp(means) > 1.0  # finite-time means that differ (a periodic orbit's would not)
    assert ds.sizes["attractor"] == 1 and ds.attrs["unsettled_starts"] == 0
    assert REGIMES[int(ds["attractor_regime"].values[0])] in ("chaotic", "chaotic-reinjection")
    low = ds["attractor_mean_speed_ci95_low"].values[0]
    high = ds["attractor_mean_speed_ci95_high"].values[0]
    assert low < means.mean() < high


# the basins guide's example: Fig. 3's motor at load 0.075, where a start above the slow branch
# (78) drifts down at about 2.3e-3 per unit time, through the scene's window of 8000
GUIDE = FIG3.replace("load_torque: 0.0", "load_torque: 0.075")


def test_a_drifting_start_runs_again_over_doubled_windows_until_it_settles(scene_file):
    scene = load_scene(scene_file(GUIDE))
    grid = B.start_grid(2, [0.0, 100.0])
    once = B.basins(scene, grid, cores=2, extend=0)
    assert once["label"].values.tolist() == [0, 0, -1, -1]
    ds = B.basins(scene, grid, cores=2)
    assert ds["label"].values.tolist() == [0, 0, 0, 0] and ds.attrs["unsettled_starts"] == 0
    assert ds["window_factor"].values.tolist() == [1.0, 1.0, 4.0, 4.0]
    assert np.ptp(ds["mean_omega"].values) < 0.01  # one slow orbit, 78.10
    # each start doubles on its own: shards (one start each side of the drift) agree bit for bit
    parts = [B.run_starts(scene, grid, shard=s, n_shards=2, cores=1) for s in (0, 1)]
    joined = B.group(B.join_shards(parts))
    for name in ("label", "window_factor", "mean_omega"):
        assert joined[name].values.tobytes() == ds[name].values.tobytes(), name
    # an extended start runs on from where its last window ended: its numbers are those of a
    # start run over the longer window directly, to rounding (the continued clock restarts)
    longer = load_scene(scene_file(GUIDE), ["stop.time=32000", "stats.discard=16000"])
    direct = B.run_starts(longer, grid, extend=0)
    for name in ("mean_omega_first_half", "mean_omega_second_half", "orbit_phases"):
        assert np.allclose(ds[name][2:], direct[name][2:], rtol=1e-9, equal_nan=True), name
    assert ds["regime"].values[2:].tolist() == direct["regime"].values[2:].tolist()
    # the tolerance is the start's own: at factor 4 the periodic tolerance shrinks 4 times
    ds["window_factor"].values[:] = 1.0
    ds["mean_omega_first_half"].values[2] += 0.01  # within 0.01 x 78 x 0.021 only at factor 1
    assert B.labels(ds)[0].tolist() == [0, 0, 0, 0]
    ds["window_factor"].values[2] = 4.0
    assert B.labels(ds)[0].tolist() == [0, 0, -1, 0]


def test_the_guides_example_settles(scene_file):
    """The guide's `--phases 48 --speeds 0,50,100,150` at load 0.075, one phase in six: every
    start settles on the slow orbit (over the scene's window alone, half of them do not)."""
    scene = load_scene(scene_file(GUIDE))
    ds = B.basins(scene, B.start_grid(8, [0.0, 50.0, 100.0, 150.0]), cores=2)
    assert ds.attrs["unsettled_starts"] == 0 and ds.sizes["attractor"] == 1
    assert float(ds["attractor_mean_speed"][0]) == pytest.approx(78.10, abs=0.01)
    assert ds["window_factor"].values.max() == 8.0


def test_a_start_capped_in_a_longer_window_keeps_its_last_one(scene_file):
    # the cap holds each run of 8000 time units (the scene's, and each half of the window
    # four times as long) but not the halves of 16000 of the window eight times as long, which
    # the start from 150 needs: it stays unsettled over its last window instead of failing
    scene = load_scene(scene_file(GUIDE), ["stop.max_events=3000"])
    ds = B.basins(scene, B.start_grid(1, [150.0]), cores=1)
    assert ds["label"].values.tolist() == [-1] and ds["window_factor"].values.tolist() == [4.0]


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (
            ["--speeds", "1e200"],
            "--speeds: must be within ±1e+100 (a scene's bound on initial.omega",
        ),
        (["--speeds=-1e101,0"], "--speeds: must be within ±1e+100"),
        (["--speeds", "1,,2"], "--speeds: has an empty speed in '1,,2'"),
        (["--speeds", "1,1"], "--speeds: repeats a speed"),
        (["--heights", "1e7"], "--heights: must be in [0, 1e+06]"),
        (["--heights", ",1"], "--heights: has an empty height"),
        (["--speeds", "0:-5:3"], "--speeds: STOP must be > START"),
        (["--set", "model=clipped"], "model (from --set model): basins run the bouncing model"),
        (["--set", "solver.method=rk45"], "solver.method (from --set solver.method)"),
        (["--extend", "-1"], "--extend: must be a whole number in [0, 8]"),
        (["--settle", "2"], "--settle: must be in (0, 1), got 2"),
    ],
)
def test_bad_starts_and_models_are_named_in_one_line(scene_file, tmp_path, capsys, args, expected):
    from cli_helpers import one_line

    out = tmp_path / "b.nc"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no numpy warning reaches the user
        assert main(["basins", str(scene_file(TWO)), "--phases", "2", *args, "-o", str(out)]) == 2
    line = one_line(capsys)
    assert line.startswith("bouncedisk: error: ") and expected in line, line
    assert "load" not in line and "np.float64" not in line
    assert not out.exists()


def test_negative_initial_speeds_are_starts_like_any_other(scene_file, capsys):
    assert main(["basins", str(scene_file(TWO)), "--phases", "2", "--speeds=-50,0", "--json"]) == 0
    captured = capsys.readouterr()
    js = json.loads(captured.out)
    assert js["per_start"]["speed"] == [-50.0, -50.0, 0.0, 0.0]
    assert captured.err == ""  # the scene discards a transient: no warning
    assert B.parse_values("-50:50:3", "--speeds", "speed") == [-50.0, 0.0, 50.0]


def test_a_window_from_switch_on_is_warned_of(scene_file, capsys):
    """Without stats.discard the averages hold the start-up: one warning line, as stats says."""
    assert main(["basins", str(scene_file(TWO)), "--phases", "1", "--set", "stats={}"]) == 0
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.startswith("bouncedisk: warning: ") and "stats.discard: 0" in line
    # a bad option is the one line: the warning waits for the options
    args = ["--phases", "1", "--speeds", "abc", "--set", "stats={}"]
    assert main(["basins", str(scene_file(TWO)), *args]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.startswith("bouncedisk: error: ") and "--speeds" in line
