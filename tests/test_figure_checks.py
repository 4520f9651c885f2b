"""The referee's checks that span a figure's meaning (bouncedisk.figures.review): no axis given
over to runs that never became stationary, no legend or colour bar naming what is not drawn,
one unit per quantity across the figures a reader compares; each fails on a planted fault, and
the figures of coexisting motions and of the regime map pass them. Small in-memory figures."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure

from bouncedisk.figures.basins import fig_basin_map, fig_startup
from bouncedisk.figures.dynamics import fig_regime_map
from bouncedisk.figures.review import (
    NOT_STATIONARY,
    legend_ghosts,
    panel_problems,
    unit_conflicts,
    unsteady_dominance,
)
from bouncedisk.studies import basins as B

LOADS = np.linspace(0.0, 1.0, 11)
SPEEDS = 150.0 * (1.0 - LOADS)  # a stationary operating curve, 150 at no load to 0 at stall


def _torque_speed(past_stall: np.ndarray, **style) -> Figure:
    fig = Figure()
    ax = fig.add_subplot()
    ax.plot(LOADS, SPEEDS, "o-", label="stationary")
    ax.plot(np.linspace(1.0, 1.1, len(past_stall)), past_stall, "x", **style)
    ax.set_xlabel("load torque")
    ax.set_ylabel("mean speed")
    return fig


# ----------------------------------------------------------------------------- never stationary
def test_an_axis_given_over_to_runs_never_stationary_is_found():
    # past stall the runs still accelerate backwards: their "means" reach -1000 and squash the
    # operating curve into the top fifth of the axis
    fig = _torque_speed(np.array([-200.0, -600.0, -1000.0]), gid=NOT_STATIONARY)
    problems = unsteady_dominance(fig)
    assert len(problems) == 1 and "79 % of the y span" in problems[0]
    # named by its legend label alone, the same
    fig = _torque_speed(np.array([-200.0, -600.0, -1000.0]), label="not stationary")
    assert unsteady_dominance(fig)
    # a few such runs near the curve take little of the axis; stationary runs count as data
    assert unsteady_dominance(_torque_speed(np.array([-5.0, -20.0]), gid=NOT_STATIONARY)) == []
    assert unsteady_dominance(_torque_speed(np.array([-200.0, -600.0, -1000.0]))) == []


def test_runs_never_stationary_on_a_log_axis_are_weighed_in_decades():
    fig = Figure()
    ax = fig.add_subplot()
    ax.loglog([1, 10], [1.0, 10.0])
    ax.loglog([10, 20], [1e4, 1e6], gid=NOT_STATIONARY)  # five decades for a curve of one
    assert any("y span" in p for p in unsteady_dominance(fig))


# ----------------------------------------------------------------------------- legend ghosts
def test_a_legend_naming_what_is_not_drawn_is_found():
    fig = Figure()
    ax = fig.add_subplot()
    ax.scatter([0, 1], [0, 1], c="C0", label="cells")
    ax.scatter([], [], facecolor="none", edgecolor="k", label="black ring: the best cell")
    ax.plot([0, 1], [np.nan, np.nan], color="C3", label="a curve with no finite point")
    ax.legend()
    problems = legend_ghosts(fig)
    assert len(problems) == 2
    assert "black ring" in problems[0] and "no finite point" in problems[1]
    # a proxy entry in a colour that is drawn, and a text-only entry, name nothing missing
    fig = Figure()
    ax = fig.add_subplot()
    ax.scatter([0, 1], [0, 1], c=[0, 1], cmap=ListedColormap(["C0", "C1"]))
    ax.scatter([], [], color="C1", marker="s", label="attractor 1")
    ax.plot([], [], ls="none", marker="none", label="not settled: 0 of 2")
    ax.axvline(0.5, color="0.4", ls="--", label="a threshold")  # a reference line is drawn
    ax.legend()
    fig.legend(*ax.get_legend_handles_labels())  # a figure legend is read alike
    assert legend_ghosts(fig) == []


def test_a_categorical_colour_bar_naming_a_class_no_cell_shows_is_found():
    fig = Figure()
    ax = fig.add_subplot()
    cmap = ListedColormap(["0.75", "C2", "C3", "C4"])
    norm = BoundaryNorm(np.arange(-0.5, 4.5), cmap.N)
    m = ax.pcolormesh(np.array([[0, 1], [2, 1]]), cmap=cmap, norm=norm)
    cb = fig.colorbar(m, ax=ax, ticks=range(4))
    cb.ax.set_yticklabels(["unresolved", "periodic", "chaotic", "rest"])
    assert legend_ghosts(fig) == ["colour bar names 'rest', which no cell shows"]


# ----------------------------------------------------------------------------- units
def _axis(ylabel: str, xlabel: str = "load torque") -> Figure:
    fig = Figure()
    ax = fig.add_subplot()
    ax.plot([0, 1], [0, 1])
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    return fig


def test_one_quantity_in_two_units_across_figures_is_found():
    figures = {
        "curves": _axis(r"max power $P$"),
        "maps": _axis(r"max power $R_\phi P$ (stator units)"),
        "prototype": _axis("max power [mW]", "load torque [mN·m]"),
    }
    problems = unit_conflicts(figures)
    assert len(problems) == 2
    power = next(p for p in problems if p.startswith("'max power'"))
    assert "in 3 units" in power and "stator units (maps)" in power and "mW (prototype)" in power
    assert any(p.startswith("'load torque'") for p in problems)
    same = {"a": _axis("max power [mW]"), "b": _axis(r"Max power $P$ [mW]")}
    assert unit_conflicts(same) == []


# ----------------------------------------------------------------------------- the figures
def _basins(settled: bool) -> xr.Dataset:
    """Eight starts by hand (phases 0 and 2, speeds 0 and 50, heights 0 and 0.5): resting on
    the stator every start reaches 144, released 0.5 above it 78 (a height the map does not
    draw), and, unless ``settled``, one resting start is still drifting."""
    n = 8
    mean = np.repeat([144.0, 78.0], 4)
    drift = np.zeros(n) if settled else np.array([0, 0, 0, 5.0, 0, 0, 0, 0])
    ds = xr.Dataset(
        {
            "phase": ("start", np.tile([0.0, 2.0], 4)),
            "speed": ("start", np.tile(np.repeat([0.0, 50.0], 2), 2)),
            "height": ("start", np.repeat([0.0, 0.5], 4)),
            "mean_omega": ("start", mean),
            "mean_omega_first_half": ("start", mean - drift / 2),
            "mean_omega_second_half": ("start", mean + drift / 2),
            "regime": ("start", np.ones(n, np.int64)),
            "period_p": ("start", np.full(n, 2)),
            "period_q": ("start", np.full(n, 2)),
            "n_impacts": ("start", np.full(n, 100)),
            "orbit_phases": (("start", "orbit_slot"), np.full((n, B.ORBIT_SLOTS), np.nan)),
        },
        coords={"start": np.arange(n)},
        attrs={"window": [4000.0, 8000.0], "omega_s": 1.5, "e": 0.3, "speeds": [0.0, 50.0]},
    )
    ds["orbit_phases"][:, :2] = [0.5, 2.0]
    ds["orbit_phases"][4:, :2] = [1.0, 3.0]
    return B.group(ds)


@pytest.mark.parametrize("settled", [True, False])
def test_the_basin_map_names_only_what_it_draws(settled):
    ds = _basins(settled)
    assert ds.attrs["unsettled_starts"] == (0 if settled else 1)
    fig = fig_basin_map(ds)
    assert legend_ghosts(fig) == [] and panel_problems(fig) == []
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "reached from none of the starts drawn" in texts[1]  # 78: from height 0.5 only
    assert ("none among the starts drawn" in texts[-1]) == settled


def test_the_start_up_figure_draws_all_three_fractions_and_names_them():
    loads = np.array([0.0, 0.05, 0.1])
    data = {
        "fast_fraction": [1.0, 0.5, 0.0],
        "slow_fraction": [0.0, 0.25, 1.0],
        "unsettled_fraction": [0.0, 0.25, 0.0],
    }
    ds = xr.Dataset(coords={"load_torque": loads, "start": np.arange(4)})
    for name, v in data.items():
        ds[name] = ("load_torque", np.array(v))
        ds[f"{name}_ci95_low"] = ds[name] - 0.1
        ds[f"{name}_ci95_high"] = ds[name] + 0.1
    ds.attrs.update({"fast_above": 110.0, "window": [4000.0, 8000.0], "extend": 3, "e": 0.3})
    fig = fig_startup(ds)
    assert legend_ghosts(fig) == [] and unsteady_dominance(fig) == []
    ax = fig.axes[0]
    assert [line.get_ydata().tolist() for line in ax.lines] == list(data.values())
    assert r"$\geq$" in ax.get_legend().get_texts()[0].get_text()  # no raw ">="
    assert "doubled up to 8x" in ax.get_title()


def test_the_regime_map_lists_only_the_regimes_it_draws():
    e, w = np.linspace(0.1, 0.9, 4), np.linspace(1.0, 2.0, 3)
    reg = np.array([[0, 1, 3, 3], [1, 2, 3, 4], [2, 2, 4, 4]], np.int64).T  # no "rest"
    lam = np.where(reg == 2, np.nan, 0.5)  # a chattering cycle resets: no finite exponent
    ds = xr.Dataset(
        {
            "regime": (("e", "omega_s"), reg),
            "period_p": (("e", "omega_s"), np.where(reg == 1, 2, 0)),
            "lyapunov": (("e", "omega_s"), lam),
            "chatter_rate": (("e", "omega_s"), np.zeros_like(lam)),
        },
        coords={"e": e, "omega_s": w},
        attrs={"ensemble_members": 4},
    )
    fig = fig_regime_map(ds)
    assert legend_ghosts(fig) == [] and panel_problems(fig) == []
    labels = [t.get_text() for t in fig.axes[3].get_yticklabels()]
    drawn = ["unresolved", "periodic", "chattering-periodic", "chaotic-reinjection", "chaotic"]
    assert labels == drawn
    # -inf is black, unlike the grey of "unresolved" beside it
    assert fig.axes[1].get_facecolor()[:3] == (0.0, 0.0, 0.0)
