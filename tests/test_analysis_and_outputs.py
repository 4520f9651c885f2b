"""Sweeps and shards, the clipped model, Poincaré datasets, checks and figures."""

import math
import re

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from matplotlib.figure import Figure

from bouncedisk.analysis.bands import omega_band
from bouncedisk.analysis.observables import REGIMES
from bouncedisk.analysis.poincare import poincare_dataset
from bouncedisk.analysis.sweeps import combine_shards, run_continuation, run_sweep
from bouncedisk.cli import main
from bouncedisk.engine import EngineConfig, simulate_arrays
from bouncedisk.figures import common, dynamics, motor, schematic, trajectory
from bouncedisk.figures import cost as figures_cost
from bouncedisk.io.netcdf import open_simulation
from bouncedisk.io.records import TrajColumn as C
from bouncedisk.model import stator
from bouncedisk.model.scene import scene_from_mapping
from bouncedisk.studies.clipped import clipped_comparison

#: its module fixtures are built once, on one worker (pytest-xdist ``--dist loadgroup``)
pytestmark = pytest.mark.xdist_group("analysis")

TORSION = {
    "name": "tq",
    "parameters": {"e": 0.6, "omega_s": 1.5, "r_phi": 0.01},
    "effects": ["impacts", "contact", "torsion"],
}
BASE = {
    "name": "sw",
    "parameters": {"e": 0.3, "omega_s": 1.5, "r_phi": 0.01, "e_sigma": 1e-9},
    "effects": ["impacts", "contact", "restitution_noise"],
    "stop": {"time": 1500.0},
    "ensemble": {"members": 3, "seed": 1},
    "stats": {"discard": 500.0},
}


def test_shards_join_to_the_unsharded_sweep(tmp_path):
    scene = scene_from_mapping(BASE)
    axes = [("e", np.linspace(0.1, 0.7, 5)), ("omega_s", np.array([1.5, 2.5]))]
    whole = run_sweep(scene, axes, tail=20)
    # the shards' points on 1, 2 and 3 threads: the numbers do not depend on how many run at once
    parts = [run_sweep(scene, axes, shard=i, n_shards=3, tail=20, cores=i + 1) for i in range(3)]
    joined = combine_shards(parts)
    for name in ("phase", "v_rel", "regime", "lyapunov", "mean_omega_ci_low", "n_events"):
        np.testing.assert_array_equal(joined[name].values, whole[name].values)
    steps = []
    threaded = run_sweep(scene, axes, tail=20, cores=2, progress=lambda d, n: steps.append((d, n)))
    assert steps == [(k, 10) for k in range(1, 11)]  # in grid order, every point once
    for name in whole.data_vars:
        np.testing.assert_array_equal(threaded[name].values, whole[name].values, err_msg=name)
    for i, p in enumerate(parts):
        p.to_netcdf(tmp_path / f"shard-{i}.nc")
    with xr.open_mfdataset(str(tmp_path / "shard-*.nc"), combine="by_coords") as mf:
        np.testing.assert_array_equal(mf["regime"].values, whole["regime"].values)

    # docs/model.md's regimes show up at omega_s = 1.5: a locked chattering cycle at e = 0.1 (exponent
    # -inf in every member), the period-2 orbit at e = 0.3, chaos at e = 0.6
    pts = run_sweep(scene, [("e", np.array([0.1, 0.3, 0.6])), ("omega_s", np.array([1.5]))])
    pts = pts.isel(omega_s=0)
    reg = pts["regime"].values
    assert [REGIMES[int(c)] for c in reg] == ["chattering-periodic", "periodic", "chaotic"]
    assert int(pts["period_p"].sel(e=0.3)) == 2 and int(pts["period_q"].sel(e=0.3)) == 2
    assert float(pts["lyapunov_reset_fraction"].sel(e=0.1)) == 1.0
    assert float(pts["lyapunov_ci_low"].sel(e=0.6)) > 0.5
    # a periodic point: every member the same, an interval of zero width
    w = pts.sel(e=0.3)
    assert float(w["mean_omega_ci_high"] - w["mean_omega_ci_low"]) == pytest.approx(0, abs=1e-6)


def test_a_sweeps_threads_run_members_in_order_a_bounded_number_ahead(monkeypatch):
    """Results in the tasks' order, and never more than ``ahead`` tasks submitted and not taken:
    a sweep's memory does not grow with its grid."""
    from concurrent.futures import ThreadPoolExecutor

    from bouncedisk.analysis import sweeps

    pulled = []
    monkeypatch.setattr(sweeps, "run_member", lambda cfg, init, member, t_from: member)

    def tasks():
        for i in range(100):
            pulled.append(i)
            yield (None, None, i, 0.0)

    out = []
    with ThreadPoolExecutor(2) as pool:
        for result in sweeps._ordered_runs(pool, tasks(), ahead=5):
            out.append(result)
            assert len(pulled) <= len(out) + 5
    assert out == list(range(100))


def test_continuation_follows_both_coexisting_attractors():
    """e in [0.19, 0.25] at omega_s = 1.5: sweeping down follows the period-1 orbit, sweeping up
    stays on the coexisting locked chattering cycles (docs/model.md "Regimes")."""
    scene = scene_from_mapping(BASE)
    values = np.linspace(0.12, 0.3, 10)
    up = run_continuation(scene, "e", values, "up", tail=20)
    down = run_continuation(scene, "e", values, "down", tail=20)
    sel = dict(e=slice(0.19, 0.25))
    # up: never the period-1 orbit there, and locked chattering cycles (the other attractor)
    up_sel = up.sel(**sel)
    assert not ((up_sel["regime"] == 1) & (up_sel["period_p"] == 1)).any()
    assert "chattering-periodic" in {REGIMES[int(c)] for c in up_sel["regime"].values}
    assert set(down["regime"].sel(**sel).values) == {1}  # periodic
    assert set(down["period_p"].sel(**sel).values) == {1}
    assert (down["lyapunov"].sel(**sel) < 0).all()
    np.testing.assert_array_equal(up["e"].values, down["e"].values)


def test_clipped_model_rides_the_stator_and_coasts_when_unloaded():
    cfg = EngineConfig(
        e=0.6, omega_s=1.5, r_phi=0.01, torsion=True, t_end=60.0, traj_dt=0.01, clipped=True
    )
    res = simulate_arrays(cfg)
    tr = res.traj
    assert len(res.events["t"]) == 0
    np.testing.assert_array_equal(tr[:, C.U], tr[:, C.U_STATOR])
    # where 1 - w² sin(wt) < 0 there is no torque: omega is constant there
    unloaded = stator.normal_load(1.5 * tr[:, C.T], 1.5) < -0.05
    runs = np.flatnonzero(np.diff(unloaded.astype(int)))
    seg = slice(runs[0] + 2, runs[1] - 1)
    assert unloaded[seg].all() and np.ptp(tr[seg, C.OMEGA]) < 1e-12
    with pytest.raises(Exception, match="stop"):
        scene_from_mapping({**BASE, "model": "clipped", "stop": {"impacts": 600}, "stats": {}})


def test_clipped_comparison_dataset():
    scene = scene_from_mapping(
        {**TORSION, "stop": {"time": 50.0}, "outputs": {"trajectory": {"dt": 0.5}}}
    )
    ds = clipped_comparison(scene, [0.0, 1.0], members=4)
    assert ds["omega_rotor"].dims == ("model", "psi", "time")
    # the bouncing model's ensemble band brackets its mean
    mean = ds["omega_bouncing_mean"]
    assert (ds["omega_bouncing_ci_low"] <= mean + 1e-12).all()
    assert (mean <= ds["omega_bouncing_ci_high"] + 1e-12).all()
    assert (ds["omega_bouncing_p025"] <= ds["omega_bouncing_p975"]).all()
    assert not np.array_equal(
        ds["omega_rotor"].sel(model="bouncing").values,
        ds["omega_rotor"].sel(model="clipped").values,
    )


@pytest.fixture(scope="module")
def sim_file(tmp_path_factory):
    d = tmp_path_factory.mktemp("sim")
    f = d / "pe.yaml"
    f.write_text(
        "name: pe\nparameters: {e: 0.3, omega_s: 1.5, r_phi: 0.01}\n"
        "effects: [impacts, contact, torsion]\nstop: {impacts: 3000}\n"
        "outputs: {events: true, stroboscopic: true, trajectory: {dt: 0.1}}\n"
    )
    out = d / "pe.nc"
    assert main(["simulate", str(f), "-o", str(out), "-q"]) == 0
    return out


def test_poincare_dataset(sim_file):
    ds = poincare_dataset(open_simulation(sim_file), transient=1000)
    assert ds.sizes["impact"] == 2000
    assert np.ptp(np.sort(ds["phase"].values[-2:])) > 0.5  # the two phases of the period-2 orbit
    assert ds.attrs["source_run_id"] != ds.attrs["run_id"]


def test_check_command_passes_and_writes_markdown(tmp_path, capsys):
    md = tmp_path / "rep.md"
    assert main(["check", "-o", str(md)]) == 0
    text = md.read_text()
    assert "period-2" in text and "**FAIL**" not in text
    assert "14 passed, 0 failed" in capsys.readouterr().out  # 7 of the paper, 6 under load, basins


def test_every_figure_function_returns_a_figure(sim_file, tmp_path):
    sim = open_simulation(sim_file)
    scene = scene_from_mapping(BASE)
    sweep2 = run_sweep(
        scene, [("e", np.array([0.2, 0.5])), ("omega_s", np.array([1.5, 2.0]))], tail=10
    )
    psi = run_sweep(
        scene_from_mapping(
            {**BASE, "effects": ["impacts", "contact", "torsion", "restitution_noise"]}
        ),
        [("psi", np.array([-1.0, 1.0])), ("r_phi", np.array([0.01, 0.1]))],
        tail=5,
    )
    pmap = poincare_dataset(sim, transient=100)
    cont = [run_continuation(scene, "e", np.array([0.2, 0.3]), d, tail=5) for d in ("up", "down")]
    traj = {"trajectory": {"dt": 0.1}}
    band = omega_band(scene_from_mapping({**TORSION, "stop": {"impacts": 50}, "outputs": traj}), 3)
    clipped = clipped_comparison(
        scene_from_mapping({**TORSION, "stop": {"time": 30.0}, "outputs": traj}), [0.0], members=3
    )
    cost = pd.DataFrame(
        {"members": [2, 4], "duration": [10.0, 10.0], "member_time": [20.0, 40.0],
         "cpu_s": [0.1, 0.2], "mean_omega": [1.0, 1.1], "ci_low": [0.5, 0.8],
         "ci_high": [1.5, 1.4], "half_width": [0.5, 0.3]}
    )  # fmt: skip
    singles = pd.DataFrame({"de": [0.0, 1e-9], "mean_omega": [1.0, 1.3]})
    wp = pd.DataFrame(
        {
            "case": ["c"] * 2,
            "solver": ["exact", "Moreau-Jean"],
            "cpu_s": [1e-4, 1e-2],
            "error": [1e-15, 1e-3],
        }
    )
    sc = pd.DataFrame(
        {
            "study": ["omega", "impacts", "memory"],
            "omega_s": [1.5] * 3,
            "n_impacts": [1e3, 1e3, 1e3],
            "s_per_impact": [1e-6, math.nan, math.nan],
            "seconds": [1e-3, 1e-3, math.nan],
            "peak_mb": [math.nan, math.nan, 200],
        }
    )
    curve = pd.DataFrame({"time_s": np.linspace(0, 1, 50), "omega_rad_s": np.linspace(0, 1, 50)})
    figs = [
        schematic.fig2_schematic(),
        trajectory.fig_trajectory(sim),
        trajectory.fig_trajectory(sim, band=band),
        dynamics.fig_clipped_vs_bouncing(clipped),
        figures_cost.fig_stats_cost(cost, singles),
        dynamics.fig_poincare({"a": pmap}),
        dynamics.fig_bifurcation(*cont),
        dynamics.fig_regime_map(sweep2),
        dynamics.fig_speed_vs_psi(psi),
        figures_cost.fig_work_precision(wp),
        figures_cost.fig_scaling(sc),
        motor.fig5_motor(curve, simulated=curve),
    ]
    for i, fig in enumerate(figs):
        assert isinstance(fig, Figure)
        common.save_figure(fig, tmp_path / f"f{i}.png")
        assert (tmp_path / f"f{i}.png").stat().st_size > 1000


def test_save_figure_lays_out_once_and_crops_every_format_to_the_same_box(tmp_path):
    """The PDF and the PNG of one figure: both cropped to the figure's tight box (the PNG's
    pixels are that box at its dpi, as a save of its own gives them), the layout frozen after
    the first save (no layout engine left), and the PDF's page the same box in points."""
    from PIL import Image, ImageChops

    def draw():
        fig = Figure(figsize=(6, 3), layout="constrained")
        for k, ax in enumerate(fig.subplots(1, 2)):
            ax.plot([0, 1], [0, k + 1])
            ax.set_xlabel("a long label that reaches below the axes")
            ax.set_title(f"panel {k}")
        return fig

    fig = draw()
    common.save_figure(fig, tmp_path / "a.pdf", tmp_path / "a.png", dpi=100)
    assert fig.get_layout_engine() is None
    alone = draw()
    alone.savefig(tmp_path / "alone.png", dpi=100, bbox_inches="tight")
    png, alone = (Image.open(tmp_path / n).convert("RGB") for n in ("a.png", "alone.png"))
    (width, height), (w0, h0) = png.size, alone.size
    assert abs(width - w0) <= 3 and abs(height - h0) <= 3, ((width, height), (w0, h0))
    # the content sits where a save of its own puts it: the box is not only as large, but there
    white = Image.new("RGB", png.size, "white")
    inked = ImageChops.difference(png, white).getbbox()
    inked0 = ImageChops.difference(alone, Image.new("RGB", alone.size, "white")).getbbox()
    assert max(abs(a - b) for a, b in zip(inked, inked0, strict=True)) <= 3, (inked, inked0)
    pdf = (tmp_path / "a.pdf").read_bytes()
    box = [float(v) for v in re.search(rb"/MediaBox \[ *([^\]]+)\]", pdf).group(1).split()]
    assert abs(box[2] * 100 / 72 - width) <= 3 and abs(box[3] * 100 / 72 - height) <= 3, box
