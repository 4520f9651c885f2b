"""States and configurations out of the engine's bounds are refused before the kernel runs, in
the API (``InputError``) and at the command line (one line, exit 2); the bounds are where the
numerics hold (bouncedisk.engine.bounds)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import bouncedisk
from bouncedisk.cli import main
from bouncedisk.engine import EngineConfig, InitialState, simulate_arrays
from bouncedisk.engine.bounds import OMEGA_S_MAX, PHASE_MAX, flight_length
from bouncedisk.model.errors import InputError
from bouncedisk.model.params import number
from bouncedisk.model.scene import load_scene, scene_from_mapping

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "workflow" / "config" / "scenes"
ENV_PATH = str(Path(bouncedisk.__file__).resolve().parents[1])
NAN, INF = math.nan, math.inf


def small(**kw) -> EngineConfig:
    return EngineConfig(**{"e": 0.3, "omega_s": 1.5, "max_events": 5, **kw})


#: Cases that hung in the kernel, deaf to SIGINT (run in a child process with a deadline).
HUNG = {
    "u=nan": "simulate_arrays(small(), InitialState(u=NAN, v=0.0))",
    "v=inf": "simulate_arrays(small(), InitialState(u=2.0, v=INF))",
    "omega_s=1e300": "simulate_arrays(small(omega_s=1e300))",
    "v=1e300": "simulate_arrays(small(), InitialState(u=2.0, v=1e300))",
    "v=-1e300": "simulate_arrays(small(), InitialState(u=2.0, v=-1e300))",
}


def test_states_that_hung_the_kernel_are_refused():
    """Before: each of these ran for ever (killed by the deadline)."""
    code = "\n".join(
        [
            "import json, math",
            "from bouncedisk.engine import EngineConfig, InitialState, simulate_arrays",
            "from bouncedisk.model.errors import InputError",
            "NAN, INF = math.nan, math.inf",
            "def small(**kw):",
            "    return EngineConfig(**{'e': 0.3, 'omega_s': 1.5, 'max_events': 5, **kw})",
            "out = {}",
            f"for name, expr in {HUNG!r}.items():",
            "    try:",
            "        eval(expr)",
            "        out[name] = 'ran'",
            "    except InputError as ex:",
            "        out[name] = ex.line()",
            "print(json.dumps(out))",
        ]
    )
    env = {"PYTHONPATH": ENV_PATH, "PATH": "/usr/bin:/bin"}
    p = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env
    )
    assert p.returncode == 0, p.stderr
    lines = json.loads(p.stdout)
    assert lines["u=nan"] == "InitialState: u: must be a finite number, got nan"
    assert lines["v=inf"] == "InitialState: v: must be a finite number, got inf"
    assert lines["omega_s=1e300"].startswith("EngineConfig: omega_s: must be a number in [2**-500")
    for name in ("v=1e300", "v=-1e300"):
        assert lines[name].startswith("InitialState: v: must be within ±1e+100"), lines[name]


@pytest.mark.parametrize(
    "make,line",
    [
        # before: completed with finite speeds (omega_before[0] = 149.85)
        (lambda: InitialState(omega=NAN), "InitialState: omega: must be a finite number, got nan"),
        # before: ValueError "cannot convert float NaN to integer"
        (lambda: InitialState(t=NAN), "InitialState: t: must be a finite number, got nan"),
        (lambda: small(traj_dt=0.1, traj_t0=NAN), "EngineConfig: traj_t0: must be a finite"),
        # before: OverflowError
        (lambda: small(max_events=2**70), "EngineConfig: max_events: must be a whole number in"),
        # before: TypeError "an integer is required" (and True was taken as 1)
        (lambda: small(max_events=True), "EngineConfig: max_events: must be a whole number in"),
        (lambda: small(torsion=2), "EngineConfig: torsion: must be true or false, got 2"),
        # before: ZeroDivisionError
        (lambda: small(omega_s=1e-300), "EngineConfig: omega_s: must be a number in [2**-500"),
        (lambda: small(t_end=1e300), "EngineConfig: t_end: 1e+300 is beyond the times"),
        # the scene's bounds hold in the API too: a phase without precision, a noise beyond e's range
        (lambda: small(psi=1e300), "EngineConfig: psi: must be an angle in radians, |psi| <= 1000"),
        (lambda: small(e_sigma=10.0), "EngineConfig: e_sigma: must be in [0, 0.5], got 10"),
    ],
)
def test_values_out_of_bounds_are_input_errors(make, line):
    with pytest.raises(InputError) as ex:
        make()
    assert ex.value.line().startswith(line), ex.value.line()


@pytest.mark.parametrize(
    "init,field",
    [
        (InitialState(t=1e300), "t"),  # before: OverflowError
        (InitialState(u=2.0, v=1e50), "v"),  # before: garbage (phase 4.3e50, times decreasing)
        (InitialState(u=2.0, v=-1e50), "v"),  # rebounds into the same flight
        (InitialState(u=1e30, v=0.0), "u"),
    ],
)
def test_a_state_the_clock_cannot_resolve_is_refused_when_the_run_starts(init, field):
    with pytest.raises(InputError, match=f"^InitialState: {field}: .* 2\\*\\*42"):
        simulate_arrays(small(), init)


def test_a_flight_at_the_bound_runs_right():
    """Just inside the bound the first impact is where the closed form puts it, its phase in
    [0, 2π) and the times increasing: the bound is not looser than the numerics."""
    w = 1.5
    v = 0.99 * PHASE_MAX / (2.0 * w)
    assert w * flight_length(0.0, v) <= PHASE_MAX
    res = simulate_arrays(small(omega_s=w, max_events=3), InitialState(u=0.0, v=v))
    t, ph = res.events["t"], res.events["phase"]
    assert res.ok and len(t) == 3
    # the rotor comes back through the band |u| <= 1 between these times
    lo, hi = v + math.sqrt(v * v - 2.0), v + math.sqrt(v * v + 2.0)
    assert lo - 1e-3 <= t[0] <= hi + 1e-3
    assert np.all(np.diff(t) > 0) and np.all((ph >= 0) & (ph < 2 * math.pi))
    with pytest.raises(InputError, match="v: "):
        simulate_arrays(small(omega_s=w), InitialState(u=0.0, v=1.02 * PHASE_MAX / (2.0 * w)))


def test_the_fastest_stator_accepted_runs():
    res = simulate_arrays(EngineConfig(e=0.6, omega_s=OMEGA_S_MAX, max_events=3))
    assert res.ok and np.all(np.diff(res.events["t"]) > 0)
    with pytest.raises(InputError, match="omega_s"):
        EngineConfig(e=0.6, omega_s=2.0 * OMEGA_S_MAX)


def test_messages_print_plain_numbers():
    """Before: ``np.float64(8e-05)`` in the line."""
    with pytest.raises(InputError) as ex:
        number("f.yaml", "motor.U0_m", np.float64(-8e-05), positive=True)
    assert ex.value.line() == "f.yaml: motor.U0_m: must be > 0, got -8e-05"
    with pytest.raises(InputError) as ex:
        EngineConfig(e=np.float64(2.0), omega_s=1.5)
    assert ex.value.line() == "EngineConfig: e: must be a number in [0, 1], got 2"


# ------------------------------------------------------------------------------- the scene
@pytest.mark.parametrize(
    "value,field",
    [
        ("1e50", "initial.v"),  # before: exit 0, status completed, garbage
        ("-1e150", "initial.v"),  # before: period_index -2**63
        ("1e200", "initial.v"),  # before: hung in check_output_size
        ("1e300", "initial.v"),
        ("-1e300", "initial.v"),
    ],
)
def test_simulate_refuses_a_huge_velocity_in_one_line(tmp_path, capsys, value, field):
    out = tmp_path / "o.nc"
    scene = SCENES / "fig3.yaml"
    argv = ["simulate", str(scene), "--set", f"initial={{u: 2, v: {value}}}", "-o", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and not out.exists()
    assert err[0].startswith(f"bouncedisk: error: {scene}: {field} (from --set initial): ")


@pytest.mark.parametrize(
    "section,field",
    [
        ({"initial": {"t": 1e13}}, "initial.t"),
        ({"stop": {"time": 1e13}}, "stop.time"),
        ({"stop": {"impacts": 5, "max_events": 1e30}}, "stop.max_events"),
        ({"outputs": {"trajectory": {"dt": 1.0, "t_start": -1e13}}}, "outputs.trajectory.t_start"),
        ({"parameters": {"e": 0.3, "omega_s": 1e300}}, "parameters.omega_s"),
    ],
)
def test_a_scene_names_the_field_out_of_bounds(section, field):
    raw = {"parameters": {"e": 0.3, "omega_s": 1.5}, "stop": {"impacts": 5}, **section}
    with pytest.raises(InputError) as ex:
        scene_from_mapping(raw, "s.yaml")
    assert ex.value.source == "s.yaml" and ex.value.field == field


def test_load_scene_takes_one_override_as_a_string():
    """Before: the string's characters were taken as overrides ('p': expected KEY=VALUE)."""
    scene = load_scene(SCENES / "fig3.yaml", "parameters.e=0.5")
    assert scene.params.e == 0.5
    with pytest.raises(InputError, match="an override is a string KEY=VALUE, got int"):
        load_scene(SCENES / "fig3.yaml", [3])


# ------------------------------------------------------------------------------- the physics
def test_a_fast_stator_flies_the_rotor_beyond_a_short_stop():
    """``omega_s = 1e4``, ``t_end = 10``: no event, rightly. The rotor leaves the stator at
    ``sin θ = 1/w²`` with the stator's speed ``≈ 1e4`` and flies ``≈ 2e4`` time units; the
    first impact is the first root of the gap there, and no earlier root is missed."""
    w, e = 1e4, 0.6
    short = simulate_arrays(EngineConfig(e=e, omega_s=w, t_end=10.0))
    assert short.ok and len(short.events["t"]) == 0
    th_s = math.asin(1.0 / w**2)
    t_s, u_s, v_s = th_s / w, 1.0 / w**2, w * math.cos(th_s)
    tau = 10.0 - t_s
    assert short.final["u"] == pytest.approx(u_s + v_s * tau - 0.5 * tau * tau, rel=1e-12)
    assert short.final["v"] == pytest.approx(v_s - tau, rel=1e-12)
    first = simulate_arrays(EngineConfig(e=e, omega_s=w, max_events=1))
    t1 = float(first.events["t"][0]) - t_s

    def gap(tau):
        return u_s + v_s * tau - 0.5 * tau * tau - np.sin(th_s + w * tau)

    # the descent through the band |u| <= 1, where every root lies
    start = v_s + math.sqrt(v_s * v_s + 2.0 * (u_s - 1.0))
    assert start - 1e-6 < t1 < v_s + math.sqrt(v_s * v_s + 2.0 * (u_s + 1.0)) + 1e-6
    grid = np.linspace(start - 1e-6, t1 - 1e-9, 200_001)
    assert np.all(gap(grid) > 0.0)  # no earlier crossing on a grid 1e-9 apart
    assert abs(gap(t1)) < 1e-6
