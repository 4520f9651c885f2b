"""Fit the bouncing-disk model to a measured rotor velocity–time curve.

The model is chaotic, so it is not fitted point by point: the measured curve and the model's
ensemble (docs/model.md "Long-run statistics of chaotic motion") are reduced to statistics of the
trend and the ripple (:mod:`~bouncedisk.fitting.summary_stats`), compared by a synthetic likelihood that counts the
model's across-member spread (:mod:`.objective`), searched globally then locally
(:mod:`.search`), and profiled for every parameter (:mod:`.uncertainty`). :mod:`.members` holds the
physical conversion (docs/model.md "Physical conversion"), :mod:`.output` the fit file, and
:mod:`.command` the fit as one call on values (``bouncedisk fit`` parses its options in
:mod:`bouncedisk.cli.fit`). Round-off chooses nothing
(docs/user_guide/reproducible.md): :mod:`.detlinalg` does the small linear algebra in a fixed order (no BLAS), and
:mod:`.likelihood_basins` lists the acceptable basins and holds the rule that picks the reported one.
"""

from .command import run_fit
from .core import FitResult, FitSettings, PosedFit, fit_curve, pose_fit, prepare_curve
from .members import param_names, physical, simulate_curve, synthesize_curve, uniform_grid
from .output import PUBLIC, fit_dataset, summary_text

__all__ = [
    "PUBLIC",
    "FitResult",
    "FitSettings",
    "PosedFit",
    "fit_curve",
    "fit_dataset",
    "param_names",
    "physical",
    "pose_fit",
    "prepare_curve",
    "run_fit",
    "simulate_curve",
    "summary_text",
    "synthesize_curve",
    "uniform_grid",
]
