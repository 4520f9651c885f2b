"""
Simulate a scene and plot the flight paths
==========================================

Read the scene of the paper's Fig. 3 (``e = 0.3``, a period-2 bouncing orbit), run it with the
exact event-driven engine, write its netCDF file and draw the rotor's and the stator's axial
positions and the rotor's angular velocity: what ``bouncedisk simulate`` does on the command line.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import xarray as xr

from bouncedisk.model.scene import load_scene
from bouncedisk.run.runner import run_scene

# a shipped scene is loaded by its name, from any folder
# %%
# A scene is a YAML file (:doc:`/user_guide/scenes`); ``overrides`` are the ``--set`` of the
# command line. Here: 120 impacts instead of 300, to keep the figure readable.
scene = load_scene("fig3", overrides=["stop.impacts=120"])
print(scene.name, scene.params, sorted(scene.effects))

# %%
# Run it: one netCDF file, streamed to disk and written atomically.
out = Path(tempfile.mkdtemp()) / "fig3.nc"
summary = run_scene(scene, out, progress=False)
print(summary.status, summary.n_impacts, "impacts,", summary.n_chatter, "chattering tails")

# %%
# The file holds one row per event and the dense trajectory the scene asked for.
ds = xr.open_dataset(out)
window = ds.time <= 40.0
fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
ax1.plot(ds.time[window], ds.u_stator[window], color="0.6", lw=1, label="stator $u_s$")
ax1.plot(ds.time[window], ds.u_rotor[window], color="C0", lw=1.2, label="rotor $u$")
ax1.set_ylabel("axial position $u$")
ax1.legend(loc="upper right")
ax2.plot(ds.time[window], ds.omega_rotor[window], color="C3")
ax2.set_ylabel(r"rotor speed $\Omega$")
ax2.set_xlabel(r"time $t / t_c$")
fig.suptitle(f"{scene.name}: e = {scene.params.e}, $\\omega_s$ = {scene.params.omega_s}")
fig.tight_layout()
ds.close()
