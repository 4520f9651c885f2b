"""Experiment tracking on MLflow: real stores in temporary folders, the pipeline on a small config.

The pipeline runs from a temporary working directory holding copies of the scene files (the
tracked scenes are never edited), with the project's Snakefile.
"""

import html
import json
import os
import shutil
import signal
import socket
import sqlite3
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import browser
import numpy as np
import pytest
import xarray as xr
import yaml

from bouncedisk.cli import main
from bouncedisk.tracking import extraction, pipeline
from bouncedisk.tracking import store as tracking_store

#: its module fixtures run the pipeline: built once, on one worker (pytest-xdist loadgroup)
pytestmark = pytest.mark.xdist_group("tracking")

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "data" / "config_small.yaml"
SCENE = """name: {name}
parameters: {{e: {e}, omega_s: 1.5}}
effects: [impacts, contact]
stop: {{impacts: 50}}
"""
needs_snakemake = pytest.mark.skipif(shutil.which("snakemake") is None, reason="no snakemake")
# the first invocation builds these (fig3 and fig4 run side by side with --cores 2); the figure
# brings the other figures of its batch, drawn by the same job
TARGETS = [
    "simulations/fig3.nc",
    "simulations/fig4.nc",
    "figures/fig4_trajectory_e06.png",
    "reproduction.md",
]


#: the figure table (workflow/config/figures.yaml): one job draws every figure of a batch
FIGURE_TABLE = yaml.safe_load((ROOT / "workflow" / "config" / "figures.yaml").read_text())
FIG4_BATCH = FIGURE_TABLE["fig4_trajectory_e06"]["batch"]


def batch_figures(batch: str) -> set[str]:
    """The figures of ``batch`` (those of figure 4's batch need no config key: all drawn)."""
    return {name for name, row in FIGURE_TABLE.items() if row["batch"] == batch}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def project(base: Path) -> Path:
    """A working directory with copies of the scenes and a small config (results inside)."""
    base.mkdir(parents=True, exist_ok=True)
    shutil.copytree(ROOT / "workflow" / "config" / "scenes", base / "workflow/config/scenes")
    cfg = yaml.safe_load(SMALL.read_text())
    cfg["results"] = str(base / "results")
    cfg["prototype"]["curve"] = str(ROOT / cfg["prototype"]["curve"])
    # the smallest search the schema allows: the checks need a fit file, what is tested is its record
    cfg["prototype"].update(scan=8, zoom=0)
    (base / "config.yaml").write_text(yaml.safe_dump(cfg))
    return base


def snake_cmd(base: Path, targets, cores: int = 2, *extra: str) -> list[str]:
    return [
        "snakemake",
        "--snakefile",
        str(ROOT / "Snakefile"),
        "--directory",
        str(base),
        "--cores",
        str(cores),
        "--configfile",
        str(base / "config.yaml"),
        *extra,
        "--",
        *[str(base / "results" / t) for t in targets],
    ]


def snake(base: Path, targets, cores: int = 2, *extra: str) -> str:
    p = subprocess.run(
        snake_cmd(base, targets, cores, *extra),
        cwd=base,
        capture_output=True,
        text=True,
        timeout=600,
    )
    out = p.stdout + p.stderr
    assert p.returncode == 0, out[-4000:]
    return out


def runs_json(base: Path, *args: str) -> object:
    p = subprocess.run(
        ["bouncedisk", "runs", *args, "--json", "--results", str(base / "results")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


def client_of(base: Path):
    store = tracking_store.resolve_store(None, base / "results")
    client = tracking_store._client(store)
    return client, client.get_experiment_by_name(tracking_store.EXPERIMENT).experiment_id


def db_statuses(db: Path) -> list[str]:
    """Statuses of the pipeline runs, read with sqlite3 (cheap enough to poll)."""
    if not db.exists():
        return []
    con = sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=30)
    try:
        return [
            r[0]
            for r in con.execute(
                "SELECT r.status FROM runs r JOIN tags t ON t.run_uuid = r.run_uuid "
                "WHERE t.key = 'bouncedisk.kind' AND t.value = 'pipeline'"
            )
        ]
    except sqlite3.Error:
        return []
    finally:
        con.close()


# ------------------------------------------------------------------------------------------
# generic extraction (fast)
# ------------------------------------------------------------------------------------------


def test_new_outputs_are_picked_up_without_code_changes(tmp_path):
    ds = xr.Dataset(
        {
            "mean_omega": ((), 1.25, {"ci_low": 1.0, "ci_high": 1.5, "units": "1"}),
            "mean_omega_ci_low": ((), 1.0),
            "omega": (("member",), np.arange(4.0)),
        },
        attrs={
            "members": 4,
            "scene_name": "s",
            "impact_rate": 0.5,
            "rate_ci95": np.array([0.4, 0.6]),
            "created": "now",
            "run_id": "x",
        },
    )
    f = tmp_path / "stats.nc"
    ds.to_netcdf(f)
    params, metrics = extraction.describe_output(f)
    assert params == {"members": "4.0", "scene_name": "s"}
    assert metrics == {
        "mean_omega": 1.25,
        "mean_omega.ci_low": 1.0,
        "mean_omega.ci_high": 1.5,
        "mean_omega_ci_low": 1.0,
        "impact_rate": 0.5,
        "rate_ci95.low": 0.4,
        "rate_ci95.high": 0.6,
    }
    j = tmp_path / "s.json"
    j.write_text(json.dumps({"a": 1, "b": {"c": [0.1, 0.2], "d": "text"}, "ok": True}))
    assert extraction.describe_output(j) == ({}, {"a": 1.0, "b.c.0": 0.1, "b.c.1": 0.2, "ok": 1.0})
    md = tmp_path / "reproduction.md"
    md.write_text(
        "| claim | measured | expected | result | from |\n| --- | --- | --- | --- | --- |\n"
        "| period 1 exists | engine: Gamma = 1.69 | 1.7 | **pass** | x |\n"
        "| chaos | no period | Lyapunov > 0 | **FAIL** | y |\n"
    )
    _, m = extraction.describe_output(md)
    assert m["check.period_1_exists.passed"] == 1.0
    assert m["check.period_1_exists.measured"] == 1.69
    assert m["check.chaos.passed"] == 0.0 and "check.chaos.measured" not in m
    assert (m["checks.passed"], m["checks.failed"], m["checks.total"]) == (1, 1, 2)


# ------------------------------------------------------------------------------------------
# bad input: one line, exit 2, nothing computed
# ------------------------------------------------------------------------------------------


def one_error_line(err: str, *needles: str) -> None:
    """The one error line of ``err``, beside Snakemake's own "Using workflow specific profile"."""
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("Using workflow")]
    assert len(lines) == 1, err
    assert lines[0].startswith("bouncedisk: error: ")
    for n in needles:
        assert n in lines[0], lines[0]


@pytest.mark.slow  # MLflow stores made and read
def test_unusable_store_and_unknown_run_exit_2_with_one_line(tmp_path, capsys):
    scene = tmp_path / "s.yaml"
    scene.write_text(SCENE.format(name="s", e=0.3))
    out = tmp_path / "s.nc"
    unreachable = f"http://127.0.0.1:{free_port()}"
    read_only = "sqlite:////proc/bouncedisk-test/mlflow.db"  # read-only even for root
    garbage = tmp_path / "garbage.db"
    garbage.write_bytes(b"not a database" * 100)
    for uri in (unreachable, read_only, f"sqlite:///{garbage}"):
        capsys.readouterr()
        assert main(["simulate", str(scene), "-o", str(out), "--track", "--tracking-uri", uri]) == 2
        one_error_line(capsys.readouterr().err, uri)
        assert not out.exists()
    # a store with one run; unknown ids, extra or unknown arguments, a missing store
    store = f"sqlite:///{tmp_path / 'store' / 'mlflow.db'}"
    assert (
        main(["simulate", str(scene), "-o", str(out), "-q", "--track", "--tracking-uri", store])
        == 0
    )
    cases = [
        (["runs", "show", "nosuchrun"], "nosuchrun"),
        (["runs", "diff", "nosuchrun", "other"], "nosuchrun"),
        (["runs", "show", "a", "b"], "runs"),
        (["runs", "list", "extra"], "runs"),
    ]
    for argv, needle in cases:
        capsys.readouterr()
        assert main([*argv, "--tracking-uri", store]) == 2, argv
        one_error_line(capsys.readouterr().err, needle)
    with pytest.raises(SystemExit) as ex:  # argparse's refusal, as every subcommand's
        main(["runs", "--bogus", "--tracking-uri", store])
    assert ex.value.code == 2
    one_error_line(capsys.readouterr().err, "runs: unrecognized arguments: --bogus (see")
    capsys.readouterr()
    assert main(["runs", "--results", str(tmp_path / "none")]) == 2
    one_error_line(capsys.readouterr().err, str(tmp_path / "none"))
    assert not (tmp_path / "none").exists()


@pytest.mark.slow  # a Snakemake subprocess
@needs_snakemake
def test_pipeline_with_unreachable_store_fails_before_any_job(tmp_path):
    base = project(tmp_path / "p")
    uri = f"http://127.0.0.1:{free_port()}"
    p = subprocess.run(
        snake_cmd(base, ["simulations/fig3.nc"], 1, "--config", f"tracking={{uri: '{uri}'}}"),
        cwd=base,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode != 0
    errors = [ln for ln in (p.stdout + p.stderr).splitlines() if "bouncedisk: error" in ln]
    assert len(errors) == 1 and uri in errors[0], p.stdout + p.stderr
    assert not (base / "results").exists()  # not even the engine compiled
    # the untracked switch: the same unreachable URI is never contacted
    snake(base, ["logs/engine_compiled.flag"], 1, "--config", "tracking=false")
    assert (base / "results/logs/engine_compiled.flag").exists()
    assert not (base / "results/mlflow.db").exists()


# ------------------------------------------------------------------------------------------
# two pipeline invocations with one scene changed
# ------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    base = project(tmp_path_factory.mktemp("tracked"))
    first = snake(base, TARGETS, 2)
    again = snake(base, TARGETS, 2)  # nothing to do: nothing logged
    assert "Nothing to be done" in again
    scene = base / "workflow/config/scenes/fig4.yaml"
    scene.write_text(scene.read_text().replace("r_phi: 0.01", "r_phi: 0.02"))
    second = snake(base, TARGETS, 2)
    return base, first, second


@pytest.mark.slow
@pytest.mark.cost(81)  # the fixture's three pipeline invocations
@needs_snakemake
def test_two_invocations_two_parent_runs_and_the_diff_names_the_change(two_runs):
    base, first, _ = two_runs
    rows = runs_json(base)
    assert [r["kind"] for r in rows] == ["pipeline", "pipeline"]
    assert [r["status"] for r in rows] == ["FINISHED", "FINISHED"]
    a, b = rows[0]["run_id"], rows[1]["run_id"]
    assert rows[1]["previous"] == a
    # fig4's simulation and its ensemble band (figure 4 draws it) depend on the scene
    changed = [f"{o}/fig4/{k}" for o in ("bands", "simulations") for k in ("r_phi", "scene_sha256")]
    assert rows[1]["changed"] == changed
    assert rows[0]["checks_total"] == 14 and rows[0]["checks_passed"] == 14
    # the files can be gone: the store keeps what the diff needs
    shutil.rmtree(base / "results" / "simulations")
    # options in any position, run id prefixes
    p = subprocess.run(
        ["bouncedisk", "runs", "diff", a[:10], "--results", str(base / "results"), b, "--json"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert set(d["params"]) == set(changed)
    assert d["params"]["simulations/fig4/r_phi"] == ["0.01", "0.02"]
    # figure 4 is redrawn by the job of its batch (figures/paper), with the batch's other figures
    depends = ("simulations/fig4/", "bands/fig4/", f"figures/{FIG4_BATCH}/")
    assert d["metrics"] and all(k.startswith(depends) for k in d["metrics"]), d["metrics"]
    assert "simulations/fig4/final_omega" in d["metrics"]
    assert f"figures/{FIG4_BATCH}/benchmark.s" in d["metrics"]
    assert {"simulations/fig4.nc", "figures/fig4_trajectory_e06.png"} <= set(d["outputs"])
    assert set(d["outputs"]) <= {"simulations/fig4.nc", "bands/fig4.nc"} | {
        f"figures/{name}.{ext}" for name in batch_figures(FIG4_BATCH) for ext in ("png", "pdf")
    }
    # text form too
    text = subprocess.run(
        ["bouncedisk", "runs", "diff", "--results", str(base / "results")],
        capture_output=True,
        text=True,
        timeout=120,
    ).stdout
    assert "simulations/fig4/r_phi: 0.01 | 0.02" in text


@pytest.mark.slow
@needs_snakemake
def test_first_run_keeps_its_metrics_artifacts_and_every_job_record(two_runs):
    base, first, second = two_runs
    client, exp = client_of(base)
    rows = runs_json(base)
    a = client.get_run(rows[0]["run_id"])
    assert a.data.metrics["simulations/fig4/n_impacts"] == 300
    assert a.data.params["simulations/fig4/r_phi"] == "0.01"
    assert a.data.metrics["checks.passed"] == a.data.metrics["checks.total"] == 14
    assert sum(k.startswith("reproduction/check.") for k in a.data.metrics) >= 12
    # --cores 2: every job that ran has its nested run, with its benchmark numbers
    for run, log in ((a, first), (client.get_run(rows[1]["run_id"]), second)):
        kids = client.search_runs(
            [exp], filter_string=f"tags.mlflow.parentRunId = '{run.info.run_id}'"
        )
        steps = int(log.split(" steps (100%) done")[0].rsplit("\n", 1)[-1].split(" of ")[0])
        assert len(kids) == steps == int(run.data.tags["bouncedisk.jobs_planned"])
        assert all(
            k.info.status == "FINISHED" and "benchmark.max_rss" in k.data.metrics for k in kids
        )
    kids = client.search_runs([exp], filter_string=f"tags.mlflow.parentRunId = '{a.info.run_id}'")
    kinds = {k.data.tags["bouncedisk.kind"] for k in kids}
    assert {"simulation", "figure", "check", "build"} <= kinds
    # the figures are drawn in batches: one job, named figures/<batch>, draws figure 4 and the
    # other figures of its batch, and its record holds every one of them
    batches = [k for k in kids if k.data.tags["bouncedisk.kind"] == "figure"]
    assert {k.data.tags["bouncedisk.job"] for k in batches} == {f"figures/{FIG4_BATCH}"}
    (fig,) = batches
    assert fig.data.tags["bouncedisk.rule"] == f"figure_{FIG4_BATCH}"
    assert fig.data.params["rule.figures.fig4_trajectory_e06.plot"] == "trajectory"
    names = {f.path for f in client.list_artifacts(fig.info.run_id, "outputs")}
    assert names == {
        f"outputs/{name}.{ext}" for name in batch_figures(FIG4_BATCH) for ext in ("png", "pdf")
    }
    png = Path(client.download_artifacts(fig.info.run_id, "outputs/fig4_trajectory_e06.png"))
    assert png.read_bytes()[:4] == b"\x89PNG"
    manifest = json.loads(
        Path(client.download_artifacts(a.info.run_id, "outputs.json")).read_text()
    )
    assert len(manifest["simulations/fig4.nc"]["sha256"]) == 64
    assert str(base / "results" / "mlartifacts") in a.info.artifact_uri


@pytest.mark.slow
@needs_snakemake
def test_mlflow_server_on_the_store_answers_with_the_pipeline_runs(two_runs):
    base, _, _ = two_runs
    rows = runs_json(base)
    port = free_port()
    env = dict(
        os.environ,
        MLFLOW_DISABLE_TELEMETRY="true",
        DO_NOT_TRACK="true",
        MLFLOW_SERVER_ENABLE_JOB_EXECUTION="false",  # no background job workers: a plain server
    )
    res = base / "results"
    server = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "mlflow",
            "server",
            "--backend-store-uri",
            f"sqlite:///{res / 'mlflow.db'}",
            "--default-artifact-root",
            (res / "mlartifacts").as_uri(),
            "--host",
            "127.0.0.1",
            "--port",
            str(port),
            "--workers",
            "1",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
        start_new_session=True,
    )
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 90
        while True:
            assert server.poll() is None, "mlflow server exited"
            try:
                with urllib.request.urlopen(f"{url}/health", timeout=2) as r:
                    if r.status == 200:
                        break
            except OSError:
                pass
            assert time.monotonic() < deadline, "mlflow server did not answer in 90 s"
            time.sleep(0.5)
        exp = tracking_store._http_request(
            url, "/api/2.0/mlflow/experiments/get-by-name?experiment_name=bouncedisk", 10
        )
        body = {"experiment_ids": [exp["experiment"]["experiment_id"]], "max_results": 500}
        found = tracking_store._http_request(url, "/api/2.0/mlflow/runs/search", 10, body)["runs"]
        ids = {r["info"]["run_id"] for r in found}
        assert {rows[0]["run_id"], rows[1]["run_id"]} <= ids
        # the same code reads the store through the server
        p = subprocess.run(
            ["bouncedisk", "runs", "--json", "--tracking-uri", url],
            capture_output=True,
            text=True,
            timeout=120,
            env=env,
        )
        assert p.returncode == 0, p.stderr
        assert [r["run_id"] for r in json.loads(p.stdout)] == [r["run_id"] for r in rows]
        check_ui_opens_on_the_runs(url, exp["experiment"], [r["name"] for r in rows], base)
    finally:
        os.killpg(server.pid, signal.SIGTERM)
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(server.pid, signal.SIGKILL)
            server.wait(timeout=20)
    assert server.poll() is not None


def check_ui_opens_on_the_runs(url: str, exp: dict, names: list[str], tmp: Path) -> None:
    """The experiment is tagged for MLflow's machine-learning view, and the URL of
    docs/user_guide/tracking.md opens on the runs table listing the pipeline's parent runs,
    named with their jobs' count (headless Chromium; no host but 127.0.0.1 resolves)."""
    tags = {t["key"]: t["value"] for t in exp.get("tags", [])}
    assert tags.get("mlflow.experimentKind") == "custom_model_development", tags
    assert names and all(n.startswith("pipeline (") and " jobs) " in n for n in names), names
    ui = f"{url}/#/experiments/{exp['experiment_id']}/runs?workflowType=machine_learning"
    page = browser.dom(ui, tmp / "chromium-profile")
    for name in names:
        assert html.escape(name, quote=False) in page, name
    assert "matching runs" in page  # the runs table's footer, not the GenAI overview of traces
    img = browser.screenshot(ui, tmp / "mlflow-runs.png", size="1400,900")
    grey = img.mean(axis=2)
    assert grey.std() > 10.0 and 0.002 < np.mean(grey < 128) < 0.6


# ------------------------------------------------------------------------------------------
# interrupted and killed pipelines
# ------------------------------------------------------------------------------------------


def start_and_wait_running(base: Path) -> subprocess.Popen:
    """Start a pipeline with a long job; return once its parent run is RUNNING in the store."""
    log = open(base / "snakemake.out", "w")  # noqa: SIM115 - closed with the process
    p = subprocess.Popen(
        snake_cmd(base, ["fit/prototype.nc"], 1, "--rerun-incomplete"),
        cwd=base,
        stdout=log,
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )
    log.close()
    db = base / "results" / "mlflow.db"
    deadline = time.monotonic() + 120
    while "RUNNING" not in db_statuses(db):
        out = (base / "snakemake.out").read_text()
        assert p.poll() is None, f"the pipeline ended before its run was recorded:\n{out[-3000:]}"
        assert time.monotonic() < deadline
        time.sleep(0.2)
    return p


@pytest.mark.slow
@needs_snakemake
def test_interrupted_or_killed_pipeline_never_reads_finished(tmp_path):
    base = project(tmp_path / "p")
    db = base / "results" / "mlflow.db"
    # Ctrl-C (SIGINT to the terminal's foreground process group: Snakemake and its running job):
    # the job stops, Snakemake cancels the rest, onerror ends the run KILLED
    p = start_and_wait_running(base)
    os.killpg(p.pid, signal.SIGINT)
    p.wait(timeout=120)
    assert p.returncode != 0
    assert db_statuses(db) == ["KILLED"]
    # SIGKILL: nothing runs on the way out; the run stays RUNNING in the store, reads KILLED
    p = start_and_wait_running(base)
    os.killpg(p.pid, signal.SIGKILL)
    p.wait(timeout=60)
    assert sorted(db_statuses(db)) == ["KILLED", "RUNNING"]
    assert [r["status"] for r in runs_json(base)] == ["KILLED", "KILLED"]
    # and the next writer on this host ends it as KILLED
    client, exp = client_of(base)
    assert pipeline.mark_stale_runs(client, exp) == 1
    assert db_statuses(db) == ["KILLED", "KILLED"]


# ------------------------------------------------------------------------------------------
# tracked commands (the quick start), written concurrently
# ------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_concurrent_tracked_commands_lose_no_record_and_diff_by_their_run_ids(tmp_path):
    store = f"sqlite:///{tmp_path / 'results' / 'mlflow.db'}"
    procs = []
    for i, e in enumerate((0.3, 0.6, 0.5)):
        scene = tmp_path / f"s{i}.yaml"
        scene.write_text(SCENE.format(name="quick", e=e))
        procs.append(
            subprocess.Popen(
                ["bouncedisk", "simulate", str(scene), "-o", str(tmp_path / f"s{i}.nc")]
                + ["--track", "--tracking-uri", store],
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
            )
        )
    outs = [p.communicate(timeout=300) for p in procs]
    assert all(p.returncode == 0 for p in procs), outs
    for _, err in outs:  # one line of its own on stderr, no MLflow chatter
        assert [ln for ln in err.splitlines() if "bouncedisk" in ln or "INFO" in ln] == [
            ln for ln in err.splitlines() if ln.startswith("bouncedisk: recorded run ")
        ], err
    printed = [o.split("(run ")[1].split(")")[0] for o, _ in outs]  # bouncedisk run ids
    p = subprocess.run(
        ["bouncedisk", "runs", "--json", "--tracking-uri", store],
        capture_output=True,
        text=True,
        timeout=120,
    )
    rows = json.loads(p.stdout)
    assert sorted(r["output_run_id"] for r in rows) == sorted(printed)
    assert {r["kind"] for r in rows} == {"simulate"} and {r["status"] for r in rows} == {"FINISHED"}
    p = subprocess.run(
        ["bouncedisk", "runs", "diff", printed[0], printed[1], "--json", "--tracking-uri", store],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert d["params"]["e"] == ["0.3", "0.6"]
