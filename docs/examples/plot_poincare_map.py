"""
A Poincaré map of the chaotic attractor
=======================================

The impact map (impact phase against the relative impact velocity) and the stroboscopic map (the
rotor's state at every stator period) of the scene ``poincare_e06.yaml`` (``e = 0.6``), from one
run of 6,000 impacts; the pipeline's figure ``poincare_maps`` uses 20,000.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import xarray as xr

from bouncedisk.analysis.poincare import poincare_dataset
from bouncedisk.model.scene import load_scene
from bouncedisk.run.runner import run_scene

# a shipped scene is loaded by its name, from any folder
scene = load_scene("poincare_e06", ["stop.impacts=6000"])
out = Path(tempfile.mkdtemp()) / "poincare_e06.nc"
run_scene(scene, out, progress=False)
with xr.open_dataset(out) as sim:
    maps = poincare_dataset(sim, transient=500).load()
print(maps.sizes)

# %%
# The impact map ``(phase, v_rel)``: at each impact, the stator's phase and the relative velocity;
# the stroboscopic map ``(u, v)``: the rotor's position and velocity at phase 0 of every period.
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 4))
ax1.plot(maps.phase, maps.v_rel, ",", color="C0")
ax1.set_xlabel(r"impact phase $\omega_s t$ mod $2\pi$")
ax1.set_ylabel("relative impact velocity")
ax1.set_title(f"impact map ({maps.sizes['impact']} impacts)")
ax2.plot(maps.strobe_u, maps.strobe_v, ",", color="C3")
ax2.set_xlabel("rotor position $u$")
ax2.set_ylabel("rotor velocity $v$")
ax2.set_title(f"stroboscopic map ({maps.sizes['period']} periods)")
fig.tight_layout()
