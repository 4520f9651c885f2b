"""``--set`` rules (replacing a mapping, exclusive keys) and the warnings of a statistic whose
window includes the start-up transient or that comes from one member of a run that is not periodic
(docs/user_guide/scenes.md "Overrides"; docs/model.md "Long-run statistics of chaotic motion")."""

import pytest

from bouncedisk.cli import main
from bouncedisk.cli.window_warnings import window_warnings
from bouncedisk.model.errors import InputError
from bouncedisk.model.scene import apply_overrides, load_scene

FIG4 = """name: fig4
parameters: {e: 0.6, omega_s: 1.5, r_phi: 0.01, psi: 0.0}
effects: [impacts, contact, torsion]
stop: {impacts: 300, max_events: 100000}
solver: {method: exact, tol: 1.0e-12}
"""


def test_a_mapping_value_replaces_the_whole_mapping():
    raw = {"stop": {"impacts": 300, "max_events": 10}, "parameters": {"e": 0.6, "psi": 0.0}}
    out = apply_overrides(raw, ["stop={time: 3000}", "parameters.e=0.3"])
    assert out["stop"] == {"time": 3000}  # max_events went with the old mapping
    assert out["parameters"] == {"e": 0.3, "psi": 0.0}  # a dotted key keeps the siblings
    assert raw["stop"] == {"impacts": 300, "max_events": 10}  # the input is not changed


@pytest.mark.parametrize("key", ["time", "periods", "impacts"])
def test_an_exclusive_stop_key_replaces_its_siblings_only(key):
    raw = {"stop": {"impacts": 300, "periods": 4, "max_events": 10}}
    out = apply_overrides(raw, [f"stop.{key}=50"])
    assert out["stop"] == {key: 50, "max_events": 10}


def test_stop_time_on_a_scene_that_stops_after_impacts(scene_file):
    f = scene_file(FIG4)
    scene = load_scene(f, ["stop.time=3000"])
    assert scene.stop.time == 3000.0 and scene.stop.impacts is None
    assert scene.stop.max_events == 100000  # the scene file's cap is kept
    scene = load_scene(f, ["stop={periods: 10}"])
    assert scene.stop.time == pytest.approx(10 * 2 * 3.141592653589793 / 1.5)
    with pytest.raises(InputError, match="exactly one"):
        load_scene(f, ["stop={max_events: 10}"])  # replaced by a mapping with no stop at all


STATS = (
    FIG4.replace("stop: {impacts: 300, max_events: 100000}", "stop: {time: 300}")
    .replace("[impacts, contact, torsion]", "[impacts, contact, torsion, restitution_noise]")
    .replace("psi: 0.0}", "psi: 0.0, e_sigma: 1.0e-9}")
)


def test_window_warnings_name_the_transient_and_the_single_member(scene_file):
    f = scene_file(STATS)
    one = load_scene(f, ["ensemble={members: 1, seed: 1}"])
    lines = window_warnings(one, ["chaotic"])
    assert len(lines) == 2
    assert lines[0].startswith(f"bouncedisk: warning: {f}: stats.discard: ")
    assert "transient" in lines[0]
    assert lines[1].startswith(f"bouncedisk: warning: {f}: ensemble.members: ")
    assert "chaotic" in lines[1] and "no interval" in lines[1]
    # a periodic member is the attractor's own average: only the transient is left to say
    assert len(window_warnings(one, ["periodic"])) == 1
    settled = load_scene(f, ["ensemble={members: 1, seed: 1}", "stats.discard=100"])
    assert window_warnings(settled, ["periodic", "chattering-periodic"]) == []
    (unresolved,) = window_warnings(settled, ["periodic", "unresolved"])
    # no period and no chaos in the window: a transient or a long cycle, not a sample to repeat
    assert unresolved.startswith(f"bouncedisk: warning: {f}: stats.discard: ")
    assert "unresolved" in unresolved and "ensemble" not in unresolved
    # loads of a curve: one unresolved, one chaotic: each gets its own advice
    both = window_warnings(settled, ["chaotic", "unresolved"])
    assert [line.split(": ")[3] for line in both] == ["stats.discard", "ensemble.members"]
    assert "unresolved" in both[0] and "irregular run (chaotic)" in both[1]
    many = load_scene(f, ["ensemble={members: 4, seed: 1}", "stats.discard=100"])
    assert window_warnings(many, ["chaotic"]) == []
    # an ensemble in an unresolved regime is still told its window shows none
    (line,) = window_warnings(many, ["unresolved"])
    assert "unresolved" in line and "stats.discard" in line


def test_stats_command_prints_the_warnings_on_stderr(scene_file, capsys):
    f = scene_file(STATS)
    assert main(["stats", str(f), "--set", "ensemble={members: 1, seed: 1}", "-q"]) == 0
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert lines and all(line.startswith("bouncedisk: warning: ") for line in lines), err
    assert any("stats.discard" in line for line in lines)
    assert "members: 1" in out  # the summary is still printed, on stdout
    assert (
        main(
            [
                "stats",
                str(f),
                "--set",
                "ensemble={members: 2, seed: 1}",
                "-q",
                "--set",
                "stats.discard=100",
            ]
        )
        == 0
    )
    assert capsys.readouterr().err == ""


def test_torque_speed_keeps_the_effects_a_set_option_gave(scene_file, capsys):
    """``--set effects=...`` is what torque-speed adds ``load`` to (not the file's list, which
    would drop restitution_noise and refuse e_sigma); with a discard and an ensemble, no warning."""
    f = scene_file(FIG4)
    args = ["torque-speed", str(f), "--loads", "0,0.5", "-q", "--json"]
    args += ["--set", "stop={time: 400}", "--set", "stats.discard=100"]
    args += ["--set", "ensemble={members: 2, seed: 1}", "--set", "parameters.e_sigma=1e-9"]
    args += ["--set", "effects=impacts,contact,torsion,restitution_noise"]
    assert main(args) == 0
    out, err = capsys.readouterr()
    assert err == "" and '"loads": [0.0, 0.5]' in out


PHYSICAL = """name: phys
physical: {m_r: 0.01, r_g: 0.004, r_c: 0.002, mu: 0.3, e: 0.6, g: 9.81, f: 20000.0, U0: 1.0e-6,
           Phi0: 2.0e-4, psi: 0.0, e_sigma: 1.0e-9}
effects: [impacts, contact, torsion, restitution_noise]
stop: {time: 1500}
stats: {discard: 300.0}
"""


def test_a_physical_unit_typo_is_told_by_what_the_rotor_did(scene_file):
    """A drive typed in kHz (f: 20) leaves the stator's acceleration below g: the rotor rests,
    and the warning gives the acceleration and the units to check. An amplitude typed in metres
    (U0: 1) launches flights longer than the window: the unresolved warning says so. A right
    physical scene at rest, or unresolved with short flights, gets neither hint."""
    f = scene_file(PHYSICAL)
    (khz,) = window_warnings(load_scene(f, ["physical.f=20"]), ["rest"])
    assert khz.startswith(f"bouncedisk: warning: {f}: physical: the stator's peak acceleration")
    assert "0.0158 m/s^2 is below g_eff = 9.81 m/s^2" in khz and khz.endswith("U0 in m")
    (metres,) = window_warnings(load_scene(f, ["physical.U0=1.0"]), ["unresolved"])
    assert "a flight lasts about 2 omega_s = 8.02e+04 time units, longer than the window" in metres
    right = load_scene(f)
    assert window_warnings(right, ["rest"]) == []
    (unresolved,) = window_warnings(right, ["unresolved"])
    assert "flight" not in unresolved
