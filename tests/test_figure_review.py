"""The figures reviewed as a referee would: no empty or clipped panel, no legend over the data,
lab units, markers only where there is something to mark (bouncedisk.figures.review)."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from load_scenes import small_load_scene
from matplotlib.figure import Figure

from bouncedisk.figures.cost import fig_scaling, fig_stats_cost, fig_work_precision
from bouncedisk.figures.load import fig_torque_speed
from bouncedisk.figures.review import legend_overlaps, panel_problems
from bouncedisk.studies.torque_speed import motor_scene, to_dataset, torque_speed


# ----------------------------------------------------------------------------- the review itself
def test_the_review_finds_an_empty_panel_and_a_clipped_one():
    fig = Figure()
    a, b, c = fig.subplots(1, 3)
    a.plot([0, 1, 2], [0, 1, 4])
    b.axhline(0.0)  # a reference line is not data
    c.plot([0, 1, 2], [0, 1, 4])
    c.set_ylim(0, 2)  # the point at 4 is drawn nowhere
    problems = panel_problems(fig)
    assert len(problems) == 2
    assert "empty" in problems[0] and "1 of 3 data points outside" in problems[1]


def test_the_review_counts_bands_and_log_axes():
    fig = Figure()
    a, b = fig.subplots(1, 2)
    a.fill_between([0, 1], [0, 0], [5, 5])
    a.set_ylim(0, 4)
    b.loglog([1, 10], [0.0, 1.0])  # a zero on a log axis is drawn nowhere
    assert len(panel_problems(fig)) == 2


def test_the_review_finds_a_legend_over_the_data():
    fig = Figure()
    ax = fig.add_subplot()
    x = np.linspace(0, 1, 200)
    ax.plot(x, np.ones_like(x), label="flat")
    ax.legend(loc="center")
    assert legend_overlaps(fig)
    ax.legend(loc="lower left")
    assert not legend_overlaps(fig)


# ----------------------------------------------------------------------------- load curves
@pytest.fixture(scope="module")
def curves() -> dict[str, xr.Dataset]:
    scene = small_load_scene(0.6, members=3, time=600.0, discard=100.0)
    past = to_dataset(scene, torque_speed(scene, np.linspace(0.0, 1.1, 6)), 0.0)
    short = to_dataset(scene, torque_speed(scene, [0.0, 0.1, 0.2]), 0.0)
    from bouncedisk.model.params import Parameters

    p = Parameters(e=0.57, omega_s=1.67, r_phi=0.002, psi=0.28, e_sigma=0.03)
    rotor = {"m_r_kg": 0.01, "r_g_m": 0.004, "r_c_m": 0.002}
    phys = motor_scene(p, 20000.0, 2e-4, rotor, 0.77, 3, 600.0, 100.0)
    proto = to_dataset(phys, torque_speed(phys, np.linspace(0.0, 1.0, 5)), 0.0)
    return {"past": past, "short": short, "physical": proto}


def _texts(fig: Figure) -> str:
    out = [t.get_text() for t in fig.texts]
    for ax in fig.axes:
        out += [ax.get_xlabel(), ax.get_ylabel(), ax.get_title()]
        leg = ax.get_legend()
        out += [t.get_text() for t in leg.get_texts()] if leg else []
    return "\n".join(out)


@pytest.mark.parametrize("which", ["past", "short", "physical"])
def test_load_figures_have_no_empty_or_clipped_panel_and_no_raw_underscores(curves, which):
    fig = fig_torque_speed(curves[which])
    assert panel_problems(fig) == []
    # an underscore outside mathtext is drawn raw (ω_s, Γ_PD)
    assert "_" not in re.sub(r"\$[^$]*\$", "", _texts(fig))


def test_the_physical_load_figure_is_in_lab_units(curves):
    text = _texts(fig_torque_speed(curves["physical"]))
    assert "mN·m" in text and "mW" in text and "rad/s" in text
    assert "N·m]" not in text.replace("mN·m]", "") and "[W]" not in text


def test_a_curve_that_stays_positive_says_where_the_stall_and_maximum_are(curves):
    ds = curves["short"]
    assert ds.attrs["stall_torque_state"] == "beyond_largest_load"
    text = _texts(fig_torque_speed(ds))
    assert "stall torque: beyond the largest load" in text
    # a power still rising at the largest load is no "max. power at load ..."
    if ds.attrs["max_power_state"] != "found":
        assert "max. power at" not in text and "max. power:" in text


def test_a_curve_past_stall_marks_the_stall_torque_and_a_real_maximum(curves):
    ds = curves["past"]
    assert ds.attrs["stall_torque_state"] == "found"
    text = _texts(fig_torque_speed(ds))
    assert f"stall torque {ds.attrs['stall_torque']:.3g}" in text
    assert ("max. power" in text) and ("95% interval" in text)


# ----------------------------------------------------------------------------- cost figures
def test_cost_figures_hold_their_data_and_say_what_errors_are_against():
    wp = pd.DataFrame({
        "case": ["c"] * 4, "solver": ["exact", "exact", "ivp", "ivp"],
        "cpu_s": [1e-4, 2e-4, 0.1, 0.2], "error": [0.0, 1e-15, 1e-3, 1e-6],
    })  # fmt: skip
    fig = fig_work_precision(wp)
    assert panel_problems(fig) == []
    assert "reference" in fig.texts[0].get_text() if fig.texts else fig._suptitle.get_text()
    table = pd.DataFrame({
        "study": ["omega", "omega", "impacts", "impacts", "memory", "memory"],
        "omega_s": [1.5, 3.0, 1.5, 1.5, 1.5, 1.5], "s_per_impact": [3e-7, 6e-7, np.nan, np.nan, np.nan, np.nan],
        "n_impacts": [np.nan, np.nan, 1e3, 1e6, 1e3, 1e6], "seconds": [np.nan, np.nan, 1e-3, 0.5, np.nan, np.nan],
        "peak_mb": [np.nan, np.nan, np.nan, np.nan, 254.0, 266.0],
    })  # fmt: skip
    fig = fig_scaling(table)
    assert panel_problems(fig) == []
    assert fig.axes[2].get_yscale() == "linear"  # 254–266 MB: no log axis over a few percent
    # each panel names its motor; the effects' costs drawn when the table has them
    effects = pd.DataFrame(
        {"study": ["effects"] * 2, "effect": ["axial only", "+ torsion"], "e": [0.6, 0.6]}
    ).assign(omega_s=1.5, s_per_impact=[1.4e-6, 1.6e-6])
    fig = fig_scaling(pd.concat([table.assign(e=0.3), effects], ignore_index=True))
    assert panel_problems(fig) == [] and len(fig.axes) == 4
    assert "e = 0.3" in fig.axes[0].get_title() and r"$\omega_s$ = 1.5" in fig.axes[3].get_title()
    assert fig.get_suptitle()
    cost = pd.DataFrame({
        "duration": [5000, 5000, 20000, 20000], "cpu_s": [0.01, 0.04, 0.02, 0.08],
        "half_width": [3.7, 1.0, 2.0, 0.6], "member_time": [1, 2, 3, 4], "members": [4, 16, 4, 16],
        "ci_low": [90, 90, 90, 91.4], "ci_high": [93, 93, 93, 92.0], "mean_omega": [91.7] * 4,
    })  # fmt: skip
    singles = pd.DataFrame({"de": np.arange(5) * 1e-9, "mean_omega": [98, 92, 95, 90, 93.0]})
    fig = fig_stats_cost(cost, singles)
    assert panel_problems(fig) == []
    fig.canvas.draw()
    labels = [t.get_text() for t in fig.axes[0].get_yticklabels() if t.get_text()]
    assert len(labels) >= 2  # not a single tick label on a log axis
