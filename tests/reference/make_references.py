"""Write the stored reference outputs of :mod:`cases` (run from the project root)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import yaml  # noqa: E402
from cases import BASES, CASES  # noqa: E402

from bouncedisk.model.scene import apply_overrides, scene_from_mapping  # noqa: E402
from bouncedisk.run.runner import run_scene_arrays  # noqa: E402

OUT = Path("tests/data/reference")


def arrays(name: str) -> dict[str, np.ndarray]:
    """Every output array of one reference case, by name."""
    base, overrides = CASES[name]
    raw = apply_overrides(yaml.safe_load(BASES[base]), overrides)
    res = run_scene_arrays(scene_from_mapping(raw, f"<reference {name}>"))
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
