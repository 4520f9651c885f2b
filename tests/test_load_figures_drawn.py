"""What the load and sensitivity figures draw: only stationary readings on the torque–speed
axes, no legend entry for a marker not drawn, indices outside [0, 1] clipped with a note, one
unit convention said on the axes, and no raw "log10 tau"."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from load_scenes import small_load_scene
from matplotlib.backends.backend_agg import FigureCanvasAgg

from bouncedisk.figures.load import fig_torque_speed
from bouncedisk.figures.sensitivity import fig_design_maps, fig_sensitivity_indices
from bouncedisk.studies.torque_speed import to_dataset, torque_speed


def _texts(fig) -> str:
    out = [t.get_text() for t in fig.texts]
    for ax in fig.axes:
        out += [ax.get_xlabel(), ax.get_ylabel(), ax.get_title()]
        out += [t.get_text() for t in ax.texts]
        leg = ax.get_legend()
        out += [t.get_text() for t in leg.get_texts()] if leg else []
    return "\n".join(out)


@pytest.fixture(scope="module")
def past_the_bound() -> xr.Dataset:
    """Fig. 3's motor swept to 1.3: past the momentum bound the runs never become stationary
    (the down branch starts from a rotor running away backwards)."""
    scene = small_load_scene(0.3, members=2, time=800.0, discard=150.0)
    return to_dataset(scene, torque_speed(scene, [0.0, 0.5, 0.9, 1.3]), 0.0)


def test_the_speed_axis_is_not_dominated_by_runs_that_never_became_stationary(past_the_bound):
    """torque_speed_fig3's speed axis ran from -1000 to 150: the runs past stall were drawn."""
    ds = past_the_bound
    assert ds["settled"].sel(load_torque=1.3).values.tolist() == [0, 0]
    fig = fig_torque_speed(ds)
    low, high = fig.axes[0].get_ylim()
    steady = ds["mean_omega"].values[ds["settled"].values.astype(bool)]
    span = steady.max() - min(steady.min(), 0.0)
    assert low >= min(steady.min(), 0.0) - 0.2 * span and high <= steady.max() + 0.2 * span
    assert float(ds["mean_omega"].values.min()) < low  # the unsettled readings: not drawn
    assert "not stationary" in _texts(fig)


def _indices(st_psi: float, n_points: int) -> xr.Dataset:
    outputs, params = ["no_load_speed", "log10_tau"], ["e", "omega_s", "log10_r_phi", "psi"]
    s = np.full((2, 4), 0.2)
    st = s.copy()
    st[0, 3] = st_psi
    dims = ("output", "parameter")
    data = {"S1": (dims, s), "S1_conf": (dims, s / 4), "ST": (dims, st), "ST_conf": (dims, s)}
    data.update({k: ("output", np.zeros(2)) for k in ("noise_share", "n_undefined")})
    ds = xr.Dataset(data, coords={"output": outputs, "parameter": params})
    ds.attrs.update({"n_points": n_points, "resolved_half_width": 0.1})
    return ds


def test_an_index_above_one_is_drawn_clipped_with_a_note_and_the_default_study_says_so():
    """S_T(psi) of the no-load speed was drawn as a bar to 1.20; "log10 tau" raw."""
    fig = fig_sensitivity_indices(_indices(1.2, 128 * 6))
    ax = fig.axes[0]
    assert max(p.get_height() for p in ax.patches) <= 1.0
    text = _texts(fig)
    assert "drawn clipped to [0, 1]: ST" in text and "1.20" in text
    assert "resolved only by the full study" in text
    assert "log10 tau" not in text and r"$\log_{10}\tau$" in text
    full = _texts(fig_sensitivity_indices(_indices(0.5, 1024 * 6)))
    assert "drawn clipped to" not in full and "full study" not in full


def _maps(stall: np.ndarray, power: tuple = (0.1, 0.3, 0.2, 0.1), n_r: int = 2) -> xr.Dataset:
    """A map of 2 psi by ``n_r`` R_phi (log10 from -3 to -1); ``stall`` and ``power`` of the
    2 x 2 corners, spread over the rows (the first row of a psi is its smallest R_phi)."""
    n_psi = 2
    psi, lr = np.meshgrid([-1.0, 1.0], np.linspace(-3.0, -1.0, n_r), indexing="ij")
    x = np.column_stack([np.full(psi.size, 0.3), np.full(psi.size, 1.5), lr.ravel(), psi.ravel()])
    data = {"x": (("point", "parameter"), x)}
    rows = np.round(np.linspace(0, 1, n_r)).astype(int)  # each row takes a corner's value

    def spread(v):
        return np.asarray(v, float).reshape(2, 2)[:, rows].ravel()

    values = {"no_load_speed": spread([1.0, 1.2, 1.1, 0.9]), "stall_torque": spread(stall),
              "max_power": spread(power) - 1e-3 * (lr.ravel() + 3.0) * (n_r > 2)}  # fmt: skip
    for name, v in values.items():
        data[name] = ("point", v)
        data[f"{name}_ci_low"], data[f"{name}_ci_high"] = ("point", v - 0.01), ("point", v + 0.01)
    ds = xr.Dataset(data, coords={"parameter": ["e", "omega_s", "log10_r_phi", "psi"]})
    ds = xr.concat([ds], dim="map").assign_coords(map_e=("map", [0.3]))
    ds.attrs.update({"map_n_psi": n_psi, "map_n_r_phi": n_r, "map_omega_s": 1.5})
    return ds


@pytest.mark.parametrize("power", [(0.3, 0.1, 0.2, 0.1), (0.1, 0.3, 0.2, 0.1)])
def test_the_design_maps_best_point_note_never_covers_the_star(power):
    """The note sat over the red star when the best point was at the smallest R_phi (e = 0.3
    of the pipeline's maps): it goes to the half of the panel away from the star."""
    fig = fig_design_maps(_maps(np.array([1.0, 0.9, 0.8, 0.7]), power, n_r=8))
    FigureCanvasAgg(fig).draw()
    ax = fig.axes[0]
    (star,) = [ln for ln in ax.get_lines() if ln.get_marker() == "*"]
    at = ax.transData.transform(np.column_stack([star.get_xdata(), star.get_ydata()]))[0]
    (note,) = [t for t in ax.texts if t.get_text().startswith("best ")]
    box = note.get_window_extent()
    assert not (box.y0 <= at[1] <= box.y1), (box, at)


def test_one_design_map_keeps_its_legend_within_the_figure_width():
    """With one map the legend's long lines ran far past the one-panel figure, and the saved
    figure's tight box widened to more than twice the panel."""
    fig = fig_design_maps(_maps(np.array([1.0, 0.9, 0.8, 0.7]), (0.3, 0.1, 0.2, 0.1)))
    FigureCanvasAgg(fig).draw()
    assert fig._suptitle.get_window_extent().width <= fig.bbox.width


def test_the_design_maps_legend_names_only_what_is_drawn_and_their_units():
    """The legend explained a black ring that no cell had; the maps' R_phi * mean(Omega)
    against the curves' mean(Omega) with no word."""
    text = _texts(fig_design_maps(_maps(np.array([1.0, 0.9, 0.8, 0.7]))))
    assert "black ring" not in text
    assert "edge of the swept range" in text  # the best point (R_phi = 0.1) is on its edge
    assert r"R_\phi" in text and "divided by" in text
    assert "black ring" in _texts(fig_design_maps(_maps(np.array([1.0, np.nan, 0.8, 0.7]))))


def test_the_design_maps_best_point_note_stays_inside_its_panel_and_the_panels_keep_their_width():
    """The note on the best point ran past its panel: the layout shrank every panel of its
    column to a sliver to make room for it, and the saved figure's tight box widened."""
    fig = fig_design_maps(_maps(np.array([1.0, 0.9, 0.8, 0.7])))
    FigureCanvasAgg(fig).draw()
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    for ax in panels:
        box = ax.get_window_extent()
        for t in ax.texts:
            inner = t.get_window_extent()
            assert box.x0 <= inner.x0 and inner.x1 <= box.x1 + 1.0, t.get_text()
        assert ax.get_position().width > 0.5, ax.get_title()  # one map: most of the figure
