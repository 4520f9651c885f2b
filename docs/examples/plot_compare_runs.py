"""
Compare two tracked runs
========================

:doc:`/user_guide/tracking`: ``bouncedisk simulate --track`` records a run in an MLflow tracking
store (parameters, metrics, the output's sha256, the code version), and ``bouncedisk runs diff A B``
says what differs between two of them. Here two runs of the Fig. 3 scene, ``e = 0.3`` and
``e = 0.5``, are recorded in a store in a temporary folder (a SQLite file: nothing leaves the
machine), compared, and their rotor speeds drawn from their files.
"""

import contextlib
import io
import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import xarray as xr

from bouncedisk.cli import main
from bouncedisk.tracking import reading as registry

os.environ["MLFLOW_DISABLE_TELEMETRY"] = "true"
# a shipped scene is loaded by its name, from any folder
scene = "fig3"
work = Path(tempfile.mkdtemp())
store = f"sqlite:///{work / 'mlflow.db'}"

# %%
# The two command lines, run in this process (``main`` is the ``bouncedisk`` command):
# ``bouncedisk simulate fig3.yaml -o e03.nc --set stop.impacts=150 --track --tracking-uri STORE``
# and the same with ``--set parameters.e=0.5``.
ids = []
for e in (0.3, 0.5):
    out = work / f"e{e}.nc"
    args = ["simulate", str(scene), "-o", str(out), "--set", "stop.impacts=150"]
    args += ["--set", f"parameters.e={e}", "--track", "--tracking-uri", store]
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        assert main(args) == 0, err.getvalue()
    with xr.open_dataset(out) as ds:
        ids.append(ds.attrs["run_id"])
print("recorded:", ids)

# %%
# ``bouncedisk runs diff A B``: the runs are found by the run ids the files carry.
runs = registry.Runs(store)
d = registry.diff(runs, runs.find(ids[0]), runs.find(ids[1]))
print(registry.format_diff(d))

# %%
# The two files, side by side.
fig, ax = plt.subplots(figsize=(7, 3.5))
for k, e in enumerate((0.3, 0.5)):
    with xr.open_dataset(work / f"e{e}.nc") as ds:
        ax.plot(
            ds.time, ds.omega_rotor, color=f"C{k}", label=f"e = {e}  ({ds.attrs['run_id'][:20]}…)"
        )
ax.set_xlabel(r"time $t / t_c$")
ax.set_ylabel(r"rotor speed $\Omega$")
ax.legend()
fig.tight_layout()
