"""``bouncedisk runs ui``: MLflow's UI on the project's store, opened on the pipeline's runs.

A small store with two pipeline runs (and their job runs) stands for the pipeline's; the command
runs as the user runs it, and headless Chromium (no host but 127.0.0.1 resolves) opens the
address it prints.
"""

from __future__ import annotations

import html
import os
import select
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import browser
import pytest

from bouncedisk.cli import main
from bouncedisk.tracking import store as tracking_store

NAMES = ["pipeline (2 jobs) 2026-01-01 10:00", "pipeline (3 jobs) 2026-01-02 10:00"]
ENV = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
ENV.update(MLFLOW_DISABLE_TELEMETRY="true", DO_NOT_TRACK="true")


@pytest.fixture(scope="module")
def small_store(tmp_path_factory) -> tuple[str, str]:
    """A SQLite store holding two pipeline runs with nested job runs: (URI, a run's id)."""
    base = tmp_path_factory.mktemp("uistore")
    store = tracking_store.resolve_store(f"sqlite:///{base / 'mlflow.db'}")
    tracking_store.preflight(store, create=True)
    client = tracking_store._client(store)
    exp = tracking_store.experiment_id(client, store, create=True)
    for i, name in enumerate(NAMES):
        run = client.create_run(exp, run_name=name, tags={"bouncedisk.kind": "pipeline"})
        client.log_metric(run.info.run_id, "mean_omega", 144.0 + i)
        for j in range(i + 2):
            kid = client.create_run(
                exp,
                run_name=f"simulate: simulations/fig{j}",
                tags={"mlflow.parentRunId": run.info.run_id},
            )
            client.set_terminated(kid.info.run_id)
        client.set_terminated(run.info.run_id)
    return store.uri, run.info.run_id


def _start(uri: str, *extra: str) -> tuple[subprocess.Popen, list[str]]:
    """``bouncedisk runs ui`` in a new session; returns it and the lines it printed up to the
    address (within 120 s)."""
    cmd = [sys.executable, "-m", "bouncedisk.cli", "runs", "ui", "--tracking-uri", uri, *extra]
    proc = subprocess.Popen(
        cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=ENV, start_new_session=True
    )
    got = b""
    deadline = time.monotonic() + 120
    while b"http://" not in got or not got.endswith(b"\n"):
        assert proc.poll() is None, proc.stderr.read()
        assert time.monotonic() < deadline, f"no address printed in 120 s: {got!r}"
        if select.select([proc.stdout], [], [], 1.0)[0]:
            got += os.read(proc.stdout.fileno(), 4096)
    return proc, got.decode().splitlines()


def _stop(proc: subprocess.Popen, sig: int) -> tuple[int, str, str]:
    os.kill(proc.pid, sig)
    try:
        out, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        raise
    return proc.returncode, out.decode(), err.decode()


def _nav(page: str) -> str:
    """The visible words of a page (tags, scripts and styles removed)."""
    import re

    page = re.sub(r"<(script|style)[^>]*>.*?</\1>", " ", page, flags=re.S)
    return " ".join(re.sub(r"<[^>]+>", " ", page).split())


@pytest.mark.slow  # MLflow's server, and Chromium four times
@pytest.mark.cost(40)
def test_runs_ui_opens_on_the_pipeline_runs_and_stops_on_ctrl_c(small_store, tmp_path):
    uri, run_id = small_store
    proc, lines = _start(uri, "--no-browser")
    try:
        url = next(line.strip() for line in lines if "http://" in line)
        assert url.startswith("http://127.0.0.1:") and url.endswith("/bouncedisk/runs"), lines
        base = url.removesuffix("/bouncedisk/runs")
        profile = tmp_path / "profile"
        page = browser.dom(url, profile)
        for name in NAMES:  # the runs table, not the GenAI overview of traces
            assert html.escape(name, quote=False) in page, name
        assert "matching runs" in page
        # a run's page without any query parameter, in the browser that opened the address:
        # the model-training layout (its side bar: runs, models); a fresh browser gets the GenAI
        # one (evaluation, judges) there, which is what the address saves it from
        run_page = f"{base}/#/experiments/1/runs/{run_id}"
        seen = _nav(browser.dom(run_page, profile))
        fresh = _nav(browser.dom(run_page, tmp_path / "fresh-profile"))
        assert NAMES[1] in seen and NAMES[1] in fresh
        assert "Model registry" in seen and "Judges" not in seen, seen[:600]
        assert "Judges" in fresh, fresh[:600]
        # it listens on loopback only (state 0A: LISTEN)
        port = int(base.rsplit(":", 1)[1])
        rows = [r.split() for r in Path("/proc/net/tcp").read_text().splitlines()[1:]]
        rows += [r.split() for r in Path("/proc/net/tcp6").read_text().splitlines()[1:]]
        mine = [r[1] for r in rows if r[3] == "0A" and r[1].endswith(f":{port:04X}")]
        assert mine == [f"0100007F:{port:04X}"], mine
    except BaseException:
        os.killpg(proc.pid, signal.SIGKILL)
        raise
    code, out, err = _stop(proc, signal.SIGINT)
    assert code == 0 and err == "", err
    assert out.strip().splitlines()[-1] == "MLflow UI stopped"
    with socket.socket() as s:  # the port is free again
        s.bind(("127.0.0.1", port))


@pytest.mark.slow  # MLflow's server
def test_runs_ui_on_a_given_port_stops_on_sigterm(small_store):
    uri, _ = small_store
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc, lines = _start(uri, "--port", str(port))  # no display: no browser, no error
    assert any(f"http://127.0.0.1:{port}/bouncedisk/runs" in line for line in lines), lines
    code, out, err = _stop(proc, signal.SIGTERM)
    assert code == 0 and err == "", err


def test_runs_ui_refusals_are_one_line(small_store, tmp_path, capsys):
    uri, _ = small_store
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        cases = [
            (["runs", "ui", "--port", str(port), "--tracking-uri", uri], f"127.0.0.1:{port}"),
            (["runs", "ui", "--port", "70000", "--tracking-uri", uri], "70000"),
            (["runs", "ui", "extra", "--tracking-uri", uri], "extra"),
            (["runs", "list", "--port", "5000", "--tracking-uri", uri], "runs ui"),
            (["runs", "ui", "--tracking-uri", "http://127.0.0.1:9"], "its own UI"),
            (["runs", "ui", "--results", str(tmp_path / "none")], str(tmp_path / "none")),
        ]
        for argv, needle in cases:
            capsys.readouterr()
            try:
                code = main(argv)
            except SystemExit as ex:  # argparse's own refusals (one line, see cli/runs.py)
                code = ex.code
            assert code == 2, argv
            err = capsys.readouterr().err
            assert len(err.strip().splitlines()) == 1 and err.startswith("bouncedisk: error: ")
            assert needle in err, (argv, err)
    assert not (tmp_path / "none").exists()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_before_the_server_runs_stops_it_cleanly(monkeypatch, sig):
    """A Ctrl-C or SIGTERM that comes while the address is being announced (before the event
    loop runs) stops the server normally: no exception, no 'never awaited' warning, the port
    closed and the previous handlers back."""
    import warnings

    from bouncedisk.tracking import ui

    async def app(scope, receive, send):  # an ASGI application that serves nothing
        if scope["type"] == "lifespan":
            while (await receive())["type"] != "lifespan.shutdown":
                await send({"type": "lifespan.startup.complete"})
            await send({"type": "lifespan.shutdown.complete"})

    monkeypatch.setattr(ui, "application", lambda store, exp: app)
    before = {s: signal.getsignal(s) for s in ui.STOP_SIGNALS}
    seen = []

    def announce(url):
        seen.append(url)
        os.kill(os.getpid(), sig)

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ui.serve(None, "1", port=None, open_browser=False, announce=announce)
    assert len(seen) == 1 and seen[0].endswith(ui.LANDING)
    assert {s: signal.getsignal(s) for s in ui.STOP_SIGNALS} == before
    port = int(seen[0].split(":")[2].split("/")[0])
    with socket.socket() as s:  # the port is free again
        s.bind(("127.0.0.1", port))
