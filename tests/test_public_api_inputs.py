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


# ------------------------------------------------- a notebook's mistakes: one InputError each

QUICK = ["stop.time=300", "stats.discard=100", "ensemble={members: 2, seed: 1}",
         "parameters.e_sigma=1e-9", "effects=impacts,contact,torsion,restitution_noise"]  # fmt: skip


@pytest.mark.parametrize(
    "call, line",
    [
        (lambda: bd.run_stats("fig3"), "scene: must be a Scene, got str: make one with load_scene"),
        (lambda: bd.run_scene_arrays({"a": 1}), "got dict: make one with scene_from_mapping"),
        (lambda: bd.load_scene({"parameters": {}}), "path: must be a file's path, got dict"),
        (lambda: bd.scene_from_mapping(None), "a scene must be a mapping (a dict of its"),
        (lambda: bd.scene_from_mapping("fig3.yaml"), "got str; load_scene(path) reads a scene"),
        (lambda: bd.torque_speed(bd.load_scene("fig3", QUICK), [-0.1, 0.2]), "loads: must be >= 0"),
        (lambda: bd.torque_speed(bd.load_scene("fig3", QUICK), []), "loads: must hold 1 to"),
        (lambda: bd.torque_speed(bd.load_scene("fig3", QUICK), [0.1], branches=["x"]), "branches"),
        (lambda: bd.run_stats(bd.load_scene("fig3", QUICK), cores=0), "cores: must be >= 1"),
        (lambda: bd.basins(bd.load_scene("fig3", QUICK), {"phases": 4}), "grid: must be a Start"),
        (lambda: bd.poincare_dataset("p.nc"), "sim: must be a simulation's Dataset"),
        (
            lambda: list(
                bd.iterate(bd.EngineConfig(e=0.3, omega_s=1.5, max_events=5), chunk_events=0)
            ),
            "chunk_events: must be a whole number >= 1",
        ),  # fmt: skip
        (
            lambda: bd.simulate_arrays(
                bd.EngineConfig(e=0.3, omega_s=1.5, max_events=5), bd.InitialState(u=-5.0, v=0.0)
            ),
            "u: must be >= u_s(t) = 0",
        ),  # fmt: skip
        (
            lambda: bd.simulate_arrays(
                bd.EngineConfig(e=0.3, omega_s=1.5, max_events=5), bd.InitialState(u=0.5)
            ),
            "v: give both u and v",
        ),  # fmt: skip
    ],
)
def test_a_wrong_argument_is_one_input_error_naming_it(call, line):
    """Before: AttributeError or TypeError from deep inside, a hang (a chunk of no events), or a
    run from a rotor placed inside the stator."""
    with pytest.raises(InputError) as ex:
        call()
    assert line in ex.value.line(), ex.value.line()


def test_numpy_numbers_are_numbers_in_a_scene_and_text_loads_are_loads():
    """np.float32, np.int64 and 0-d arrays were "must be a number, got 0.5"; a curve's loads
    may be the command's text."""
    import numpy as np

    raw = {"parameters": {"e": np.float32(0.5), "omega_s": np.int64(2), "r_phi": np.array(0.01),
                          "psi": 0.0}, "stop": {"impacts": np.int64(20)}}  # fmt: skip
    scene = bd.scene_from_mapping(raw)
    assert (scene.params.e, scene.params.omega_s, scene.stop.impacts) == (0.5, 2.0, 20)
    with pytest.raises(InputError, match="must be a whole number, got 2.5"):
        bd.scene_from_mapping({**raw, "stop": {"impacts": np.float32(2.5)}})
    with pytest.raises(InputError, match="must be a number, got True"):
        bd.scene_from_mapping({**raw, "parameters": {**raw["parameters"], "e": np.bool_(True)}})
    from bouncedisk.studies.torque_speed import checked_loads

    assert checked_loads("0:0.5:3").tolist() == [0.0, 0.25, 0.5]
    assert checked_loads([0.5, np.float32(0.25), 0]).tolist() == [0.0, 0.25, 0.5]  # sorted


def test_an_interval_level_is_a_fraction():
    from bouncedisk.analysis.statistics import confidence_interval

    with pytest.raises(InputError, match="level: must be a fraction in"):
        confidence_interval([1.0, 2.0, 3.0], level=95)
    assert confidence_interval([1.0, 2.0, 3.0])[0] == 2.0
