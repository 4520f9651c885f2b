"""Ensemble statistics (docs/model.md "Long-run statistics of chaotic motion"; docs/formats.md "Statistics").

Restitution noise, members, confidence intervals, regimes and the ``bouncedisk stats`` command.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
import xarray as xr
from numba import njit

from bouncedisk.analysis.ensembles import MemberStats, run_ensemble
from bouncedisk.analysis.observables import REGIME_CODES
from bouncedisk.analysis.statistics import EnsembleStats, confidence_interval, run_stats
from bouncedisk.cli import main
from bouncedisk.cli.stats import format_summary
from bouncedisk.engine import EngineConfig, InitialState, simulate_arrays
from bouncedisk.engine.noise import member_key, noisy_restitution, normal
from bouncedisk.io.records import TrajColumn as C
from bouncedisk.model.scene import load_scene

CHAOTIC = """\
name: chaotic
parameters: {e: 0.6, omega_s: 1.5, r_phi: 0.01, psi: 0.0, e_sigma: 1.0e-9}
effects: [impacts, contact, torsion, restitution_noise]
stop: {time: 53000.0}
ensemble: {members: 32, seed: 1}
stats: {discard: 3000.0}
"""
SINGLE = """\
name: single
parameters: {e: 0.6, omega_s: 1.5, r_phi: 0.01, psi: 0.0}
effects: [impacts, contact, torsion]
stop: {time: 53000.0}
stats: {discard: 3000.0}
"""


def _json_stats(capsys, path, *sets: str) -> dict:
    args = ["stats", str(path), "--json", "-q"]
    for s in sets:
        args += ["--set", s]
    assert main(args) == 0
    return json.loads(capsys.readouterr().out)


# ------------------------------------------------------------------------------------ the noise
@njit
def normals(seed, member, k0, n):
    """``n`` consecutive deviates ``ξ_{k0}, …, ξ_{k0+n−1}`` of member ``member``'s stream."""
    key = member_key(seed, member)
    out = np.empty(n)
    for i in range(n):
        out[i] = normal(key, k0 + i)
    return out


def test_noise_stream_is_standard_normal_and_counter_based():
    x = normals(1, 0, 0, 200_000)
    assert abs(x.mean()) < 0.01 and abs(x.std() - 1.0) < 0.01
    assert abs(np.mean(np.abs(x) > 1.959964) - 0.05) < 0.003
    # the k-th deviate depends on (seed, member, k) only
    assert np.array_equal(normals(7, 3, 5, 10)[2:], normals(7, 3, 7, 8))
    y = normals(1, 1, 0, 200_000)
    assert abs(np.corrcoef(x, y)[0, 1]) < 0.01
    assert not np.array_equal(normals(2, 0, 0, 10), x[:10])


def test_noisy_restitution_is_clipped_to_the_unit_interval():
    from bouncedisk.engine.noise import member_key

    key = member_key(1, 0)
    high = [noisy_restitution(1.0, 0.5, key, k) for k in range(200)]
    low = [noisy_restitution(0.0, 0.5, key, k) for k in range(200)]
    assert max(high) == 1.0 and min(high) < 0.9
    assert min(low) == 0.0 and max(low) > 0.1


def test_noise_of_zero_width_changes_nothing():
    base = EngineConfig(e=0.6, omega_s=1.5, torsion=True, max_events=3000)
    a = simulate_arrays(base)
    # sigma 0 switches the effect off; any sigma > 0 draws the stream
    b = simulate_arrays(EngineConfig(e=0.6, omega_s=1.5, torsion=True, max_events=3000, seed=9))
    assert a.events["t"].tobytes() == b.events["t"].tobytes()
    c = simulate_arrays(
        EngineConfig(e=0.6, omega_s=1.5, torsion=True, max_events=3000, e_sigma=1e-9)
    )
    assert not np.array_equal(a.events["t"], c.events["t"])


# ---------------------------------------------------------------------- the time average of Ω
@pytest.mark.parametrize("e, psi", [(0.6, 0.0), (0.3, 1.0), (0.0, 1.0)])
def test_omega_integral_is_the_integral_of_the_dense_trajectory(e, psi):
    """∫Ω dt from the closed forms converges to the trapezoid sum of the samples as dt → 0."""
    errors = []
    for dt in (2e-4, 2e-5):
        cfg = EngineConfig(
            e=e, omega_s=1.5, torsion=True, psi=psi, t_end=300.0, max_events=10**6,
            traj_dt=dt, stats_from=50.0,
        )  # fmt: skip
        res = simulate_arrays(cfg)
        t, om = res.traj[:, C.T], res.traj[:, C.OMEGA]
        sel = t >= 50.0
        jumps = np.abs(res.events["omega_after"] - res.events["omega_before"]).sum()
        err = abs(res.final["omega_integral"] - np.trapezoid(om[sel], t[sel]))
        assert err <= dt * (jumps + 1.0)
        errors.append(err)
    assert errors[1] < errors[0] / 5


# ----------------------------------------------------------------- determinism and parallelism
def test_same_seed_is_bit_identical_other_seeds_differ_cores_do_not_matter():
    cfg = EngineConfig(
        e=0.6, omega_s=1.5, torsion=True, t_end=6000.0, max_events=10**8, e_sigma=1e-9, seed=4
    )
    one = run_ensemble(cfg, InitialState(), 6, 1000.0, cores=1)
    two = run_ensemble(cfg, InitialState(), 6, 1000.0, cores=2)
    assert one == two
    means = [m.mean_omega for m in one]
    assert len(set(means)) == len(means)  # members differ
    other = run_ensemble(
        EngineConfig(**{**cfg.__dict__, "seed": 5}), InitialState(), 6, 1000.0, cores=2
    )
    assert [m.mean_omega for m in other] != means


def test_stats_files_are_identical_on_one_and_two_cores(scene_file, tmp_path):
    f = scene_file(CHAOTIC)
    outs = []
    for cores in (1, 2):
        out = tmp_path / f"c{cores}.nc"
        args = ["stats", str(f), "-o", str(out), "--cores", str(cores), "-q"]
        assert main(args + ["--set", "ensemble.members=6", "--set", "stop.time=13000"]) == 0
        outs.append(xr.open_dataset(out))
    a, b = outs
    assert a.sizes["member"] == 6
    for name in a.data_vars:
        assert a[name].values.tobytes() == b[name].values.tobytes(), name


# --------------------------------------------------------------------- statistics that hold up
def test_ensemble_mean_is_robust_where_single_runs_jump(scene_file, capsys):
    """e and e + 1e-9 (e = 0.6, omega_s = 1.5): ensemble means agree within their intervals,
    single runs from the same start differ by far more than those intervals."""
    ens = scene_file(CHAOTIC, "ens.yaml")
    single = scene_file(SINGLE, "single.yaml")
    a = _json_stats(capsys, ens)
    b = _json_stats(capsys, ens, "parameters.e=0.600000001")
    half_a = (a["mean_omega_ci95"][1] - a["mean_omega_ci95"][0]) / 2
    half_b = (b["mean_omega_ci95"][1] - b["mean_omega_ci95"][0]) / 2
    assert 0 < half_a <= 1.5 and 0 < half_b <= 1.5  # the target width
    assert abs(a["mean_omega"] - b["mean_omega"]) <= math.hypot(half_a, half_b)
    s1 = _json_stats(capsys, single)["mean_omega"]
    s2 = _json_stats(capsys, single, "parameters.e=0.600000001")["mean_omega"]
    assert abs(s1 - s2) > 2 * math.hypot(half_a, half_b)
    assert a["regime"] == "chaotic-reinjection" and a["lyapunov_ci95"][0] > 0.5


def test_periodic_orbit_gives_the_single_run_value_with_a_zero_width_interval(scene_file, capsys):
    ens = scene_file(CHAOTIC, "ens.yaml")
    single = scene_file(SINGLE, "single.yaml")
    sets = ("parameters.e=0.3", "stop.time=13000", "ensemble.members=8")
    a = _json_stats(capsys, ens, *sets)
    s = _json_stats(capsys, single, "parameters.e=0.3", "stop.time=13000")
    low, high = a["mean_omega_ci95"]
    assert high - low < 1e-6 * abs(a["mean_omega"])
    assert a["mean_omega"] == pytest.approx(s["mean_omega"], rel=1e-9)
    assert a["regime"] == "periodic" and a["period"] == [2, 2]
    assert a["lyapunov"] < 0 and s["mean_omega_ci95"] == [None, None]


def test_regime_of_a_locked_chattering_cycle_and_its_exponent(scene_file, capsys):
    ens = scene_file(CHAOTIC, "ens.yaml")
    sets = ("parameters.e=0.5", "parameters.omega_s=1.126", "stop.time=8000")
    a = _json_stats(capsys, ens, *sets, "ensemble.members=4")
    assert a["regime"] == "chattering-periodic" and a["regime_fraction"] == 1.0
    # the cycle passes through a reset: exponent -inf, never positive
    assert a["lyapunov"] is None and a["lyapunov_reset_fraction"] == 1.0
    assert a["chatter_rate"] > 0.1


def test_confidence_interval_is_student_t():
    mean, low, high = confidence_interval([1.0, 2.0, 3.0, 4.0])
    # t_{0.975, 3} = 3.182446, s = 1.290994
    assert mean == 2.5 and high - mean == pytest.approx(3.182446 * 1.290994 / 2, rel=1e-6)
    assert all(math.isnan(x) for x in confidence_interval([5.0])[1:])
    assert confidence_interval([2.0, 2.0, 2.0])[1:] == (2.0, 2.0)


@pytest.mark.parametrize("k", [2, 3, 5, 32, 64, 1000])
@pytest.mark.parametrize("level", [0.9, 0.95, 0.99])
def test_confidence_interval_is_bit_identical_to_scipy_stats_t(k, level):
    """The interval's t quantile (scipy.special.stdtrit, light to import) is scipy.stats.t.ppf's
    to the last bit: the stored statistics do not move."""
    from scipy import stats as sps

    x = np.random.default_rng(k).normal(90.0, 5.0, k)
    mean, low, high = confidence_interval(x, level)
    half = float(sps.t.ppf(0.5 + level / 2.0, k - 1) * np.std(x, ddof=1) / math.sqrt(k))
    assert (mean, low, high) == (mean, mean - half, mean + half)


def test_t_half_width_is_per_column_and_matches_scipy_stats_t():
    """The one Student half-width: per time column of a (member, time) band, bit for bit the
    ``scipy.stats.t.ppf`` formula the band used; two members ``[0, 2]`` give ``t_{0.975,1} = 12.706``."""
    from scipy import stats as sps

    from bouncedisk.analysis.statistics import t_half_width, t_quantile

    assert t_quantile(1) == pytest.approx(12.7062047, rel=1e-8)
    assert t_half_width(np.array([0.0, 2.0])) == pytest.approx(12.7062047, rel=1e-8)
    om = np.random.default_rng(3).normal(1.0, 0.1, (7, 5))
    ref = sps.t.ppf(0.975, 6) * om.std(axis=0, ddof=1) / np.sqrt(7)
    assert np.array_equal(t_half_width(om, axis=0), ref)
    assert np.array_equal(t_half_width(om.T, axis=1), ref)


def test_run_stats_needs_a_time_stop(scene_file):
    f = scene_file(CHAOTIC.replace("stop: {time: 53000.0}", "stop: {impacts: 100}"))
    from bouncedisk.model.errors import InputError

    scene = load_scene(f, ["stats.discard=0"])
    with pytest.raises(InputError, match="stop.time"):
        run_stats(scene)


# -------------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    "override, field",
    [
        ("ensemble.members=0", "ensemble.members"),
        ("ensemble.members=-3", "ensemble.members"),
        ("ensemble.members=2.5", "ensemble.members"),
        ("parameters.e_sigma=-1.0e-9", "parameters.e_sigma"),
        ("parameters.e_sigma=.nan", "parameters.e_sigma"),
        ("stats.discard=53000.0", "stats.discard"),
        ("stats.discard=90000.0", "stats.discard"),
        ("effects=[impacts, contact, torsion]", "parameters.e_sigma"),
    ],
)
def test_bad_ensemble_input_exits_2_with_one_line_and_no_output(
    scene_file, tmp_path, capsys, override, field
):
    f = scene_file(CHAOTIC)
    out = tmp_path / "s.nc"
    assert main(["stats", str(f), "-o", str(out), "--set", override, "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(f) in err[0] and field in err[0]
    assert not out.exists() and list(tmp_path.iterdir()) == [f]


def test_members_without_noise_are_refused(scene_file, capsys):
    f = scene_file(SINGLE)
    assert main(["stats", str(f), "--set", "ensemble.members=4", "-q"]) == 2
    assert "restitution_noise" in capsys.readouterr().err


def test_output_that_is_not_a_regular_file_is_refused_before_work(scene_file, tmp_path, capsys):
    """A pipe (like /dev/null, a device) at -o is refused, not replaced by a file."""
    import os
    import stat

    f = scene_file(CHAOTIC)
    fifo = tmp_path / "pipe.nc"
    os.mkfifo(fifo)
    assert main(["stats", str(f), "-o", str(fifo), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "-o" in err[0] and "not a regular file" in err[0]
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert main(["stats", str(f), "-o", "", "-q"]) == 2
    assert "empty" in capsys.readouterr().err


def test_members_with_zero_noise_are_refused(scene_file, capsys):
    f = scene_file(CHAOTIC)
    assert main(["stats", str(f), "--set", "parameters.e_sigma=0", "-q"]) == 2
    err = capsys.readouterr().err
    assert "ensemble.members" in err and "e_sigma > 0" in err


def test_intervals_of_rates_stay_nonnegative(scene_file, capsys):
    """Few members and rare chatters: Student's interval would dip below 0; rates cannot."""
    s = _json_stats(
        capsys, scene_file(CHAOTIC), "ensemble.members=4", "stop.time=8000", "stats.discard=0"
    )
    for name in ("impact_rate", "chatter_rate", "chatter_interval"):
        low = s[f"{name}_ci95"][0]
        assert low is None or low >= 0.0, (name, s[f"{name}_ci95"])
    assert s["chatter_rate"] > 0 and s["chatter_rate_ci95"][0] == 0.0


def _member(k: int, regime: str) -> MemberStats:
    p = 1 if regime == "periodic" else 0
    return MemberStats(k, 1.0, 0.0, 1.0, 0.0, math.nan, 0.5, REGIME_CODES[regime], p, p, 10, 0, 1.0)


def test_a_regime_tie_is_reported_as_a_tie():
    tied = EnsembleStats([_member(0, "periodic"), _member(1, "chaotic")], 0.0, 1.0)
    s = tied.summary()
    assert s["regime_tie"] == ["periodic", "chaotic"] and s["regime_fraction"] == 0.5
    assert "tie between periodic and chaotic, 50% of members each" in format_summary(s)
    clear = EnsembleStats([_member(0, "chaotic"), _member(1, "chaotic"), _member(2, "periodic")], 0.0, 1.0)  # fmt: skip
    s = clear.summary()
    assert s["regime"] == "chaotic" and s["regime_tie"] == []
    assert "chaotic, 67% of members" in format_summary(s) and "tie" not in format_summary(s)


def test_a_statistic_some_members_lack_says_over_how_many_it_is():
    """The chatter interval of 2 of 3 members (one had fewer than two chatters): its mean and
    interval are theirs, and the table and JSON say so; with one member left, no interval."""
    members = [
        dataclasses.replace(_member(k, "chaotic"), chatter_interval=x)
        for k, x in enumerate((math.nan, 100.0, 140.0))
    ]
    s = EnsembleStats(members, 0.0, 1.0).summary()
    counted = s["members_with_value"]
    assert counted["chatter_interval"] == 2 and "lyapunov" not in counted
    assert s["chatter_interval"] == 120.0
    table = format_summary(s)
    assert "chatter_interval: 120  95% CI [" in table and "(2 of 3 members)" in table
    assert "lyapunov: 0.5  95% CI [0.5, 0.5]\n" in table  # every member: no count
    members[1] = dataclasses.replace(members[1], chatter_interval=math.nan)
    s = EnsembleStats(members, 0.0, 1.0).summary()
    assert "chatter_interval: 140  (1 of 3 members: no interval)" in format_summary(s)


def test_the_regime_fraction_counts_only_members_on_its_period():
    """Three of eight periodic members on period 1/1, five on 2/2: the ensemble is periodic
    [2, 2] in 5/8 of its members, not in all of them."""
    members = [_member(k, "periodic") for k in range(8)]
    members[3:] = [dataclasses.replace(m, period_p=2, period_q=2) for m in members[3:]]
    s = EnsembleStats(members, 0.0, 1.0).summary()
    assert s["regime"] == "periodic" and s["period"] == [2, 2]
    assert s["regime_fraction"] == 5 / 8


# ------------------------------------------------------------------------------ settled or not


def test_a_window_still_running_up_is_not_settled_and_a_long_one_is(capsys):
    """fig3's rotor runs up for about 2000 time units: a window of 200–600 averages a speed
    still rising (its second half faster), a window of 2000–5000 the settled speed."""
    scene = "workflow/config/scenes/fig3.yaml"
    early = run_stats(load_scene(scene, ["stop.time=600", "stats.discard=200"])).summary()
    late = run_stats(load_scene(scene, ["stop.time=5000", "stats.discard=2000"])).summary()
    assert early["settled"] == 0 and early["drift"] > 0.02 * early["mean_omega"]
    assert late["settled"] == 1 and abs(late["drift"]) < 0.02 * late["mean_omega"]
    assert late["mean_omega"] > early["mean_omega"]  # the early window read a run-up
    line = format_summary(early).splitlines()[3]
    assert line.startswith("           settled: NO, the second half's mean speed is ")
    assert line.endswith("lengthen stats.discard (and stop.time)")


def test_a_cycle_locked_to_the_stator_is_settled_whatever_its_ripple(monkeypatch):
    """A locked chattering cycle is stationary. Sampled 256 times over the window, a step of
    7.0003 stator periods here (the planted error), its samples' phases creep slowly through the
    cycle: each half's mean reads a different part of its ripple, and they differ by several
    percent. At the settling step's golden fraction of a period they agree."""
    import bouncedisk.analysis.settling as settling

    scene = load_scene("workflow/config/scenes/stats_locked.yaml", ["ensemble.members=2"])
    s = run_stats(scene).summary()
    assert s["settled"] == 1 and abs(s["drift"]) < 1e-3 * s["mean_omega"]
    step = settling.settle_step(0.0, 10_000.0, scene.params.omega_s)
    periods = step * scene.params.omega_s / (2 * math.pi)
    assert periods - math.floor(periods) == pytest.approx(settling.GOLDEN_FRACTION)
    monkeypatch.setattr(settling, "settle_step", lambda t0, t1, w: (t1 - t0) / 256)
    aliased = run_stats(scene).summary()
    assert aliased["settled"] == 0 and abs(aliased["drift"]) > 0.02 * aliased["mean_omega"]
    assert aliased["mean_omega"] == s["mean_omega"]  # the sampling changes no statistic


def test_a_rotor_in_flight_through_the_window_is_unresolved_and_one_at_rest_is_rest():
    """No event in the window is "rest" only with the rotor on the stator: at omega_s = 1000 the
    rotor's first flight outlasts the window (the helper's "rest" for a rotor in the air), at
    omega_s = 0.8 (Γ < 1) it never leaves the stator."""
    scene = "workflow/config/scenes/stats_e03.yaml"
    window = ["stop.time=1500", "stats.discard=300", "ensemble.members=2"]
    flight = run_stats(load_scene(scene, [*window, "parameters.omega_s=1000"])).summary()
    rest = run_stats(load_scene(scene, [*window, "parameters.omega_s=0.8"])).summary()
    assert flight["impact_rate"] == rest["impact_rate"] == 0.0
    assert flight["regime"] == "unresolved" and rest["regime"] == "rest"
    assert flight["audit_residual_axial"] < 1e-12  # round-off of the energies, not 1


def test_the_regime_fraction_carries_its_wilson_interval():
    """The fraction of members in the reported regime is a proportion of a sample: it carries
    Wilson's interval, as a basin's fraction does (closed form: all of n members)."""
    from bouncedisk.analysis.statistics import Z95, wilson

    scene = load_scene("workflow/config/scenes/stats_locked.yaml", ["ensemble.members=3"])
    s = run_stats(scene).summary()
    assert s["regime_fraction"] == 1.0
    assert s["regime_fraction_ci95"] == list(wilson(3, 3))
    assert s["regime_fraction_ci95"][0] == pytest.approx(3 / (3 + Z95**2), rel=1e-14)
    assert format_summary(s).splitlines()[-1].endswith("(95% CI [44%, 100%], Wilson)")


def test_settled_reads_the_members_mean_drift_not_member_zero():
    """The rule is the ensemble's: its members' mean drift against 2 % of the speed and three
    standard errors. Member 0 alone drifting (or alone not) decides nothing."""
    import dataclasses as dc

    scene = load_scene("workflow/config/scenes/stats_locked.yaml", ["ensemble.members=8"])
    base = run_stats(scene)
    scale = abs(base.summary()["mean_omega"])  # about 7.9: 2 % is about 0.16
    still = dc.replace(base, drift=np.array([0.0] + [0.4] * 7)).summary()
    assert still["settled"] == 0 and still["drift"] == pytest.approx(0.35)
    chance = dc.replace(base, drift=np.array([0.5, -0.5, 0.4, -0.4, 0.3, -0.3, 0.2, -0.2]))
    assert chance.summary()["settled"] == 1  # a mean of 0: member 0's +0.5 alone says nothing
    assert 0.02 * scale < 0.35


@pytest.mark.parametrize("periods", [100.0, 255.0, 256.5, 300.0, 1000.0])
def test_the_settling_step_reads_a_stationary_ripple_as_settled(periods):
    """A speed 10 + sin(omega_s t) locked to the stator, sampled at the settling step over
    windows of fewer and more than 256 periods: its halves' means agree to well under 2 % of
    10. At a step of the window over 256 (0.996 periods at 255) they differed by 1.3."""
    from bouncedisk.analysis.settling import settle_step

    w = 1.126
    window = periods * 2 * np.pi / w
    for step in (settle_step(0.0, window, w), window / 256):
        t = np.arange(0.0, window, step)
        om = 10.0 + np.sin(w * t)
        half = t < window / 2
        drift = om[~half].mean() - om[half].mean()
        if step == settle_step(0.0, window, w):
            assert abs(drift) < 0.02, (periods, drift)
    assert periods != 255.0 or abs(drift) > 0.5  # the planted error: the plain step aliases
