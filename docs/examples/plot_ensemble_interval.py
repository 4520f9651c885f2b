"""
Ensemble statistics with a confidence interval
==============================================

A long-run number from one run of a chaotic scene is not a result (:doc:`/user_guide/ensembles`):
``bouncedisk stats`` runs an ensemble whose members differ by a tiny restitution noise and reports
the mean across members with a 95 % Student-t interval. Here the scene of the paper's Fig. 4
(``e = 0.6``, chaotic) with 12 members over a short window, so that it runs in seconds; the
shipped scene ``stats_e06.yaml`` uses 32 members over ``t`` in [3000, 53000].
"""

import matplotlib.pyplot as plt
import numpy as np

from bouncedisk.analysis.statistics import confidence_interval, run_stats
from bouncedisk.model.scene import load_scene

# a shipped scene is loaded by its name, from any folder
scene = load_scene(
    "stats_e06",
    overrides=["ensemble.members=12", "stop.time=8000", "stats.discard=2000"],
)
result = run_stats(scene, cores=2)
summary = result.summary()
for name in ("mean_omega", "lyapunov"):
    low, high = summary[f"{name}_ci95"]
    print(f"{name:>12}: {summary[name]:.4g}  95% CI [{low:.4g}, {high:.4g}]")
print("regime:", summary["regime"], f"({summary['regime_fraction']:.0%} of members)")

# %%
# Each member's mean rotor speed, and the interval of their mean. The interval is
# ``mean ± t s/sqrt(K)`` (:func:`bouncedisk.analysis.statistics.confidence_interval`): it narrows like
# ``1/sqrt(members × duration)``; the members themselves scatter much more widely.
speeds = result.column("mean_omega")
mean, low, high = confidence_interval(speeds)
fig, ax = plt.subplots(figsize=(7, 3.5))
ax.plot(np.arange(len(speeds)), speeds, "o", color="C0", label="members")
ax.axhspan(low, high, color="C1", alpha=0.3, label="95 % interval of the mean")
ax.axhline(mean, color="C1")
ax.set_xlabel("member")
ax.set_ylabel(r"mean rotor speed $\bar\Omega$ over the window")
ax.set_title(f"{scene.name}: {len(speeds)} members, " + r"$t \in$ [2000, 8000]")
ax.legend()
fig.tight_layout()
