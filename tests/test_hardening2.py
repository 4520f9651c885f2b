"""Issue 21: hardening, second pass (items 1, 2, 5-11, 14-18).

Each test names the numbered item of the issue it covers; each failed before the fix.
"""

import math
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import netCDF4
import numpy as np
import pytest

import bouncedisk
from bouncedisk.cli import main
from bouncedisk.io import atomic

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "workflow" / "config" / "scenes"
S6 = str(SCENES / "stats_e06.yaml")
FIG3 = str(SCENES / "fig3.yaml")
#: Subprocesses run the package these tests import.
ENV = {**os.environ, "PYTHONPATH": str(Path(bouncedisk.__file__).resolve().parents[1])}

SMALL = """
name: small
parameters: {e: 0.3, omega_s: 1.5, r_phi: 0.01}
effects: [impacts, contact, torsion]
stop: {impacts: 50}
outputs: {events: true, trajectory: {dt: 0.05}}
"""
#: A short chaotic ensemble (seconds).
QUICK_STATS = ["--set", "stop.time=300", "--set", "stats.discard=50", "--set", "ensemble.members=4"]


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "Traceback" not in err[0]
    return err[0]


def _leftovers(folder: Path, stem: str) -> list[Path]:
    return [p for p in folder.iterdir() if p.name == stem or p.name.startswith(f".{stem}.")]


def _scene(tmp_path: Path, text: str = SMALL) -> str:
    f = tmp_path / "s.yaml"
    f.write_text(text)
    return str(f)


# ------------------------------------------------------------------ item 1: noise below an ulp
@pytest.mark.parametrize("sigma", ["1e-17", "1e-320", "2e-16"])
def test_item1_noise_that_cannot_perturb_e_is_refused(tmp_path, capsys, sigma):
    out = tmp_path / "s.nc"
    argv = ["stats", S6, *QUICK_STATS, "--set", f"parameters.e_sigma={sigma}", "-o", str(out)]
    assert main([*argv, "--json"]) == 2
    line = _one_line(capsys)
    assert "parameters.e_sigma" in line and "ulp of e" in line
    assert not _leftovers(tmp_path, "s.nc")
    # 4 ulp of e = 0.6 is the least noise accepted; it does make members differ
    least = 4 * math.ulp(0.6)
    assert f"{least:.3g}" in line


def test_item1_least_accepted_noise_gives_distinct_members(capsys):
    import json

    argv = ["stats", S6, *QUICK_STATS, "--set", f"parameters.e_sigma={4 * math.ulp(0.6)!r}"]
    assert main([*argv, "--json", "-q"]) == 0
    s = json.loads(capsys.readouterr().out)
    low, high = s["mean_omega_ci95"]
    assert high - low > 0.0  # members are distinct runs: the interval has a width


# ------------------------------------------------------------------ item 2: averaging window
@pytest.mark.parametrize("discard", ["1999.9999999", "1996"])
def test_item2_window_shorter_than_a_stator_period_is_an_error(capsys, discard):
    argv = ["stats", S6, "--set", "stop.time=2000", "--set", "ensemble.members=4"]
    assert main([*argv, "--set", f"stats.discard={discard}", "--json"]) == 2
    line = _one_line(capsys)
    assert "stats.discard" in line and "stator period (4.189)" in line
    assert capsys.readouterr().out == ""


def test_item2_window_of_one_period_is_accepted(capsys):
    period = 2 * math.pi / 1.5
    argv = ["stats", S6, "--set", "stop.time=2000", "--set", "ensemble.members=2", "-q"]
    assert main([*argv, "--set", f"stats.discard={2000 - 1.001 * period!r}"]) == 0


# ------------------------------------------------------------------ item 5: interrupts stop
def _kill_self_during(monkeypatch, module, name: str, sig=signal.SIGINT) -> None:
    """Send ``sig`` to this process as ``module.name`` runs (then let it finish)."""
    orig = getattr(module, name)

    def wrapped(*a, **k):
        os.kill(os.getpid(), sig)
        return orig(*a, **k)

    monkeypatch.setattr(module, name, wrapped)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_item5_interrupt_while_writing_stats_leaves_no_output(tmp_path, capsys, monkeypatch, sig):
    from bouncedisk.io import netcdf as datasets

    out = tmp_path / "s.nc"
    _kill_self_during(monkeypatch, datasets, "finalize", sig)  # inside write_dataset
    assert main(["stats", S6, *QUICK_STATS, "--json", "-q", "-o", str(out)]) == 130
    cap = capsys.readouterr()
    assert cap.out == ""  # no JSON
    assert "interrupted; no output written" in cap.err
    assert not _leftovers(tmp_path, "s.nc")


def test_item5_interrupt_after_the_members_leaves_no_output(tmp_path, capsys, monkeypatch):
    from bouncedisk.analysis import statistics as stats

    out = tmp_path / "s.nc"
    _kill_self_during(monkeypatch, stats, "to_dataset")  # the members are done
    assert main(["stats", S6, *QUICK_STATS, "--json", "-q", "-o", str(out)]) == 130
    assert capsys.readouterr().out == ""
    assert not _leftovers(tmp_path, "s.nc")


def test_item5_interrupt_while_printing_removes_the_output(tmp_path, capsys, monkeypatch):
    from bouncedisk.analysis import statistics as stats

    out = tmp_path / "s.nc"
    _kill_self_during(monkeypatch, stats.EnsembleStats, "summary")  # after the rename
    assert main(["stats", S6, *QUICK_STATS, "--json", "-q", "-o", str(out)]) == 130
    assert not _leftovers(tmp_path, "s.nc")


def test_item5_interrupt_while_simulating_leaves_no_output(tmp_path, capsys, monkeypatch):
    from bouncedisk.io import netcdf as datasets

    out = tmp_path / "out.nc"
    _kill_self_during(monkeypatch, datasets.SimulationWriter, "set_attrs", signal.SIGTERM)
    assert main(["simulate", _scene(tmp_path), "-o", str(out), "-q"]) == 130
    assert not _leftovers(tmp_path, "out.nc")


# ------------------------------------------------------------------ item 6: full disks
def _tmpfs(path: Path, size: str = "2m") -> bool:
    path.mkdir()
    if os.geteuid() != 0:
        return False
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)])
    return r.returncode == 0


@pytest.fixture
def full_folder(tmp_path):
    """A 2 MB tmpfs (root) or, elsewhere, a folder with a 2 MB file-size limit."""
    folder = tmp_path / "small"
    mounted = _tmpfs(folder)
    yield folder, mounted
    if mounted:
        subprocess.run(["umount", "-l", str(folder)])


BIG = SMALL.replace("{impacts: 50}", "{impacts: 3000}").replace("dt: 0.05", "dt: 0.001")


@pytest.mark.parametrize("command", ["simulate", "stats", "check"])
def test_item6_disk_full_is_one_line_naming_the_file(full_folder, tmp_path, command):
    folder, mounted = full_folder
    out = folder / ("x.md" if command == "check" else "x.nc")
    if command == "simulate":
        argv = ["simulate", _scene(tmp_path, BIG), "-o", str(out), "-q"]
    elif command == "stats":
        argv = ["stats", S6, *QUICK_STATS, "-o", str(out), "-q"]
    if mounted:  # fill the disk first for the small writes
        if command != "simulate":
            with open(folder / "fill", "wb") as fh, pytest.raises(OSError):
                fh.write(b"\0" * (3 << 20))
    limit = (
        ""
        if mounted
        else "import resource; resource.setrlimit(resource.RLIMIT_FSIZE, (2 << 20,) * 2);"
    )
    if command == "check":  # the report of `check -o` is written by write_text_atomic
        code = (
            f"{limit}import sys; from bouncedisk.cli import main; from bouncedisk.studies import reproduction as checks\n"
            "checks.run_checks = lambda d: []\n"
            "checks.to_markdown = lambda r: 'x' * (3 << 20)\n"
            f"sys.exit(main(['check', '-o', {str(out)!r}]))"
        )
    else:
        code = f"{limit}import sys; from bouncedisk.cli import main; sys.exit(main({argv!r}))"
    r = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env=ENV,
        timeout=300,
        preexec_fn=lambda: signal.signal(signal.SIGXFSZ, signal.SIG_IGN),
    )
    err = r.stderr.strip().splitlines()
    assert r.returncode == 2, r.stderr[-2000:]
    assert len(err) == 1 and "Traceback" not in r.stderr, err
    assert err[0].startswith(f"bouncedisk: error: {out}: cannot write: ")
    if mounted:
        assert err[0].endswith("No space left on device")
    assert not _leftovers(folder, out.name)


def test_item6_write_error_names_the_output(tmp_path):
    err = atomic.write_error(tmp_path / "x.nc", RuntimeError("NetCDF: HDF error"))
    assert err.filename == str(tmp_path / "x.nc") and "HDF error" in err.strerror
    assert atomic.write_error(tmp_path / "x.nc", RuntimeError("engine")) is None


# ------------------------------------------------------------------ item 7: nothing left behind
@pytest.mark.parametrize("command", ["stats", "simulate"])
def test_item7_stdout_on_a_full_disk_leaves_no_output(tmp_path, command):
    out = tmp_path / "x.nc"
    if command == "stats":
        argv = ["stats", S6, *QUICK_STATS, "--json", "-q", "-o", str(out)]
    else:
        argv = ["simulate", _scene(tmp_path), "-o", str(out)]
    with open("/dev/full", "w") as full:
        r = subprocess.run(
            [sys.executable, "-m", "bouncedisk.cli", *argv],
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            env=ENV,
            timeout=300,
        )
    assert r.returncode == 2
    assert r.stderr.strip() == "bouncedisk: error: <stdout>: No space left on device"
    assert not _leftovers(tmp_path, "x.nc")


# ------------------------------------------------------------------ item 8: symbolic links
def test_item8_symlink_output_is_written_through(tmp_path, capsys):
    scene = _scene(tmp_path)
    (tmp_path / "real").mkdir()
    target = tmp_path / "real" / "t.nc"
    target.write_text("old")
    link = tmp_path / "link.nc"
    link.symlink_to(target)
    assert main(["simulate", scene, "-o", str(link), "-q"]) == 0
    assert link.is_symlink() and os.readlink(link) == str(target)
    with netCDF4.Dataset(target) as nc:
        assert nc.dimensions["impact"].size > 0
    dangling = tmp_path / "dangling.nc"
    dangling.symlink_to(tmp_path / "real" / "new.nc")
    assert main(["simulate", scene, "-o", str(dangling), "-q"]) == 0
    assert dangling.is_symlink() and (tmp_path / "real" / "new.nc").is_file()


@pytest.mark.parametrize("name", ["/dev/stdout", "/proc/self/fd/1", "link"])
def test_item8_device_or_process_file_is_refused(tmp_path, capsys, name):
    if name == "link":
        name = str(tmp_path / "l.nc")
        Path(name).symlink_to("/proc/self/fd/1")
    stdout = tmp_path / "stdout.txt"
    code = f"import sys; from bouncedisk.cli import main; sys.exit(main(['simulate', {_scene(tmp_path)!r}, '-o', {name!r}, '-q']))"
    with open(stdout, "w") as fh:  # stdout a regular file: /proc/self/fd/1 leads to it
        r = subprocess.run(
            [sys.executable, "-c", code], stdout=fh, stderr=subprocess.PIPE, text=True, env=ENV
        )
    assert r.returncode == 2 and "is a device or process file" in r.stderr
    assert stdout.stat().st_size == 0
    if name.endswith("l.nc"):
        assert Path(name).is_symlink()


# ------------------------------------------------------------------ item 9: stale temporaries
def test_item9_temporary_of_a_killed_run_is_removed_by_the_next(tmp_path):
    out = tmp_path / "big.nc"
    long = SMALL.replace("{impacts: 50}", "{impacts: 5000000}")
    scene = _scene(tmp_path, long.replace(", trajectory: {dt: 0.05}", ""))
    p = subprocess.Popen(
        [sys.executable, "-m", "bouncedisk.cli", "simulate", scene, "-o", str(out), "-q"],
        env=ENV,
    )
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        tmps = [t for t in tmp_path.iterdir() if t.name.startswith(".big.nc.") and ".tmp" in t.name]
        if tmps and tmps[0].stat().st_size > 0:
            break
        time.sleep(0.1)
    p.kill()
    p.wait()
    assert tmps, "the run wrote no temporary"
    # a live process's temporary (this test's parent) and another host's are left alone
    live = tmp_path / f".big.nc.{atomic._host()}-{os.getppid()}.abcd.tmp.nc"
    other = tmp_path / f".big.nc.otherhost-{p.pid}.abcd.tmp.nc"
    live.touch()
    other.touch()
    assert main(["simulate", _scene(tmp_path), "-o", str(out), "-q"]) == 0
    assert out.is_file()
    assert not any(t.exists() for t in tmps)
    assert live.exists() and other.exists()


# ------------------------------------------------------------------ item 10: FIFOs
@pytest.mark.parametrize("command", ["info", "simulate"])
def test_item10_fifo_input_is_refused_at_once(tmp_path, command):
    fifo = tmp_path / "f.nc"
    os.mkfifo(fifo)
    argv = [command, str(fifo)] + (["-o", str(tmp_path / "o.nc")] if command == "simulate" else [])
    r = subprocess.run(
        [sys.executable, "-m", "bouncedisk.cli", *argv],
        capture_output=True,
        text=True,
        env=ENV,
        timeout=60,
    )
    assert r.returncode == 2
    assert r.stderr.strip().endswith(
        "is not a regular file (a pipe or device?), not a "
        + ("bouncedisk simulation file" if command == "info" else "scene file")
    )


# ------------------------------------------------------------------ item 11: YAML bombs
def test_item11_nested_aliases_are_refused_quickly(tmp_path, capsys):
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    for i in range(1, 10):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]")
    f = tmp_path / "bomb.yaml"
    f.write_text("\n".join(lines) + "\nname: x\n")
    assert f.stat().st_size < 600
    start = time.process_time()
    assert main(["simulate", str(f), "-o", str(tmp_path / "o.nc")]) == 2
    assert time.process_time() - start < 10.0  # CPU seconds (it ran for minutes before)
    assert "aliases (*name) expand to more than 100,000 values" in _one_line(capsys)


def test_item11_ordinary_aliases_still_load():
    from bouncedisk.model import yamlio

    text = "p: &p {e: 0.3, omega_s: 1.5}\nq: *p\nr: {<<: *p, e: 0.5}\n"
    data = yamlio.load(text, "x")
    assert data["q"] == {"e": 0.3, "omega_s": 1.5} and data["r"] == {"e": 0.5, "omega_s": 1.5}
    assert yamlio._expanded_size(yamlio.Loader(text).get_single_node(), "x") == 23


# ------------------------------------------------------------------ item 14: stalled servers
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


@pytest.mark.slow  # waits out the store's time-outs
def test_item14_runs_on_a_stalled_server_times_out_in_one_line(stalling_server):
    env = {**ENV, "MLFLOW_HTTP_REQUEST_TIMEOUT": "2"}
    r = subprocess.run(
        [sys.executable, "-m", "bouncedisk.cli", "runs", "--tracking-uri", stalling_server.url],
        capture_output=True,
        text=True,
        env=env,
        timeout=80,
    )
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and f"tracking store {stalling_server.url}: cannot be read" in lines[0]
    assert stalling_server.stalled >= 1


@pytest.mark.slow  # waits out the store's time-outs
def test_item14_simulate_track_on_a_stalled_server_keeps_and_names_the_output(
    stalling_server, tmp_path
):
    out = tmp_path / "x.nc"
    argv = ["simulate", _scene(tmp_path), "-o", str(out), "-q", "--track"]
    env = {**ENV, "MLFLOW_HTTP_REQUEST_TIMEOUT": "2"}
    r = subprocess.run(
        [sys.executable, "-m", "bouncedisk.cli", *argv, "--tracking-uri", stalling_server.url],
        capture_output=True,
        text=True,
        env=env,
        timeout=80,
    )
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "recording failed (the outputs were written)" in lines[0]
    assert out.is_file()


@pytest.mark.slow  # waits out the store's time-outs
def test_item14_interrupt_while_recording_says_the_output_was_kept(stalling_server, tmp_path):
    out = tmp_path / "x.nc"
    argv = ["simulate", _scene(tmp_path), "-o", str(out), "-q", "--track"]
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


def test_item14_every_store_request_has_a_timeout(monkeypatch):
    from bouncedisk.tracking import store as tracking_store

    env = {k: v for k, v in os.environ.items() if not k.startswith("MLFLOW_HTTP_REQUEST")}
    monkeypatch.setattr(os, "environ", env)
    tracking_store._client(tracking_store.Store("http://127.0.0.1:9"))
    assert env["MLFLOW_HTTP_REQUEST_TIMEOUT"] == str(tracking_store.HTTP_TIMEOUT_S) == "10"
    assert env["MLFLOW_HTTP_REQUEST_MAX_RETRIES"] == "1"


# ------------------------------------------------------------------ item 15: never create stores
def test_item15_reading_never_touches_a_foreign_or_empty_sqlite_file(tmp_path, capsys):
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
    assert "not an MLflow tracking store" in _one_line(capsys)
    assert main(["runs", "--tracking-uri", f"sqlite:///{empty}"]) == 2
    assert "is empty, not an MLflow tracking store" in _one_line(capsys)
    assert foreign.read_bytes() == before and empty.stat().st_size == 0
    # writing into a foreign database is refused too
    argv = ["simulate", _scene(tmp_path), "-o", str(tmp_path / "o.nc"), "-q", "--track"]
    assert main([*argv, "--tracking-uri", str(foreign)]) == 2
    assert "not an MLflow tracking store" in _one_line(capsys)
    assert foreign.read_bytes() == before and not (tmp_path / "o.nc").exists()


@pytest.mark.parametrize("uri", ["nonsense", "databricks", "databricks://profile", "s3://b/x"])
def test_item15_unknown_schemes_are_refused(tmp_path, capsys, monkeypatch, uri):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MLFLOW_TRACKING_URI", uri)
    argv = ["simulate", _scene(tmp_path), "-o", "o.nc", "-q", "--track"]
    assert main(argv) == 2
    assert _one_line(capsys).startswith(f"bouncedisk: error: tracking store {uri}: ")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.yaml"]


def test_item15_missing_parent_folders_are_refused(tmp_path, capsys):
    root = tmp_path / "no"
    argv = ["simulate", _scene(tmp_path), "-o", str(tmp_path / "o.nc"), "-q", "--track"]
    assert main([*argv, "--tracking-uri", f"sqlite:///{root}/such/dir/x.db"]) == 2
    assert f"folder '{root}/such' does not exist" in _one_line(capsys)
    assert not root.exists()


# ------------------------------------------------------------------ item 16: MLflow's logging
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
def test_item16_damaged_store_is_one_line(tracked_store, tmp_path, damage, command):
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
        argv = ["simulate", _scene(tmp_path), "-o", str(tmp_path / "o.nc"), "-q", "--track"]
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


# ------------------------------------------------------------------ item 17: runs diff
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


def test_item17_diff_compares_the_jobs_both_runs_ran():
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


def test_item17_changed_since_previous_names_only_changed_inputs():
    from bouncedisk.tracking import reading as registry

    ra, rb = _pipeline_pair()
    assert registry.changed_keys(ra.data.params, rb.data.params) == [
        "figures/fig4_trajectory_e06/dpi"
    ]
    assert registry.changed_keys(rb.data.params, ra.data.params) == [
        "figures/fig4_trajectory_e06/dpi"
    ]


# ------------------------------------------------------------------ item 18: CF and ACDD
#: The one CF-1.10 result compliance-checker 6.1 still reports, and why it stays (docs,
#: "Sharing results"): its §5.1 check wants ``standard_name: time`` on the coordinate of any
#: dimension *named* ``time`` (CF gives names no meaning; ioos/compliance-checker#1245, and the
#: open PR #1353 removes the rule). Ours is nondimensional (units "1") or seconds from an undated
#: start: not a CF time coordinate, which needs "UNIT since DATE" (§4.4); docs/formats.md fixes
#: the name. Only exactly this message, on such a ``time``, is let through.
SECTION_5_1 = "§5.1 Independent Latitude, Longitude, Vertical, and Time Axes"
TIME_NAME_RULE = "Coordinate variable 'time' should have standard_name='time', found: 'None'"
#: ACDD-1.3 global attributes every file carries (highly recommended and recommended with a
#: meaning here; geospatial coverage and the time coverage's start and end (dates) have none
#: for a rotor in nondimensional or undated time).
ACDD_GLOBALS = (
    "title", "summary", "keywords", "Conventions", "id", "naming_authority", "history",
    "source", "processing_level", "comment", "acknowledgement", "license",
    "standard_name_vocabulary", "date_created", "creator_name", "creator_email", "creator_url",
    "institution", "project", "publisher_name", "publisher_email", "publisher_url",
    "creator_type", "creator_institution", "date_modified", "date_issued",
    "date_metadata_modified", "product_version", "references",
)  # fmt: skip
#: ACDD-1.3 recommended attributes without a meaning here (see ACDD_GLOBALS).
ACDD_NO_MEANING = ("geospatial_", "time_coverage_start", "time_coverage_end")
#: ... and the time coverage's duration and resolution, in files whose time is not in seconds.
ACDD_SECONDS_ONLY = ("time_coverage_duration", "time_coverage_resolution")
#: The dates of a file: a joined file's parts are written by separate jobs, at other times.
DATES = ("created", "date_created", "date_modified", "date_issued", "date_metadata_modified")
PHYSICAL = (
    "name: phys\nphysical: {m_r: 0.01, r_g: 0.004, r_c: 0.001, mu: 0.2, e: 0.5, g: 9.81,\n"
    "  f: 2.0e+2, U0: 1.0e-4, Phi0: 1.0e-3}\neffects: [impacts, contact, torsion]\n"
    "stop: {impacts: 20}\noutputs: {events: true, trajectory: {dt: 0.1}, stroboscopic: true}\n"
)
LOAD_SCENE = (
    "parameters: {e: 0.6, omega_s: 1.5, r_phi: 0.01, psi: 0.0, e_sigma: 1.0e-9}\n"
    "effects: [impacts, contact, torsion, restitution_noise]\n"
    "stop: {time: 300.0}\nensemble: {members: 2, seed: 1}\n"
)


def _earlier(ds):
    """``ds`` as a job that ran earlier wrote it (its dates differ from the other parts')."""
    ds.attrs.update(dict.fromkeys(DATES, "2000-01-01T00:00:00Z"))
    return ds


def _sensitivity_files(d: Path) -> dict[str, Path]:
    """The sensitivity study's files at a smoke-test size, as its rules make them."""
    import dataclasses

    import yaml

    from bouncedisk.io.netcdf import open_checked, write_dataset
    from bouncedisk.studies import sensitivity as sens
    from bouncedisk.studies import sensitivity_settings as sc

    cfg = yaml.safe_load((ROOT / "workflow" / "config" / "config.yaml").read_text())
    st = dataclasses.replace(
        sc.study_settings({**cfg, "sensitivity": "small"}), base_samples=2, shards=2, members=2,
        duration=10.0, discard=5.0, map_points=(3, 2),
    )  # fmt: skip
    model = sens.MotorModel(st)
    files = {"sensitivity_shard": d / "sens-shard-0.nc", "sensitivity_map": d / "sens-map-0.nc"}
    for i in range(st.shards):
        write_dataset(_earlier(sens.run_shard(st, model, i)) if i else sens.run_shard(st, model, i),
                      d / f"sens-shard-{i}.nc")  # fmt: skip
    maps = [d / f"sens-map-{i}.nc" for i in range(len(st.map_e))]
    for i, path in enumerate(maps):
        write_dataset(_earlier(sens.design_map(st, model, i)) if i else sens.design_map(st, model, i),
                      path)  # fmt: skip
    files["sensitivity_points"] = d / "sens-points.nc"
    parts = [open_checked(d / f"sens-shard-{i}.nc") for i in range(st.shards)]
    write_dataset(sens.join_shards(parts), files["sensitivity_points"])
    files["sensitivity_indices"] = d / "sens-indices.nc"
    points = open_checked(files["sensitivity_points"], required=("x", "regime"))
    write_dataset(sens.analyse(points, st.ranges, 20, st.seed), files["sensitivity_indices"])
    files["sensitivity_maps"] = d / "sens-maps.nc"
    write_dataset(sens.join_maps([open_checked(m).load() for m in maps]), files["sensitivity_maps"])
    return files


@pytest.fixture(scope="module")
def every_kind(tmp_path_factory):
    """One small file of every kind the package writes, through the functions the pipeline's
    scripts call (workflow/scripts/*.py); the parts of joined files written at other times."""
    import yaml

    from bouncedisk.analysis.bands import omega_band
    from bouncedisk.analysis.poincare import poincare_dataset
    from bouncedisk.analysis.sweeps import combine_shards, grid_values, run_continuation, run_sweep
    from bouncedisk.io.netcdf import open_checked, open_simulation, write_dataset
    from bouncedisk.model.params import Parameters
    from bouncedisk.model.scene import load_scene
    from bouncedisk.studies.clipped import clipped_comparison
    from bouncedisk.studies.torque_speed import motor_scene, to_dataset, torque_speed

    d = tmp_path_factory.mktemp("kinds")
    (d / "s.yaml").write_text(SMALL)
    (d / "p.yaml").write_text(PHYSICAL)
    (d / "l.yaml").write_text(LOAD_SCENE)
    env = {**ENV, "BOUNCEDISK_CREATOR_NAME": "A. Tester", "BOUNCEDISK_INSTITUTION": "Test Lab"}
    old = {k: os.environ.get(k) for k in ("BOUNCEDISK_CREATOR_NAME", "BOUNCEDISK_INSTITUTION")}
    os.environ.update({k: env[k] for k in old})
    try:
        files = {}
        for name, scene in (("simulation", "s.yaml"), ("simulation_physical", "p.yaml")):
            assert main(["simulate", str(d / scene), "-o", str(d / f"{name}.nc"), "-q"]) == 0
            files[name] = d / f"{name}.nc"
        files["stats"] = d / "stats.nc"
        assert main(["stats", S6, *QUICK_STATS, "-q", "-o", str(files["stats"])]) == 0
        sc = load_scene(SCENES / "regime_map.yaml")
        axes = [("e", grid_values({"min": 0.2, "max": 0.8, "n": 2})), ("omega_s", [1.5])]
        shards = [run_sweep(sc, axes, shard=i, n_shards=2, tail=5) for i in range(2)]
        for i, ds in enumerate(shards):
            write_dataset(_earlier(ds) if i else ds, d / f"shard{i}.nc")
        files["sweep_shard"] = d / "shard0.nc"
        files["sweep"] = d / "sweep.nc"
        write_dataset(
            combine_shards([open_checked(d / f"shard{i}.nc") for i in range(2)]), files["sweep"]
        )
        files["band"] = d / "band.nc"
        write_dataset(
            omega_band(load_scene(d / "s.yaml"), 3, seed=1, e_sigma=1e-9, cores=1), files["band"]
        )
        files["poincare"] = d / "poincare.nc"
        write_dataset(
            poincare_dataset(open_simulation(files["simulation"]), transient=5), files["poincare"]
        )
        files["continuation"] = d / "continuation.nc"
        cont = run_continuation(
            load_scene(SCENES / "bifurcation.yaml"), "e", [0.3, 0.6], direction="up", tail=5
        )
        write_dataset(cont, files["continuation"])
        files["clipped"] = d / "clipped.nc"
        clip = clipped_comparison(
            load_scene(SCENES / "clipped_comparison.yaml"), [0.0], members=2, seed=1, e_sigma=1e-9
        )
        write_dataset(clip, files["clipped"])
        files["fit"] = d / "fit.nc"
        curve = ROOT / "data" / "prototype" / "synthetic_motor.csv"
        argv = ["fit", str(curve), "-o", str(files["fit"]), "-q", "--seed", "1"]
        argv += ["--scan", "8", "--zoom", "0", "--bootstrap", "40", "--members", "4"]
        assert main(argv) == 0
        files["load"] = d / "load.nc"
        argv = ["torque-speed", str(d / "l.yaml"), "--loads", "0,0.5", "-q", "-o"]
        assert main([*argv, str(files["load"])]) == 0
        # the fitted prototype's curve in SI units (workflow/scripts/torque_speed_prototype.py)
        motor = yaml.safe_load((ROOT / "workflow" / "config" / "synthetic_motor.yaml").read_text())
        scene = motor_scene(
            Parameters(e=0.5, omega_s=1.5, r_phi=0.01, psi=0.0, e_sigma=1e-9),
            motor["drive_frequency_hz"], motor["Phi0_rad"], motor["rotor"], motor["preload_N"],
            2, 300.0, 100.0,
        )  # fmt: skip
        files["load_prototype"] = d / "load_prototype.nc"
        ds = to_dataset(scene, torque_speed(scene, [0.0, 0.5], cores=1), 1.0)
        ds.attrs["fit_file"] = "fit/prototype.nc (in the results folder)"
        write_dataset(ds, files["load_prototype"])
        files.update(_sensitivity_files(d))
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return files


def _no_network(monkeypatch) -> list:
    """Make any network access by the checker fail, and record it."""
    tries = []

    def refuse(*a, **k):
        tries.append(a)
        raise OSError("network access in a test")

    monkeypatch.setattr(socket.socket, "connect", refuse)
    from compliance_checker.cf import util as cfu

    monkeypatch.setattr(cfu, "download_cf_standard_name_table", refuse)
    return tries


def _check(path: Path) -> dict:
    """compliance-checker's CF-1.10 and ACDD-1.3 results on ``path``: per suite, the failed
    results ``(priority, name, messages)``, the checks that raised, and the score."""
    from compliance_checker.runner import CheckSuite

    cs = CheckSuite()
    cs.load_all_available_checkers()
    ds = cs.load_dataset(str(path))
    out = {}
    for name, (groups, errors) in cs.run_all(ds, ["cf:1.10", "acdd:1.3"], skip_checks=[]).items():
        score = cs.build_structure(name, groups, str(path))
        failed = [
            (pr.split("_")[0], r.name, list(r.msgs))
            for pr in ("high_priorities", "medium_priorities", "low_priorities")
            for r in score[pr]
            if isinstance(r.value, tuple) and r.value[0] < r.value[1] or r.value is False
        ]
        out[name] = (failed, set(errors), score["scored_points"], score["possible_points"])
    return out


def _time_name_rule(result, nc) -> bool:
    """Whether a failed CF result is only the §5.1 dimension-name rule, on a ``time`` that is
    not a CF time coordinate (no "since", no standard_name or axis of time)."""
    _, name, msgs = result
    if name != SECTION_5_1 or set(msgs) != {TIME_NAME_RULE} or "time" not in nc.variables:
        return False
    t = nc["time"]
    return " since " not in getattr(t, "units", " since ") and not {"axis", "standard_name"} & set(
        t.ncattrs()
    )


def _acdd_without_meaning(result, seconds: bool) -> bool:
    """Whether a failed ACDD result asks only for what has no meaning here: a variable's
    standard_name (none in the CF table for these quantities), geospatial coverage, the time
    coverage's dates, and its duration and resolution when time is not in seconds."""
    _, name, msgs = result
    if name.startswith("variable ") and msgs == ["standard_name"]:
        return True
    if name in ("geospatial_lat_extents_match", "geospatial_lon_extents_match"):
        return True
    absent = [m.removesuffix(" not present") for m in msgs]
    allowed = ACDD_NO_MEANING + (() if seconds else ACDD_SECONDS_ONLY)
    return name == "Global Attributes" and all(a.startswith(allowed) for a in absent)


KINDS = (
    "simulation simulation_physical stats sweep sweep_shard band poincare continuation clipped "
    "fit load load_prototype sensitivity_shard sensitivity_points sensitivity_map "
    "sensitivity_indices sensitivity_maps"
).split()
#: Kinds whose time is in seconds: a fit's measured ``time``, a physical scene's ``time_s``.
SECONDS = {"fit", "simulation_physical"}


@pytest.mark.slow  # compliance-checker on every kind of file: an external validation, in CI
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.xdist_group("every_kind")  # one worker writes the files, not both
@pytest.mark.cost(12)  # the files
def test_item18_every_file_kind_is_cf_clean_and_carries_acdd(every_kind, monkeypatch, kind):
    pytest.importorskip("compliance_checker")
    tries = _no_network(monkeypatch)
    res = _check(every_kind[kind])
    failed, errors, *_ = res["cf:1.10"]
    assert not errors, errors  # no check raised (string coordinate variables made one raise)
    assert not tries  # no standard-name table was downloaded
    with netCDF4.Dataset(every_kind[kind]) as nc:
        assert not [r for r in failed if not _time_name_rule(r, nc)], failed
        acdd_failed = [r for r in res["acdd:1.3"][0] if r[0] in ("high", "medium")]
        assert not [r for r in acdd_failed if not _acdd_without_meaning(r, kind in SECONDS)]
        attrs = nc.__dict__
        missing = [a for a in ACDD_GLOBALS if not str(attrs.get(a, "")).strip()]
        assert not missing, missing
        assert attrs["creator_name"] == "A. Tester" and attrs["institution"] == "Test Lab"
        assert attrs["license"].startswith("MIT")
        # a fit holds measured data and its time is in seconds: the file says so
        assert attrs["processing_level"].startswith("measured" if kind == "fit" else "model")
        assert ("time is in seconds" in attrs["comment"]) == (kind == "fit")
        if kind == "fit":  # the shipped curve: 0.12 s sampled every 20 µs
            assert attrs["time_coverage_duration"] == "PT0.12S"
            assert attrs["time_coverage_resolution"] == "PT0.00002S"
        elif kind in SECONDS:
            assert attrs["time_coverage_duration"].startswith("PT"), attrs
            assert attrs["time_coverage_resolution"].startswith("PT"), attrs
        for name, var in nc.variables.items():
            assert var.getncattr("coverage_content_type") in (
                "coordinate", "modelResult", "physicalMeasurement",
            ), name  # fmt: skip
            if name in nc.dimensions:  # CF §1.3: coordinate variables are numeric, no fill
                assert var.dtype.kind in "iuf", name
                assert "_FillValue" not in var.ncattrs(), name


@pytest.mark.slow  # the files of every kind (the fixture above): in CI
@pytest.mark.xdist_group("every_kind")  # the files of the worker that wrote them
def test_item18_string_labels_are_cf_labels_that_read_back_as_the_index(every_kind):
    """A string-labelled dimension keeps no coordinate variable in the file (CF-1.10 §1.3: they
    are numeric): the labels ``X`` are an auxiliary coordinate (§6.1) on the dimension
    ``X_index``, which xarray reads as a coordinate, and the package's reader restores ``X``
    as the dimension and its index. Files written before still read."""
    import xarray as xr

    from bouncedisk.io.netcdf import labels_to_cf, open_checked

    with netCDF4.Dataset(every_kind["load"]) as nc:
        assert nc["branch"].dimensions == ("branch_index",) and "branch" not in nc.dimensions
        assert "branch" in nc["mean_omega"].coordinates.split()
    ds = open_checked(every_kind["load"])
    assert list(ds["branch"].values) == ["up", "down"] and "branch_index" not in ds.dims
    assert ds["mean_omega"].dims == ("branch", "load_torque") and "branch" in ds.indexes
    assert ds["branch"].attrs["long_name"] == "direction of the continuation sweep"
    with xr.open_dataset(every_kind["load"]) as raw:  # plain xarray: the labels, selectable
        assert raw["branch"].values.tolist() == ["up", "down"]
        down = raw["mean_omega"].set_xindex("branch").sel(branch="down")
        np.testing.assert_array_equal(down.values, ds["mean_omega"].sel(branch="down"))
    fit = open_checked(every_kind["fit"])
    assert list(fit["parameter"].values) == list(fit["parameter2"].values)
    assert {"parameter", "parameter2", "source"} <= set(fit.indexes)
    # a file in the old layout (string coordinate variable) reads as it did
    old = every_kind["load"].with_name("old-layout.nc")
    ds.to_netcdf(old)
    assert open_checked(old).identical(ds)
    with pytest.raises(ValueError, match="branch_index"):
        labels_to_cf(ds.expand_dims(branch_index=1))
