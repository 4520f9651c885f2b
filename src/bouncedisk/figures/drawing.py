"""Drawing a figure by name: the openers of its inputs and :data:`FIGURES`, the registry
:mod:`bouncedisk.figures.registry` resolved to functions.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr
from matplotlib.figure import Figure

from ..io.netcdf import open_checked, open_simulation
from .basins import fig_basin_map, fig_startup  # noqa: F401 (looked up by name)
from .cost import (
    fig_scaling,  # noqa: F401 (looked up by name)
    fig_stats_cost,  # noqa: F401 (looked up by name)
    fig_work_precision,  # noqa: F401 (looked up by name)
)
from .dynamics import (
    fig_bifurcation,  # noqa: F401 (looked up by name)
    fig_clipped_vs_bouncing,  # noqa: F401 (looked up by name)
    fig_poincare,  # noqa: F401 (looked up by name)
    fig_regime_map,  # noqa: F401 (looked up by name)
    fig_speed_vs_psi,  # noqa: F401 (looked up by name)
)
from .joint_fit import fig_fit_identifiability, fig_fit_load  # noqa: F401 (looked up by name)
from .load import fig_torque_speed  # noqa: F401 (looked up by name)
from .motor import (
    fig5_motor,
    fig_fit_profiles,  # noqa: F401 (looked up by name)
)
from .registry import FIGURES as DECLARED
from .registry import FigureDecl
from .schematic import fig2_schematic  # noqa: F401 (looked up by name)
from .sensitivity import (
    fig_design_maps,  # noqa: F401 (looked up by name)
    fig_sensitivity_indices,  # noqa: F401 (looked up by name)
    fig_sensitivity_scatter,  # noqa: F401 (looked up by name)
)
from .trajectory import fig_trajectory  # noqa: F401 (looked up by name)

# ----------------------------------------------------------------------------- the registry
Opener = Callable[[str], Any]


def _netcdf(*required: str, what: str = "netCDF") -> Opener:
    """An opener of a netCDF file that must hold the variables ``required``."""

    def open_(path: str) -> xr.Dataset:
        return open_checked(path, required=required, what=what)

    return open_


def _curve(path: str) -> dict[str, np.ndarray]:
    """A motor curve (CSV and sidecar) as the columns :func:`fig5_motor` draws."""
    from ..io.runup_curves import read_curve

    curve = read_curve(path)
    return {"time_s": curve.time, "omega_rad_s": curve.omega}


def _fig5_with_fit(curve: dict[str, np.ndarray], fit: xr.Dataset) -> Figure:
    """Fig. 5 from the curve and its fit file (:func:`fig5_motor`)."""
    return fig5_motor(curve, fitted=fit)


def _poincare_labelled(maps: Sequence[xr.Dataset], labels: Sequence[str]) -> Figure:
    """The Poincaré maps, each under its label (:func:`fig_poincare`)."""
    return fig_poincare(dict(zip(labels, maps, strict=True)))


@dataclass(frozen=True)
class FigureSpec:
    """How one kind of figure is drawn from files: a :class:`~.figure_registry.FigureDecl` resolved.

    Attributes
    ----------
    draw : callable
        Called as ``draw(*opened, **params)``: the opened inputs in the order of ``inputs``,
        then the figure's parameters (e.g. ``labels``); returns the Figure.
    inputs : mapping
        Input name -> the function that opens one path of it (a list of paths opens each).
    params : tuple of str
        The names of the parameters ``draw`` takes besides the inputs.
    """

    draw: Callable[..., Figure]
    inputs: Mapping[str, Opener] = field(default_factory=dict)
    params: tuple[str, ...] = ()


#: The openers of the figures' inputs, by the names :mod:`bouncedisk.figures.registry` gives.
OPENERS: dict[str, Opener] = {
    "simulation": open_simulation,
    "band": _netcdf("omega_mean", "omega_ci_low", what="band"),
    "curve": _curve,
    "fit": _netcdf("omega_measured", "omega_fitted", what="fit"),
    "poincare_map": _netcdf("phase", "v_rel"),
    "branch": _netcdf("phase", "is_chatter", "lyapunov"),
    "regime_sweep": _netcdf("regime", "lyapunov"),
    "psi_sweep": _netcdf("mean_omega", "mean_omega_ci_low"),
    "clipped_study": _netcdf("omega_rotor"),
    "csv": pd.read_csv,
    "sensitivity_indices": _netcdf("S1", "ST", "noise_share", what="sensitivity indices"),
    "sensitivity_points": _netcdf("x", "regime", what="sensitivity study"),
    "design_maps": _netcdf("x", "map_e", what="design maps"),
    "load_curve": _netcdf("mean_omega", "power_out", what="load curve"),
    "basins": _netcdf("label", "attractor_fraction", what="basins"),
    "startup": _netcdf("fast_fraction", "label", what="start-up under load"),
}


def _resolve(decl: FigureDecl) -> FigureSpec:
    """The drawing function and openers ``decl`` names, looked up in this module."""
    return FigureSpec(
        globals()[decl.draw], {key: OPENERS[o] for key, o in decl.inputs.items()}, decl.params
    )


#: Every figure the package draws, by name: :data:`bouncedisk.figures.registry.FIGURES` resolved.
FIGURES: dict[str, FigureSpec] = {name: _resolve(d) for name, d in DECLARED.items()}


def draw_figure(
    name: str, paths: Mapping[str, str | Sequence[str]], params: Mapping[str, Any] | None = None
) -> Figure:
    """Open the inputs of figure ``name`` (a key of :data:`FIGURES`) and draw it.

    Parameters
    ----------
    name : str
        The figure's kind, a key of :data:`FIGURES`.
    paths : mapping
        Input name -> a path, or a list of paths: the inputs the figure takes, each optional
        one (its drawing function's argument has a default, as ``trajectory``'s ``band``) left
        out or given.
    params : mapping, optional
        Exactly the parameters the figure takes (``FigureSpec.params``).

    Raises
    ------
    ValueError
        An unknown figure, or inputs or parameters other than the figure's.
    """
    spec = FIGURES.get(name)
    if spec is None:
        raise ValueError(f"unknown figure {name!r}; known figures: {', '.join(sorted(FIGURES))}")
    params = dict(params or {})
    optional = _optional_inputs(spec)
    for what, given, wanted, least in (
        ("inputs", set(paths), set(spec.inputs), set(spec.inputs) - optional),
        ("parameters", set(params), set(spec.params), set(spec.params)),
    ):
        if not least <= given <= wanted:
            takes = sorted(least) + [f"{k} (optional)" for k in sorted(wanted - least)]
            raise ValueError(f"figure {name!r} takes the {what} {takes}, given {sorted(given)}")
    opened = [
        None
        if key not in paths
        else [opener(str(p)) for p in paths[key]]
        if isinstance(paths[key], Sequence) and not isinstance(paths[key], str)
        else opener(str(paths[key]))
        for key, opener in spec.inputs.items()
    ]
    return spec.draw(*opened, **params)


def _optional_inputs(spec: FigureSpec) -> set[str]:
    """The inputs whose drawing-function argument (in the inputs' order) has a default."""
    args = list(inspect.signature(spec.draw).parameters.values())
    return {
        key
        for key, arg in zip(spec.inputs, args, strict=False)
        if arg.default is not inspect.Parameter.empty
    }
