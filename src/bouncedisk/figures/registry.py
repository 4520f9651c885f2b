"""The figures the package draws, declared without drawing anything.

Each figure's name, the inputs and parameters it takes, and where its drawing function and the
openers of its inputs live. This module imports only the standard library, so the pipeline's
Snakefile (``workflow/rules/figure_table.smk``) can check its figure table against it at parse
time without importing matplotlib, xarray or pandas. :data:`bouncedisk.figures.drawing.FIGURES` is built
from it, each name resolved to its function, and :func:`bouncedisk.figures.drawing.draw_figure` draws.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

#: The module that holds every drawing function and :data:`OPENERS <bouncedisk.figures.drawing.OPENERS>`.
DRAWING_MODULE = "bouncedisk.figures.drawing"


@dataclass(frozen=True)
class FigureDecl:
    """What one kind of figure takes, and which function draws it.

    Attributes
    ----------
    draw : str
        The name of the drawing function in :data:`DRAWING_MODULE`, called as
        ``draw(*opened, **params)``: the opened inputs in the order of ``inputs``, then the
        parameters.
    inputs : mapping
        Input name -> the name of the opener of one path of it, a key of
        ``bouncedisk.figures.drawing.OPENERS`` (a list of paths opens each).
    params : tuple of str
        The names of the parameters ``draw`` takes besides the inputs.
    """

    draw: str
    inputs: Mapping[str, str] = field(default_factory=dict)
    params: tuple[str, ...] = ()


#: Every figure the package draws, by name (the pipeline's figure table names one per figure).
FIGURES: dict[str, FigureDecl] = {
    "fig2": FigureDecl("fig2_schematic"),
    "trajectory": FigureDecl("fig_trajectory", {"sim": "simulation", "band": "band"}),
    "fig5": FigureDecl("_fig5_with_fit", {"curve": "curve", "fit": "fit"}),
    "fit_profiles": FigureDecl("fig_fit_profiles", {"fit": "fit"}),
    "fit_load": FigureDecl("fig_fit_load", {"fit": "fit"}),
    "fit_identifiability": FigureDecl("fig_fit_identifiability", {"fit": "fit"}),
    "poincare": FigureDecl("_poincare_labelled", {"maps": "poincare_map"}, params=("labels",)),
    "bifurcation": FigureDecl("fig_bifurcation", {"up": "branch", "down": "branch"}),
    "regime_map": FigureDecl("fig_regime_map", {"sweep": "regime_sweep"}),
    "speed_vs_psi": FigureDecl("fig_speed_vs_psi", {"sweep": "psi_sweep"}),
    "clipped": FigureDecl("fig_clipped_vs_bouncing", {"study": "clipped_study"}),
    "work_precision": FigureDecl("fig_work_precision", {"table": "csv"}),
    "scaling": FigureDecl("fig_scaling", {"table": "csv"}),
    "stats_cost": FigureDecl("fig_stats_cost", {"table": "csv", "singles": "csv"}),
    "sensitivity_indices": FigureDecl(
        "fig_sensitivity_indices", {"indices": "sensitivity_indices"}
    ),
    "sensitivity_scatter": FigureDecl("fig_sensitivity_scatter", {"points": "sensitivity_points"}),
    "design_maps": FigureDecl("fig_design_maps", {"maps": "design_maps"}),
    "torque_speed": FigureDecl("fig_torque_speed", {"curve": "load_curve"}),
    "basin_map": FigureDecl("fig_basin_map", {"basins": "basins"}),
    "startup": FigureDecl("fig_startup", {"startup": "startup"}),
}
