"""The Snakemake pipeline: lint, bad config, interrupted runs, determinism across core counts."""

import shutil
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "data" / "config_small.yaml"
pytestmark = pytest.mark.skipif(shutil.which("snakemake") is None, reason="snakemake not found")


def targets(res: Path) -> list[str]:
    names = [
        "continuation/up.nc",
        "sweeps/regime_map.nc",
        "simulations/fig4.nc",
        "poincare/poincare_e06.nc",
        "figures/fig3_trajectory_e03.png",
        "studies/clipped_vs_bouncing.nc",
    ]
    return [str(res / n) for n in names]


def snake(res: Path, cores: int, *extra: str, config: Path = SMALL, items=(), **kw):
    """Start the pipeline on the small config; ``items`` are extra ``--config`` KEY=VALUE."""
    cmd = [
        "snakemake",
        *targets(res),
        "--cores",
        str(cores),
        "--configfile",
        str(config),
        *extra,
        "--config",
        f"results={res}",
        *items,
    ]
    return subprocess.Popen(
        cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, **kw
    )


def run(res: Path, cores: int, *extra: str, config: Path = SMALL, items=()) -> str:
    p = snake(res, cores, *extra, config=config, items=items)
    out, _ = p.communicate(timeout=900)
    assert p.returncode == 0, out[-3000:]
    return out


def data_vars(res: Path) -> dict[str, dict[str, np.ndarray]]:
    out = {}
    for f in sorted(res.rglob("*.nc")):
        with xr.open_dataset(f) as ds:
            out[str(f.relative_to(res))] = {k: ds[k].values for k in ds.data_vars}
    return out


def assert_identical(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for f in a:
        assert a[f].keys() == b[f].keys(), f
        for k in a[f]:
            np.testing.assert_array_equal(a[f][k], b[f][k], err_msg=f"{f}:{k}")


def test_lint_is_clean():
    p = subprocess.run(["snakemake", "--lint"], cwd=ROOT, capture_output=True, text=True)
    assert p.returncode == 0 and "Congratulations" in p.stdout + p.stderr


def dry_run(config: Path, res: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [
            "snakemake",
            "--cores",
            "1",
            "--configfile",
            str(config),
            "--config",
            f"results={res}",
            "-n",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )


def test_bad_config_fails_before_any_job(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(SMALL.read_text().replace("scene: regime_map", "scene: no_such_scene"))
    p = dry_run(bad, tmp_path / "r")
    assert p.returncode != 0 and "sweeps.regime_map.scene" in p.stdout + p.stderr
    bad.write_text(SMALL.read_text().replace("scene: bifurcation", "scene: no_such_scene"))
    p = dry_run(bad, tmp_path / "r")
    assert p.returncode != 0 and "continuation.scene" in p.stdout + p.stderr
    bad.write_text(SMALL.read_text().replace("shards: 3", "shards: -1"))
    p = dry_run(bad, tmp_path / "r")
    assert p.returncode != 0 and "shards" in p.stdout + p.stderr
    bad.write_text(SMALL.read_text().replace("per_omega: 50000", "per_omega: -1"))
    p = dry_run(bad, tmp_path / "r")
    assert p.returncode != 0 and "per_omega" in p.stdout + p.stderr
    assert not (tmp_path / "r").exists()


@pytest.mark.slow
def test_interrupted_run_resumes_to_identical_results_and_cores_do_not_matter(tmp_path):
    a = tmp_path / "one_core"
    run(a, 1)
    # nothing to do the second time
    out = run(a, 1, "--dry-run")
    assert "Nothing to be done" in out or "nothing to be done" in out.lower()
    b = tmp_path / "two_cores"
    p = snake(b, 2, start_new_session=False)
    start = time.monotonic()
    while not list(b.rglob("shard-*.nc")) and time.monotonic() - start < 300:
        assert p.poll() is None, p.communicate()[0][-2000:]
        time.sleep(0.2)
    p.send_signal(signal.SIGINT)
    p.communicate(timeout=300)
    run(b, 2, "--rerun-incomplete")
    assert_identical(data_vars(a), data_vars(b))


@pytest.mark.slow
def test_changing_one_scene_reruns_only_what_depends_on_it(tmp_path):
    res = tmp_path / "r"
    scenes = tmp_path / "scenes"
    shutil.copytree(ROOT / "workflow" / "config" / "scenes", scenes)
    run(res, 2, items=[f"scenes={scenes}"])
    scene = scenes / "fig4.yaml"
    scene.write_text(scene.read_text().replace("impacts: 300", "impacts: 301"))
    out = run(res, 2, "--dry-run", items=[f"scenes={scenes}"])
    jobs = [
        line.split()[0]
        for line in out.splitlines()
        if line.strip().startswith(("simulate", "poincare", "sweep", "fig", "clipped", "compile"))
    ]
    assert any(j.startswith("simulate") for j in jobs)
    assert not any(j.startswith(("sweep", "clipped", "compile")) for j in jobs), out
