"""
A torque–speed curve
====================

A motor is read from its load characteristic (:doc:`/user_guide/load`). The effect ``load`` puts a
constant load torque ``τ_L`` on the rotor; :func:`bouncedisk.studies.torque_speed.torque_speed` runs the
scene's ensemble at each load, up and then down by continuation, and reduces it to the mean rotor
speed and output power with 95 % intervals. A small ensemble here (6 members, 7 loads, short
window) so that it runs in seconds; the pipeline's ``torque_speed_fig3`` uses 32 members and 18 loads
up to ``τ_L = 1.02``, past the momentum bound.
"""

import time

import matplotlib.pyplot as plt
import numpy as np

from bouncedisk.model.scene import load_scene
from bouncedisk.studies.torque_speed import to_dataset, torque_speed

# a shipped scene is loaded by its name, from any folder
scene = load_scene(
    "load_fig3",
    ["ensemble.members=6", "stop.time=3000", "stats.discard=1000"],
)
loads = np.array([0.0, 0.02, 0.05, 0.1, 0.3, 0.6, 0.9])
start = time.perf_counter()
curve = torque_speed(scene, loads, cores=2)
ds = to_dataset(scene, curve, time.perf_counter() - start)
derived = curve.summary()
for key in ("no_load_speed", "stall_torque", "max_power", "max_power_load"):
    print(f"{key:>15}: {derived.get(key)}")
# the loads here end at 0.9, before the speed reaches 0: the stall torque and the power's
# maximum lie past the largest load, and are None (their state says why)
print(f"{'state':>15}: {derived['stall_torque_state']}, {derived['max_power_state']}")

# %%
# At the parameters of Fig. 3 (the period-2 orbit) the speed falls steeply under the first small
# loads and then hardly changes up to ``τ_L = 0.9``, as in the pipeline's ``torque_speed_fig3``.
# Speed and output power ``P_out = τ_L Ω̄`` against the load, both branches of the sweep, each with
# the 95 % interval of its ensemble mean. The project's figure of the same file is
# :func:`bouncedisk.figures.load.fig_torque_speed`.
fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(7, 5.5))
for k, branch in enumerate(ds["branch"].values):
    sel = ds.sel(branch=branch)
    for ax, name in ((ax1, "mean_omega"), (ax2, "power_out")):
        ax.plot(loads, sel[name], "o-", color=f"C{k}", label=f"branch {branch}")
        ax.fill_between(
            loads, sel[f"{name}_ci95_low"], sel[f"{name}_ci95_high"], color=f"C{k}", alpha=0.25
        )
ax1.set_ylabel(r"mean rotor speed $\bar\Omega$")
ax2.set_ylabel(r"output power $\tau_L \bar\Omega$")
ax2.set_xlabel(r"load torque $\tau_L$ (units of $\mu m_r g r$)")
ax1.legend()
ax1.set_title(f"{scene.name}: e = {scene.params.e}, {scene.ensemble.members} members per load")
fig.tight_layout()
