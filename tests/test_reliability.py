"""Reliability: no lost or partial results, clear errors on bad input, no crash on fuzzed input."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import xarray as xr
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bouncedisk.cli import main
from bouncedisk.io.runup_curves import read_curve
from bouncedisk.model.errors import InputError
from bouncedisk.model.scene import EFFECTS, scene_from_mapping

LONG = """
name: long
parameters: {e: 0.6, omega_s: 1.5}
effects: [impacts, contact]
stop: {impacts: 100000000}
outputs: {events: true}
"""


def _start(scene, out):
    return subprocess.Popen(
        [sys.executable, "-m", "bouncedisk.cli", "simulate", str(scene), "-o", str(out), "-q"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _wait_for_tmp(folder, proc, timeout=60.0):
    """Wait until the run is streaming into its temporary file."""
    start = time.monotonic()
    while time.monotonic() - start < timeout:
        tmp = [p for p in folder.iterdir() if p.name.startswith(".out.nc.")]
        if tmp and tmp[0].stat().st_size > 200_000:
            return tmp[0]
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.1)
    raise AssertionError("the run never started writing")


@pytest.mark.slow  # a run in a subprocess, killed, per signal
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT, signal.SIGTERM])
def test_killed_run_leaves_previous_complete_file_or_none(tmp_path, sig):
    scene = tmp_path / "long.yaml"
    scene.write_text(LONG)
    out = tmp_path / "out.nc"
    # a previous complete result sits at the output path
    short = tmp_path / "short.yaml"
    short.write_text(LONG.replace("100000000", "1000"))
    assert main(["simulate", str(short), "-o", str(out), "-q"]) == 0
    before = out.read_bytes()
    proc = _start(scene, out)
    _wait_for_tmp(tmp_path, proc)
    proc.send_signal(sig)
    _stdout, err = proc.communicate(timeout=60)
    assert out.read_bytes() == before  # untouched: never truncated, never half-written
    with xr.open_dataset(out) as ds:
        assert ds.sizes["impact"] == 1000
    if sig in (signal.SIGINT, signal.SIGTERM):
        assert proc.returncode == 130
        assert "interrupted" in err and "Traceback" not in err
        assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.nc.")]
    else:
        assert proc.returncode == -signal.SIGKILL


@pytest.mark.slow  # a run in a subprocess, killed
def test_killed_first_run_leaves_no_output(tmp_path):
    scene = tmp_path / "long.yaml"
    scene.write_text(LONG)
    out = tmp_path / "out.nc"
    proc = _start(scene, out)
    _wait_for_tmp(tmp_path, proc)
    proc.send_signal(signal.SIGINT)
    proc.communicate(timeout=60)
    assert not out.exists()


def test_truncated_netcdf_is_reported(tmp_path, capsys):
    out = tmp_path / "good.nc"
    short = tmp_path / "s.yaml"
    short.write_text(LONG.replace("100000000", "5000"))
    assert main(["simulate", str(short), "-o", str(out), "-q"]) == 0
    data = out.read_bytes()
    bad = tmp_path / "cut.nc"
    bad.write_bytes(data[: len(data) // 2])
    assert main(["info", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cut.nc" in err[0]


# ------------------------------------------------------------------------------- fuzzing
values = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-5, 10**9),
    st.floats(allow_nan=True),
    st.text(max_size=12),
    st.lists(st.integers(), max_size=3),
)
param_maps = st.fixed_dictionaries(
    {},
    optional={
        "e": values | st.floats(0, 1),
        "omega_s": values | st.floats(0.1, 20),
        "r_phi": values,
        "psi": values,
        "mu_ratio": values,
        "inertia_ratio": values,
        "bogus": values,
    },
)
scene_maps = st.fixed_dictionaries(
    {"parameters": param_maps | values},
    optional={
        "name": st.text(max_size=10) | values,
        "effects": st.lists(
            st.sampled_from([*EFFECTS, "warp"]),
            max_size=4,
        )
        | values,
        "stop": st.fixed_dictionaries(
            {},
            optional={
                "impacts": st.integers(-2, 300) | values,
                "time": st.floats(-1, 50) | values,
                "periods": values,
            },
        )
        | values,
        "initial": st.fixed_dictionaries(
            {}, optional={"t": values, "u": values, "v": values, "omega": values}
        )
        | values,
        "outputs": st.fixed_dictionaries(
            {},
            optional={
                "events": values,
                "trajectory": st.fixed_dictionaries({"dt": st.floats(1e-3, 1)}) | values,
                "stroboscopic": values,
            },
        )
        | values,
        "solver": st.fixed_dictionaries(
            {},
            optional={
                "method": st.sampled_from(["exact", "rk45", "moreau", "nope"]),
                "tol": values | st.floats(1e-14, 1e-3),
            },
        )
        | values,
        "model": st.sampled_from(["bouncing", "clipped", "other"]),
        "bogus": values,
    },
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(raw=scene_maps)
def test_fuzzed_scenes_never_crash(raw):
    try:
        scene = scene_from_mapping(raw, "fuzz.yaml")
    except InputError as ex:
        assert ex.line().startswith("fuzz.yaml: ")
        assert "\n" not in ex.line()
        return
    # a valid scene runs to an end (caps apply) or fails with a clear InputError
    from bouncedisk.engine import EngineError
    from bouncedisk.run.runner import run_scene_arrays

    small = scene_from_mapping(
        {
            **raw,
            "stop": {"impacts": 200},
            "outputs": {"events": True},
            "solver": {"method": "exact"},
            "model": "bouncing",
        },
        "fuzz.yaml",
    )
    try:
        res = run_scene_arrays(small)
    except InputError as ex:
        assert "effects" in ex.line()
        return
    except EngineError:
        pytest.fail("engine failure on a valid scene")
    assert res.ok and len(res.events["t"]) <= 200
    assert scene.sha256


@settings(max_examples=100, deadline=None)
@given(
    rows=st.lists(
        st.tuples(
            st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=4)),
            st.one_of(st.floats(allow_nan=True), st.text(max_size=4)),
        ),
        max_size=40,
    ),
    header=st.sampled_from(["time_s,omega_rad_s", "time_s,omega", "t,omega_rad_s", ""]),
)
def test_fuzzed_csv_never_crash(tmp_path_factory, rows, header):
    d = tmp_path_factory.mktemp("csv")
    p = d / "c.csv"
    text = header + "\n" + "\n".join(f"{a},{b}" for a, b in rows) + "\n"
    p.write_text(text)
    (d / "c.yaml").write_text(
        yaml.safe_dump(
            {
                "source": "fuzz",
                "units": {"time": "s", "omega": "rad/s"},
                "motor": {"drive_frequency_hz": 1000.0},
            }
        )
    )
    try:
        curve = read_curve(p)
    except InputError as ex:
        assert "\n" not in ex.line() and ex.source.endswith((".csv", ".yaml"))
        return
    assert len(curve.time) >= 20 and np.all(np.diff(curve.time) > 0)
    assert np.all(np.isfinite(curve.omega))


def test_fuzzed_cli_leaves_no_partial_file(tmp_path):
    """Bad scenes through the real command: exit 2, nothing at the output path, no temporaries."""
    for text in (
        "parameters: {e: 0.3, omega_s: 1.5}\nstop: {impacts: -1}\n",
        "{",
        "[1, 2]",
        "parameters: {e: 0.3, omega_s: .nan}\nstop: {impacts: 3}\n",
    ):
        f = tmp_path / "s.yaml"
        f.write_text(text)
        out = tmp_path / "o.nc"
        assert main(["simulate", str(f), "-o", str(out), "-q"]) == 2
        assert not out.exists()
        assert not [p for p in os.listdir(tmp_path) if p.startswith(".o.nc")]
