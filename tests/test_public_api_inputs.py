"""The public API refuses what the engine cannot run, before it runs."""

from __future__ import annotations

import math

import pytest

import bouncedisk as bd
from bouncedisk.model.errors import InputError
from bouncedisk.model.params import Parameters
from bouncedisk.model.scene import scene_from_mapping


@pytest.mark.parametrize(
    "field,value",
    [
        ("e", math.nan),  # before: hung in the kernel, deaf to SIGINT
        ("e", 2.0),  # before: hung too
        ("e", -0.5),  # before: accepted
        ("omega_s", 0.0),
        ("omega_s", math.inf),
        ("r_phi", math.nan),
        ("tol", 0.0),
        ("t_end", math.nan),
        ("max_events", 0),
        ("max_events", 2.5),
        ("e_sigma", -1.0),
        ("load_torque", math.inf),
        ("seed", -1),
    ],
)
def test_engine_config_refuses_what_cannot_run(field, value):
    kw = {"e": 0.6, "omega_s": 1.5, "max_events": 10, "t_end": 100.0, field: value}
    with pytest.raises(InputError, match=f"^EngineConfig: {field}: "):
        bd.EngineConfig(**kw)


def test_engine_config_takes_numpy_numbers_and_a_driving_torque():
    import numpy as np

    cfg = bd.EngineConfig(e=np.float64(0.6), omega_s=1.5, max_events=np.int64(10), t_end=5.0,
                          load_torque=-0.1)  # fmt: skip
    assert len(bd.simulate_arrays(cfg).events["t"]) > 0


@pytest.mark.parametrize("kw", [{"e": 2.0}, {"e": -0.1}, {"omega_s": -1.0}, {"mu_ratio": 0.5}])
def test_parameters_refuse_values_outside_the_model(kw):
    with pytest.raises(InputError, match="Parameters: Parameters"):
        Parameters(**{"e": 0.6, "omega_s": 1.5, **kw})


def test_a_scene_still_names_its_file_and_field():
    raw = {"parameters": {"e": 1.5, "omega_s": 1.5}, "stop": {"impacts": 5}}
    with pytest.raises(InputError) as ex:
        scene_from_mapping(raw, "s.yaml")
    assert ex.value.line() == "s.yaml: parameters.e: must be in [0, 1], got 1.5"


def test_run_scene_refuses_a_folder_before_running(tmp_path, monkeypatch):
    """Before: the whole scene ran, then a raw OSError."""
    from bouncedisk.run import runner

    scene = scene_from_mapping({"parameters": {"e": 0.6, "omega_s": 1.5}, "stop": {"impacts": 5}})
    monkeypatch.setattr(runner, "_chunks", lambda s: pytest.fail("ran before the path check"))
    with pytest.raises(InputError, match="is a directory"):
        bd.run_scene(scene, tmp_path)
