"""Write the stored reference outputs of :mod:`cases` (run from the project root)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from cases import CASES  # noqa: E402

from bouncedisk.runner import run_scene_arrays  # noqa: E402
from bouncedisk.scene import load_scene  # noqa: E402

OUT = Path("tests/data/reference")


def arrays(name: str) -> dict[str, np.ndarray]:
    """Every output array of one reference case, by name."""
    path, overrides = CASES[name]
    res = run_scene_arrays(load_scene(path, overrides))
    out = {f"ev_{k}": v for k, v in res.events.items()}
    out["traj"] = res.traj
    out["strobe"] = res.strobe
    out["final"] = np.array([res.final[k] for k in ("t", "u", "v", "omega")])
    out["status_code"] = np.array(res.status_code)
    return out


if __name__ == "__main__":
    OUT.mkdir(parents=True, exist_ok=True)
    for name in CASES:
        data = arrays(name)
        np.savez_compressed(OUT / f"{name}.npz", **data)
        print(name, len(data["ev_t"]), "events", data["traj"].shape, data["strobe"].shape)
