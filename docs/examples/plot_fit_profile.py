"""
Fit a velocity–time curve and show the profiles
===============================================

:doc:`/user_guide/fitting` fits the model to a motor's measured run-up by comparing the curve's
statistics with their distribution under the model's ensemble, then profiles each parameter.

**This example reads a stored fit instead of running one.** A fit searches a four-dimensional
space with an ensemble at every point it reads: more than the few seconds a gallery example may
take, and a search small enough for them can end in a wrong basin. The stored file
``docs/examples/data/prototype_fit_small.nc`` is the fit of the shipped curve with a small
search and the restitution noise stated at the curve's 0.03 (the default fits it), made by::

    bouncedisk fit data/prototype/synthetic_motor.csv \\
        -o docs/examples/data/prototype_fit_small.nc \\
        --scan 32 --zoom 4 --seed 20261121 --cores 2 --e-sigma 0.03

The pipeline fits the same curve with its own search sizes (``workflow/config/config.yaml``).
To run a fit from Python::

    from bouncedisk.io.runup_curves import read_curve
    from bouncedisk.fitting import FitSettings, fit_curve, fit_dataset

    fit = fit_dataset(fit_curve(read_curve("data/prototype/synthetic_motor.csv"),
                                FitSettings(scan=32, zoom=4, seed=20261121, cores=2,
                                            e_sigma=0.03)))
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from bouncedisk.fitting import summary_text

ROOT = next(p for p in (Path.cwd(), *Path.cwd().parents) if (p / "workflow").is_dir())
fit = xr.load_dataset(ROOT / "docs/examples/data/prototype_fit_small.nc")
print(summary_text(fit))

# %%
# Left: the curve and the fitted model's ensemble mean with its 95 % band. Right: the profile of
# ``chi2`` along each fitted parameter, with the 95 % threshold (``Delta chi2 = 3.84`` above the
# best, scaled by ``chi2/dof`` when that exceeds 1) and the parameter's interval.
names = [n for n in ("e", "r_phi", "psi", "omega_s") if f"profile_chi2_{n}" in fit]
fig = plt.figure(figsize=(10, 6), layout="constrained")
grid = fig.add_gridspec(2, len(names))
ax = fig.add_subplot(grid[0, :])
t_ms = 1e3 * fit["time"].values
ax.plot(t_ms, fit["omega_measured"], color="0.5", lw=0.6, label="shipped (synthetic) curve")
ax.plot(t_ms, fit["omega_fitted"], color="C0", label="fitted model, ensemble mean")
ax.fill_between(t_ms, fit["omega_fitted_low"], fit["omega_fitted_high"], color="C0", alpha=0.3)
ax.set_xlabel("time (ms)")
ax.set_ylabel("rotor speed (rad/s)")
ax.legend(loc="lower right")
for k, name in enumerate(names):
    axk = fig.add_subplot(grid[1, k])
    x, chi2 = fit[f"profile_{name}"].values, fit[f"profile_chi2_{name}"].values
    ok = np.isfinite(chi2)
    axk.plot(x[ok], chi2[ok], ".-", color="C3")
    axk.axvspan(fit[name].attrs["ci_low"], fit[name].attrs["ci_high"], color="C1", alpha=0.2)
    axk.axvline(float(fit[name]), color="C1")
    axk.set_xlabel(name)
    if k == 0:
        axk.set_ylabel(r"profile $\chi^2$")
