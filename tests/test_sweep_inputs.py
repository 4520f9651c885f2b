"""A sweep whose point stops at its safety cap says which scene, field and point."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bouncedisk.analysis.sweeps import run_continuation, run_sweep
from bouncedisk.model.errors import InputError
from bouncedisk.model.scene import load_scene

SCENE = Path(__file__).resolve().parents[1] / "workflow" / "config" / "scenes" / "regime_map.yaml"
CAPPED = ["stop.max_events=300", "ensemble.members=2", "stats.discard=10", "stop.time=2000"]


@pytest.mark.parametrize(
    "run",
    [
        lambda sc: run_sweep(sc, [("e", np.array([0.3, 0.5])), ("omega_s", np.array([1.5]))]),
        lambda sc: run_continuation(sc, "e", np.array([0.3, 0.5])),
    ],
    ids=["sweep", "continuation"],
)
def test_a_capped_point_names_the_scene_and_the_point(run):
    """Before: a bare CappedRun ('member 0 stopped at the safety cap ...'), no scene, no point."""
    scene = load_scene(SCENE, CAPPED)
    with pytest.raises(InputError) as ex:
        run(scene)
    assert ex.value.source == str(SCENE) and ex.value.field == "stop.max_events"
    assert "safety cap of 300 events" in ex.value.message
    assert "at the sweep point e = 0.3" in ex.value.message
