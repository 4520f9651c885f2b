"""The tracking store when things go wrong: stalled servers, stores never created by
reading, MLflow's own logging, and ``runs diff`` of pipeline runs.
"""

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import pytest
from cli_checks import ENV, SMALL, one_line, write_scene

from bouncedisk.cli import main


# ------------------------------------------------------------------------------ stalled servers
class StallingServer:
    """An HTTP server on 127.0.0.1 that answers the connection check, then stalls.

    It answers ``experiments/search`` (what :func:`bouncedisk.tracking.store.preflight` asks) and
    holds every other request open without replying until it is stopped or ``lifetime`` seconds
    have passed; then it closes itself.
    """

    def __init__(self, lifetime: float = 90.0):
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(16)
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.url = f"http://127.0.0.1:{self.port}"
        self.deadline = time.monotonic() + lifetime
        self.stop = threading.Event()
        self.stalled = 0
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        conns = []
        while not self.stop.is_set() and time.monotonic() < self.deadline:
            try:
                conn, _ = self.sock.accept()
            except TimeoutError:
                continue
            conn.settimeout(5)
            try:
                head = conn.recv(65536).decode("latin-1")
            except OSError:
                conn.close()
                continue
            if "experiments/search" in head.split("\r\n", 1)[0]:
                body = b'{"experiments": []}'
                conn.sendall(
                    b"HTTP/1.1 200 OK\r\nContent-Type: application/json\r\nContent-Length: "
                    + str(len(body)).encode()
                    + b"\r\nConnection: close\r\n\r\n"
                    + body
                )
                conn.close()
            else:
                self.stalled += 1
                conns.append(conn)  # never answered
        for c in conns:
            c.close()
        self.sock.close()

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5)


@pytest.fixture
def stalling_server():
    srv = StallingServer()
    yield srv
    srv.close()


def _stalled(server, *argv: str) -> subprocess.CompletedProcess:
    """``bouncedisk ARGV --tracking-uri SERVER`` in a subprocess whose store requests time out
    after 2 s."""
    env = {**ENV, "MLFLOW_HTTP_REQUEST_TIMEOUT": "2"}
    command = [sys.executable, "-m", "bouncedisk.cli", *argv, "--tracking-uri", server.url]
    return subprocess.run(command, capture_output=True, text=True, env=env, timeout=80)


@pytest.mark.slow  # waits out the store's time-outs
def test_runs_on_a_stalled_server_times_out_in_one_line(stalling_server):
    r = _stalled(stalling_server, "runs")
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and f"tracking store {stalling_server.url}: cannot be read" in lines[0]
    assert stalling_server.stalled >= 1


@pytest.mark.slow  # waits out the store's time-outs
def test_simulate_track_on_a_stalled_server_keeps_and_names_the_output(stalling_server, tmp_path):
    out = tmp_path / "x.nc"
    r = _stalled(
        stalling_server, "simulate", write_scene(tmp_path), "-o", str(out), "-q", "--track"
    )
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "recording failed (the outputs were written)" in lines[0]
    assert out.is_file()


@pytest.mark.slow  # waits out the store's time-outs
def test_interrupt_while_recording_says_the_output_was_kept(stalling_server, tmp_path):
    out = tmp_path / "x.nc"
    argv = ["simulate", write_scene(tmp_path), "-o", str(out), "-q", "--track"]
    env = {**ENV, "MLFLOW_HTTP_REQUEST_TIMEOUT": "60"}
    p = subprocess.Popen(
        [sys.executable, "-m", "bouncedisk.cli", *argv, "--tracking-uri", stalling_server.url],
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    deadline = time.monotonic() + 60
    while stalling_server.stalled == 0 and time.monotonic() < deadline:
        time.sleep(0.1)
    assert stalling_server.stalled, "the command never reached the store"
    p.send_signal(signal.SIGTERM)  # what `timeout 10 bouncedisk ...` sends
    err = p.communicate(timeout=30)[1]
    assert p.returncode == 130
    assert "no output written" not in err
    assert "interrupted while recording the run" in err
    assert f"the outputs were written and kept: {out}" in err
    assert out.is_file()


def test_every_store_request_has_a_timeout(monkeypatch):
    from bouncedisk.tracking import store as tracking_store

    env = {k: v for k, v in os.environ.items() if not k.startswith("MLFLOW_HTTP_REQUEST")}
    monkeypatch.setattr(os, "environ", env)
    tracking_store._client(tracking_store.Store("http://127.0.0.1:9"))
    assert env["MLFLOW_HTTP_REQUEST_TIMEOUT"] == str(tracking_store.HTTP_TIMEOUT_S) == "10"
    assert env["MLFLOW_HTTP_REQUEST_MAX_RETRIES"] == "1"


# -------------------------------------------------------------------------- never create stores
def test_reading_never_touches_a_foreign_or_empty_sqlite_file(tmp_path, capsys):
    import sqlite3

    foreign = tmp_path / "data.db"
    con = sqlite3.connect(foreign)
    con.execute("CREATE TABLE samples (x REAL)")
    con.commit()
    con.close()
    before = foreign.read_bytes()
    empty = tmp_path / "empty.db"
    empty.touch()
    assert main(["runs", "--tracking-uri", str(foreign)]) == 2
    assert "not an MLflow tracking store" in one_line(capsys)
    assert main(["runs", "--tracking-uri", f"sqlite:///{empty}"]) == 2
    assert "is empty, not an MLflow tracking store" in one_line(capsys)
    assert foreign.read_bytes() == before and empty.stat().st_size == 0
    # writing into a foreign database is refused too
    argv = ["simulate", write_scene(tmp_path), "-o", str(tmp_path / "o.nc"), "-q", "--track"]
    assert main([*argv, "--tracking-uri", str(foreign)]) == 2
    assert "not an MLflow tracking store" in one_line(capsys)
    assert foreign.read_bytes() == before and not (tmp_path / "o.nc").exists()


@pytest.mark.parametrize("uri", ["nonsense", "databricks", "databricks://profile", "s3://b/x"])
def test_unknown_schemes_are_refused(tmp_path, capsys, monkeypatch, uri):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MLFLOW_TRACKING_URI", uri)
    argv = ["simulate", write_scene(tmp_path), "-o", "o.nc", "-q", "--track"]
    assert main(argv) == 2
    assert one_line(capsys).startswith(f"bouncedisk: error: tracking store {uri}: ")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.yaml"]


def test_an_unknown_scheme_lists_only_the_schemes_that_work(tmp_path, capsys):
    """file:// stores are refused later: the list a user is offered leaves them out."""
    argv = ["simulate", write_scene(tmp_path), "-o", str(tmp_path / "o.nc"), "-q", "--track"]
    assert main([*argv, "--tracking-uri", "ftp://x/y"]) == 2
    line = one_line(capsys)
    assert "unknown scheme 'ftp://'; use one of sqlite://" in line and "file://" not in line


def test_runs_names_an_unknown_action_and_a_short_prefix(tracked_store, capsys):
    assert main(["runs", "frobnicate", "--tracking-uri", str(tracked_store)]) == 2
    assert one_line(capsys).endswith(
        "runs: frobnicate: unknown action (known: list, show, diff, ui)"
    )
    assert main(["runs", "show", "ab", "--tracking-uri", str(tracked_store)]) == 2
    assert one_line(capsys).endswith(
        "ab: no run with this id (a prefix needs at least 4 characters)"
    )


def test_missing_parent_folders_are_refused(tmp_path, capsys):
    root = tmp_path / "no"
    argv = ["simulate", write_scene(tmp_path), "-o", str(tmp_path / "o.nc"), "-q", "--track"]
    assert main([*argv, "--tracking-uri", f"sqlite:///{root}/such/dir/x.db"]) == 2
    assert f"folder '{root}/such' does not exist" in one_line(capsys)
    assert not root.exists()


# ----------------------------------------------------------------------------- MLflow's logging
@pytest.fixture(scope="module")
def tracked_store(tmp_path_factory):
    base = tmp_path_factory.mktemp("store")
    scene = base / "s.yaml"
    scene.write_text(SMALL)
    store = base / "mlflow.db"
    argv = ["simulate", str(scene), "-o", str(base / "a.nc"), "-q", "--track"]
    r = subprocess.run(
        [sys.executable, "-m", "bouncedisk.cli", *argv, "--tracking-uri", str(store)],
        capture_output=True,
        text=True,
        env=ENV,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    return store


@pytest.mark.parametrize(
    "damage",
    ["DROP TABLE latest_metrics", "ALTER TABLE runs RENAME COLUMN lifecycle_stage TO lc"],
)
@pytest.mark.parametrize("command", ["runs", "simulate"])
@pytest.mark.xdist_group("tracked_store")  # one worker builds the store, not both
@pytest.mark.slow  # five subprocesses importing MLflow
def test_damaged_store_is_one_line(tracked_store, tmp_path, damage, command):
    import shutil
    import sqlite3

    db = tmp_path / "mlflow.db"
    shutil.copy(tracked_store, db)
    con = sqlite3.connect(db)
    con.execute(damage)
    con.commit()
    con.close()
    argv = ["runs"]
    if command == "simulate":
        argv = ["simulate", write_scene(tmp_path), "-o", str(tmp_path / "o.nc"), "-q", "--track"]
    r = subprocess.run(
        [sys.executable, "-m", "bouncedisk.cli", *argv, "--tracking-uri", str(db)],
        capture_output=True,
        text=True,
        env=ENV,
        timeout=300,
    )
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr[-3000:]
    assert lines[0].startswith(f"bouncedisk: error: tracking store sqlite:///{db}: ")
    assert "latest_metrics" in lines[0] or "lifecycle_stage" in lines[0]


# ------------------------------------------------------------------------------------ runs diff
def _fake_run(run_id: str, params: dict, metrics: dict, manifest: dict):
    from types import SimpleNamespace

    run = SimpleNamespace(
        info=SimpleNamespace(run_id=run_id),
        data=SimpleNamespace(params=params, metrics=metrics, tags={}),
    )
    run.manifest = manifest
    return run


class _FakeRuns:
    def manifest(self, run):
        return run.manifest


def _pipeline_pair():
    """A: a whole pipeline (three jobs); B: an invocation that redrew one figure and changed
    its dpi; the other jobs are absent from B's snapshot."""
    jobs = {
        "simulations/fig4": {"r_phi": "0.01", "scene_sha256": "abc"},
        "bands/fig4": {"members": "16"},
        "figures/fig4_trajectory_e06": {"dpi": "150"},
    }
    pa = {f"{j}/{k}": v for j, d in jobs.items() for k, v in d.items()}
    ma = {"simulations/fig4/final_omega": 1.5, "figures/fig4_trajectory_e06/benchmark.s": 2.0}
    ma["pipeline.jobs_run"] = 3.0
    fa = {
        "simulations/fig4.nc": {"sha256": "s1"},
        "bands/fig4.nc": {"sha256": "b1"},
        "figures/fig4_trajectory_e06.png": {"sha256": "f1"},
    }
    pb = {"figures/fig4_trajectory_e06/dpi": "300"}
    mb = {"figures/fig4_trajectory_e06/benchmark.s": 2.5, "pipeline.jobs_run": 1.0}
    fb = {"figures/fig4_trajectory_e06.png": {"sha256": "f2"}}
    return _fake_run("A", pa, ma, fa), _fake_run("B", pb, mb, fb)


def test_diff_compares_the_jobs_both_runs_ran():
    from bouncedisk.tracking import reading as registry

    ra, rb = _pipeline_pair()
    d = registry.diff(_FakeRuns(), ra, rb)
    assert d["params"] == {"figures/fig4_trajectory_e06/dpi": ["150", "300"]}
    assert d["metrics"] == {"figures/fig4_trajectory_e06/benchmark.s": [2.0, 2.5]}
    assert d["outputs"] == {"figures/fig4_trajectory_e06.png": ["f1", "f2"]}
    assert d["jobs_only_in_a"] == ["bands/fig4", "simulations/fig4"]
    assert d["jobs_only_in_b"] == []
    text = registry.format_diff(d)
    assert "—" not in text
    assert "jobs of A that B did not run (2; not compared): bands/fig4, simulations/fig4" in text
    # tracked commands (keys without a job) compare as before
    ca = _fake_run("a", {"e": "0.3", "scene_file": "s.yaml"}, {}, {})
    cb = _fake_run("b", {"e": "0.6", "scene_file": "s.yaml"}, {}, {})
    assert registry.diff(_FakeRuns(), ca, cb)["params"] == {"e": ["0.3", "0.6"]}


def test_changed_since_previous_names_only_changed_inputs():
    from bouncedisk.tracking import reading as registry

    ra, rb = _pipeline_pair()
    assert registry.changed_keys(ra.data.params, rb.data.params) == [
        "figures/fig4_trajectory_e06/dpi"
    ]
    assert registry.changed_keys(rb.data.params, ra.data.params) == [
        "figures/fig4_trajectory_e06/dpi"
    ]


@pytest.mark.xdist_group("tracked_store")
def test_runs_reads_the_experiment_it_is_given_and_names_the_others(tracked_store, capsys):
    """A pipeline's tracking.experiment puts its runs in their own experiment: `runs` reads it
    with --experiment, and a listing of an experiment with no run names the store's others."""
    uri = str(tracked_store)
    assert main(["runs", "--tracking-uri", uri, "--experiment", "bouncedisk", "--json"]) == 0
    assert len(json.loads(capsys.readouterr().out)) == 1
    assert main(["runs", "--tracking-uri", uri, "--experiment", "mylab"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out == [
        "(no runs recorded yet)",
        "(experiment 'mylab'; this store also has 'bouncedisk': give --experiment NAME)",
    ]
