"""The Snakemake pipeline: lint, bad config, interrupted runs, determinism across core counts."""

import contextlib
import io
import shutil
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from bouncedisk.figures import drawing
from bouncedisk.figures import registry as figure_registry

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "data" / "config_small.yaml"
#: Snakemake's own line, before any of the pipeline's: the default profile was read.
PROFILE_LINE = "Using workflow specific profile"
#: one worker runs every Snakemake in the project root (pytest-xdist ``--dist loadgroup``)
pytestmark = [
    pytest.mark.skipif(shutil.which("snakemake") is None, reason="snakemake not found"),
    pytest.mark.xdist_group("snakemake-root"),
]


def targets(res: Path) -> list[str]:
    """A sharded sweep, simulations, a Poincaré map, a figure batch and a study: what a scene
    change must or must not rerun, and shards that an interrupted run leaves half done (the
    sensitivity study's shards and the continuation are tested on their own:
    tests/test_sensitivity.py, tests/test_analysis_and_outputs.py)."""
    names = [
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


def dry_run(config: Path, res: Path, cwd: Path = ROOT) -> subprocess.CompletedProcess:
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
        cwd=cwd,
        capture_output=True,
        text=True,
    )


def parse_error(config: Path, res: Path, monkeypatch, cwd: Path = ROOT) -> str:
    """The error that stops the workflow's parse and DAG (what ``snakemake -n`` does before any
    job), "" when there is none. In this process, through Snakemake's API: a ``snakemake``
    process per case would spend a second and a half importing Snakemake each time."""
    from snakemake.api import SnakemakeApi
    from snakemake.settings.types import ConfigSettings, OutputSettings, ResourceSettings

    monkeypatch.chdir(cwd)  # Snakemake changes into the workdir; pytest changes back
    err = io.StringIO()
    try:
        with SnakemakeApi(OutputSettings()) as api, contextlib.redirect_stderr(err):
            api.workflow(
                resource_settings=ResourceSettings(cores=1),
                config_settings=ConfigSettings(configfiles=[config], config={"results": str(res)}),
                snakefile=cwd / "Snakefile",
                workdir=cwd,
            ).dag()
    except SystemExit as ex:  # the pipeline's own one line (exit status 2)
        assert ex.code == 2 and len(err.getvalue().strip().splitlines()) == 1, err.getvalue()
        return err.getvalue()
    except Exception as ex:  # noqa: BLE001 - any error is the answer
        return str(ex)
    return ""


@pytest.mark.slow  # Snakemake parses the pipeline once per bad config
def test_bad_config_fails_before_any_job(tmp_path, monkeypatch):
    bad = tmp_path / "bad.yaml"
    # one case end to end: the snakemake command fails, naming the key
    bad.write_text(SMALL.read_text().replace("scene: regime_map", "scene: no_such_scene"))
    p = dry_run(bad, tmp_path / "r")
    assert p.returncode != 0 and "sweeps.regime_map.scene" in p.stdout + p.stderr
    for old, new, key in (
        ("scene: bifurcation", "scene: no_such_scene", "continuation.scene"),
        ("shards: 3", "shards: -1", "shards"),
        ("per_omega: 50000", "per_omega: -1", "per_omega"),
        ("scan: 32", "scan: 4", "scan"),
        ("results: results-small", "results: results-small\ntrackin: true", "trackin"),
        # a swept value the model refuses: before the first shard, not after it
        (
            "e: {min: 0.2, max: 0.8, n: 4}",
            "e: {min: 0.2, max: 1.5, n: 4}",
            "sweeps.regime_map.axes.e: the value 1.5: must be in [0, 1]",
        ),
        (
            "r_phi: {values: [0.01, 0.1]}",
            "r_fi: {values: [0.01, 0.1]}",
            "sweeps.psi_speed.axes: 'r_fi' is not one of",
        ),
    ):
        bad.write_text(SMALL.read_text().replace(old, new))
        assert key in parse_error(bad, tmp_path / "r", monkeypatch), key
    # a scene file the config names is read before any job: its own one line
    scenes = tmp_path / "scenes"
    shutil.copytree(ROOT / "workflow" / "config" / "scenes", scenes)
    (scenes / "fig3.yaml").write_text(
        (scenes / "fig3.yaml").read_text().replace("e: 0.3", "e: 1.7")
    )
    bad.write_text(SMALL.read_text() + f"\nscenes: {scenes}\n")
    line = parse_error(bad, tmp_path / "r", monkeypatch)
    assert (
        line.strip()
        == f"bouncedisk: error: {scenes}/fig3.yaml: parameters.e: must be in [0, 1], got 1.7"
    )
    assert not (tmp_path / "r").exists()


@pytest.mark.slow  # as above
def test_bad_sensitivity_ranges_or_sizes_are_one_line_exit_2_before_any_job(tmp_path):
    bad = tmp_path / "bad.yaml"
    for old, new, field in (
        ("e: [0.1, 0.9]", "e: [0.9, 0.1]", "sensitivity_study.ranges.e"),
        ("base_samples: 8,", "base_samples: 12,", "sensitivity_study.sizes.small.base_samples"),
    ):
        assert old in SMALL.read_text()
        bad.write_text(SMALL.read_text().replace(old, new, 1))
        p = dry_run(bad, tmp_path / "r")
        lines = [ln for ln in p.stderr.strip().splitlines() if not ln.startswith(PROFILE_LINE)]
        assert p.returncode == 2 and len(lines) == 1, p.stdout[-1000:] + p.stderr[-1000:]
        assert lines[0].startswith("bouncedisk: error: pipeline config: " + field), lines
    assert not (tmp_path / "r").exists()


# results/figures/<name>.pdf and .png: what README, `bouncedisk check` and the report point at
FIGURE_NAMES = {
    "fig2_schematic",
    "fig3_trajectory_e03",
    "fig4_trajectory_e06",
    "fig5_prototype_fit",
    "poincare_maps",
    "bifurcation_e",
    "regime_map",
    "speed_vs_psi",
    "clipped_vs_bouncing",
    "work_precision",
    "scaling",
    "stats_cost",
    "sensitivity_indices",
    "sensitivity_scatter",
    "design_maps",
    "torque_speed_fig3",
    "torque_speed_fig4",
    "torque_speed_prototype",
    "fit_profiles",
    "fit_load",
    "fit_identifiability",
    "basin_map",
    "startup_under_load",
}


def test_figure_table_names_every_figure_and_uses_every_registered_plot():
    table = yaml.safe_load((ROOT / "workflow" / "config" / "figures.yaml").read_text())
    assert set(table) == FIGURE_NAMES
    assert {row["plot"] for row in table.values()} == set(drawing.FIGURES)
    for name, row in table.items():
        spec = drawing.FIGURES[row["plot"]]
        assert set(row.get("inputs", {})) == set(spec.inputs), name
        assert set(row.get("params", {})) == set(spec.params), name
        assert (ROOT / "workflow" / "report" / f"{row['caption']}.rst").is_file(), name


def pipeline_copy(tmp_path: Path) -> tuple[Path, Path, str]:
    """A scratch copy of the pipeline: its root, its figure table and the table's text."""
    copy = tmp_path / "copy"
    shutil.copytree(ROOT / "workflow", copy / "workflow")
    shutil.copytree(ROOT / "data", copy / "data")
    shutil.copy(ROOT / "Snakefile", copy / "Snakefile")
    table = copy / "workflow" / "config" / "figures.yaml"
    return copy, table, table.read_text()


def test_a_bad_figure_table_names_the_table_and_the_entry(tmp_path, monkeypatch):
    # a scratch copy of the pipeline, whose figure table is broken one way at a time
    copy, table, good = pipeline_copy(tmp_path)
    entry = "  caption: regime_map\n  category: Studies beyond the paper\n"
    assert entry in good
    for broken, message in (
        (good.replace(entry, "  caption: regime_map\n"), "regime_map: 'category' is a required"),
        (good + "bad:\n  plot: [fig2\n", 'in "'),  # malformed YAML: the position in the file
        ("- fig2\n", "must be a mapping"),
    ):
        table.write_text(broken)
        out = parse_error(SMALL, tmp_path / "r", monkeypatch, cwd=copy)
        assert "figures.yaml" in out and message in out, out[-2000:]
        assert "config file" not in out and "<unicode string>" not in out
    assert not (tmp_path / "r").exists()


def test_a_figure_without_a_batch_or_with_a_bad_batch_name_is_refused_before_any_job(
    tmp_path, monkeypatch
):
    # each figure is drawn by the job of its batch (rule figure_<batch>): the batch is required
    # and a plain identifier, checked with the table before any job, naming the table and entry
    copy, table, good = pipeline_copy(tmp_path)
    entry = "regime_map:\n  batch: dynamics\n"
    assert entry in good
    pattern = "does not match '^[A-Za-z][A-Za-z0-9_]*$'"
    for broken, message in (
        (good.replace(entry, "regime_map:\n"), "regime_map: 'batch' is a required property"),
        (
            good.replace(entry, "regime_map:\n  batch: dyn amics\n"),
            f"regime_map.batch: 'dyn amics' {pattern}",
        ),
        (good.replace(entry, "regime_map:\n  batch: 2nd\n"), f"regime_map.batch: '2nd' {pattern}"),
        (
            good.replace(entry, "regime_map:\n  batch: ../x\n"),
            f"regime_map.batch: '../x' {pattern}",
        ),
        (
            good.replace(entry, "regime_map:\n  batch: [dynamics]\n"),
            "regime_map.batch: ['dynamics'] is not of type 'string'",
        ),
        # a figure's name holds no "__": its batch job's inputs and outputs are <figure>__<name>
        (
            good.replace(entry, "regime__map:\n  batch: dynamics\n"),
            "(top level): 'regime__map' does not match",
        ),
    ):
        table.write_text(broken)
        out = parse_error(SMALL, tmp_path / "r", monkeypatch, cwd=copy)
        assert f"figures.yaml: {message}" in out, out[-2000:]
        assert "config file" not in out
    # the end-to-end command: it fails before any job, the message on one line
    table.write_text(good.replace(entry, "regime_map:\n  batch: dyn amics\n"))
    p = dry_run(SMALL, tmp_path / "r", cwd=copy)
    lines = [ln for ln in (p.stdout + p.stderr).splitlines() if "figures.yaml" in ln]
    assert p.returncode == 2 and len(lines) == 1, p.stdout[-2000:] + p.stderr[-2000:]
    assert "Traceback" not in p.stdout + p.stderr and lines[0].startswith("bouncedisk: error: ")
    assert "regime_map.batch: 'dyn amics'" in lines[0]
    assert not (tmp_path / "r").exists()


def planned_jobs(out: str) -> list[tuple[str, list[str]]]:
    """(rule, outputs) of every job a dry run printed."""
    jobs = []
    for block in out.split("\nrule ")[1:]:
        rule = block.split(":", 1)[0]
        outputs = next(
            (ln.split(":", 1)[1] for ln in block.splitlines() if ln.strip().startswith("output:")),
            "",
        )
        jobs.append((rule, [o.strip() for o in outputs.split(",") if o.strip()]))
    return jobs


#: Figures of the joint fit: drawn only when the config names a load curve (figures.yaml ``needs``);
#: the small config fits the run-up alone.
#: The figures that need the prototype's load curve (the joint fit's, and the fitted motor's load
#: characteristic, whose rotor its sidecar gives): the table's `needs`.
JOINT_FIGURES = {
    name
    for name, entry in yaml.safe_load((ROOT / "workflow/config/figures.yaml").read_text()).items()
    if entry.get("needs") == "prototype.load_curve"
}
assert JOINT_FIGURES == {"fit_load", "fit_identifiability", "torque_speed_prototype"}


def test_the_figure_batches_draw_exactly_what_rule_all_wants(tmp_path):
    table = yaml.safe_load((ROOT / "workflow" / "config" / "figures.yaml").read_text())
    res = tmp_path / "r"
    p = dry_run(SMALL, res)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    jobs = [
        (rule, {str(Path(o).relative_to(res)) for o in outs if o.startswith(str(res / "figures"))})
        for rule, outs in planned_jobs(p.stdout)
    ]
    drawn = FIGURE_NAMES - JOINT_FIGURES  # the small config sets prototype.load_curve: null
    # one job per batch (rule figure_<batch>), drawing exactly its figures, PDF and PNG
    wanted = {}
    for name in drawn:
        wanted.setdefault(f"figure_{table[name]['batch']}", set()).update(
            {f"figures/{name}.pdf", f"figures/{name}.png"}
        )
    figure_jobs = [(rule, figs) for rule, figs in jobs if figs]
    assert sorted(rule for rule, _ in figure_jobs) == sorted(wanted)
    assert dict(figure_jobs) == wanted
    assert len(wanted) < len(drawn) / 3  # batches, not a job per figure
    # with the default config (a load curve) the joint fit's figures are wanted too, drawn by
    # the job of their batch
    q = dry_run(ROOT / "workflow" / "config" / "config.yaml", tmp_path / "full")
    assert q.returncode == 0, q.stdout[-3000:] + q.stderr[-3000:]
    for rule, outs in planned_jobs(q.stdout):
        for name in JOINT_FIGURES:
            made = str(tmp_path / "full" / "figures" / f"{name}.png") in outs
            assert made == (rule == f"figure_{table[name]['batch']}"), (rule, name)
    assert all(f"figures/{n}.png" in q.stdout for n in JOINT_FIGURES)


def test_one_figure_asked_for_runs_the_job_of_its_batch(tmp_path):
    table = yaml.safe_load((ROOT / "workflow" / "config" / "figures.yaml").read_text())
    res = tmp_path / "r"
    p = subprocess.run(
        ["snakemake", "--cores", "1", "--configfile", str(SMALL), "--config", f"results={res}"]
        + ["-n", "--", str(res / "figures" / "regime_map.pdf")],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    batch = table["regime_map"]["batch"]
    same = {n for n, row in table.items() if row["batch"] == batch} - JOINT_FIGURES
    figure_jobs = [(r, o) for r, o in planned_jobs(p.stdout) if any("/figures/" in x for x in o)]
    assert [r for r, _ in figure_jobs] == [f"figure_{batch}"]
    assert set(figure_jobs[0][1]) == {
        str(res / "figures" / f"{n}.{e}") for n in same for e in ("pdf", "png")
    }
    assert not res.exists()


def test_figure_registry_refuses_an_unknown_figure_or_wrong_inputs(tmp_path):
    with pytest.raises(ValueError, match=r"unknown figure 'nope'; known figures: .*trajectory"):
        drawing.draw_figure("nope", {})
    with pytest.raises(ValueError, match=r"takes the inputs \['table'\], given \['tabel'\]"):
        drawing.draw_figure("scaling", {"tabel": "x.csv"})
    with pytest.raises(ValueError, match=r"takes the parameters \['labels'\], given \[\]"):
        drawing.draw_figure("poincare", {"maps": []})
    assert drawing.draw_figure("fig2", {}).axes
    # an optional input (the trajectory's band: fig_trajectory's band=None) may be left out
    with pytest.raises(ValueError, match=r"takes the inputs \['sim', 'band \(optional\)'\]"):
        drawing.draw_figure("trajectory", {"band": "b.nc"})
    import bouncedisk as bd

    scene = bd.load_scene("fig3", ["stop.impacts=40"])
    bd.run_scene(scene, tmp_path / "fig3.nc", progress=False)
    assert len(drawing.draw_figure("trajectory", {"sim": str(tmp_path / "fig3.nc")}).axes) == 3
    bd.run_scene(bd.load_scene("poincare_e03", ["stop.impacts=40"]), tmp_path / "p.nc", False)
    with pytest.raises(ValueError, match="poincare_e03: no dense trajectory to draw"):
        drawing.draw_figure("trajectory", {"sim": str(tmp_path / "p.nc")})


def run_figure_script(tmp_path, figures, inputs):
    """Run workflow/scripts/figure.py as Snakemake would, on a batch of ``figures`` (name ->
    plot, options) with ``inputs`` (``<figure>__<name>`` -> path); the outputs' folder."""
    import gc
    import runpy
    from types import SimpleNamespace

    out = tmp_path / "figures"
    out.mkdir(parents=True)
    outputs = {f"{n}__{e}": str(out / f"{n}.{e}") for n in figures for e in ("pdf", "png")}
    fake = SimpleNamespace(
        input={"code": str(tmp_path / "flag"), **inputs},  # what it reads: items(), by name
        output=outputs,
        log=[str(tmp_path / "batch.log")],
        params=SimpleNamespace(
            batch="b",
            figures={
                n: {"plot": plot, "options": options} for n, (plot, options) in figures.items()
            },
        ),
    )
    try:
        runpy.run_path(str(ROOT / "workflow" / "scripts" / "figure.py"), {"snakemake": fake})
    finally:
        gc.unfreeze()  # log_to froze the heap, as at a job's end: this process goes on
    return out


def test_the_figure_script_draws_a_batch_and_a_failing_figure_leaves_no_output(tmp_path):
    # a batch of two figures: both drawn, PDF and PNG, in one process
    out = run_figure_script(tmp_path / "ok", {"a": ("fig2", {}), "b": ("fig2", {})}, {})
    assert sorted(p.name for p in out.iterdir()) == ["a.pdf", "a.png", "b.pdf", "b.png"]
    assert (out / "a.png").read_bytes()[:4] == b"\x89PNG"
    assert (out / "b.pdf").read_bytes()[:5] == b"%PDF-"
    # the second of three figures fails (a table without the columns it plots): the job fails
    # naming it, the first figure's files are removed again, the third is never drawn
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y\n1,2\n")
    figures = {"first": ("fig2", {}), "broken": ("scaling", {}), "third": ("fig2", {})}
    with pytest.raises(RuntimeError) as info:
        run_figure_script(tmp_path / "fail", figures, {"broken__table": str(bad)})
    assert str(info.value).startswith("figure batch 'b': figure 'broken' (plot 'scaling') failed: ")
    assert list((tmp_path / "fail" / "figures").iterdir()) == []  # no temporary either
    log = (tmp_path / "fail" / "batch.log").read_text()
    assert (
        "figure 'broken'" in log and f"removed {tmp_path / 'fail' / 'figures' / 'first.png'}" in log
    )


@pytest.mark.slow
@pytest.mark.cost(70)
def test_one_run_is_final_reruns_only_what_a_scene_change_affects_and_cores_do_not_matter(tmp_path):
    """One run of the small pipeline on one core serves three checks (each ran it once before):
    a second invocation has nothing to do; after one scene changes, the plan reruns only what
    depends on it; an interrupted two-core run, resumed, gives bit-identical data."""
    scenes = tmp_path / "scenes"
    shutil.copytree(ROOT / "workflow" / "config" / "scenes", scenes)
    items = [f"scenes={scenes}"]
    a = tmp_path / "one_core"
    run(a, 1, items=items)
    out = run(a, 1, "--dry-run", items=items)
    assert "nothing to be done" in out.lower()
    scene = scenes / "fig4.yaml"
    original = scene.read_text()
    scene.write_text(original.replace("impacts: 300", "impacts: 301"))
    out = run(a, 1, "--dry-run", items=items)
    jobs = [
        line.split()[0]
        for line in out.splitlines()
        if line.strip().startswith(("simulate", "poincare", "sweep", "fig", "clipped", "compile"))
    ]
    assert any(j.startswith("simulate") for j in jobs)
    assert not any(j.startswith(("sweep", "clipped", "compile")) for j in jobs), out
    scene.write_text(original)  # the two-core run below computes what run `a` did
    b = tmp_path / "two_cores"
    p = snake(b, 2, items=items, start_new_session=False)
    start = time.monotonic()
    while not list(b.rglob("shard-*.nc")) and time.monotonic() - start < 300:
        assert p.poll() is None, p.communicate()[0][-2000:]
        time.sleep(0.2)
    p.send_signal(signal.SIGINT)
    p.communicate(timeout=300)
    run(b, 2, items=items)  # resumed by the default profile alone (rerun-incomplete)
    assert_identical(data_vars(a), data_vars(b))


def test_the_figure_table_is_checked_against_the_registry(tmp_path, monkeypatch):
    # a scratch copy of the pipeline, whose figure table disagrees with the registry one way at a
    # time: the Snakefile fails before any job, naming the table and the entry
    copy, table, good = pipeline_copy(tmp_path)
    entry = "  plot: regime_map\n  inputs: {sweep:"
    assert entry in good
    known = ", ".join(sorted(figure_registry.FIGURES))
    for broken, message in (
        (
            good.replace(entry, "  plot: nope\n  inputs: {sweep:"),
            f"regime_map.plot: unknown figure 'nope' (bouncedisk.figures.drawing.FIGURES: {known})",
        ),
        (
            good.replace(entry, "  plot: regime_map\n  inputs: {swep:"),
            "regime_map.inputs: 'regime_map' takes ['sweep'], the table gives ['swep']",
        ),
        (
            good.replace("  params: {labels: poincare}\n", ""),
            "poincare_maps.params: 'poincare' takes ['labels'], the table gives []",
        ),
    ):
        table.write_text(broken)
        out = parse_error(SMALL, tmp_path / "r", monkeypatch, cwd=copy)
        assert f"figures.yaml: {message}" in out, out[-2000:]
    assert not (tmp_path / "r").exists()


def test_an_edited_package_reruns_the_fit():
    """The fit starts beside ``compile_engine``, not after its flag: its own inputs name every
    source file of the package, so that an edited package reruns it as it reruns the others."""
    out = subprocess.run(
        ["snakemake", "--filegraph", "results/fit/prototype.nc", "--forceall"],
        cwd=ROOT, capture_output=True, text=True, timeout=300, check=True,
    ).stdout  # fmt: skip
    sources = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "src/bouncedisk").rglob("*.py"))
    assert "fit_prototype" in out and "compile_engine" not in out
    assert [s for s in sources if s not in out] == []


def test_snakemake_reads_the_default_profile_by_itself(tmp_path):
    """profiles/default (resume an interrupted run) is Snakemake's workflow profile only next to
    the Snakefile: one folder down, under workflow, it was never read."""
    out = run(tmp_path / "res", 1, "--dry-run")
    assert "Using workflow specific profile profiles/default" in out, out[:500]
    profile = yaml.safe_load((ROOT / "profiles" / "default" / "config.yaml").read_text())
    assert profile["rerun-incomplete"] is True


def test_numbers_written_as_text_are_numbers_where_the_schema_wants_one():
    """``1e-9`` is text to YAML 1.1 (Snakemake's reader) and ``--config`` gives nested values as
    text: where the schema asks for a number they are read as one, as in a scene file; text that
    is no number, or a fraction where a whole number is wanted, stays a schema error."""
    from bouncedisk.io.schema_check import numbers_from_text, schema_error

    schema = ROOT / "workflow" / "schemas" / "config.schema.yaml"
    cfg = yaml.safe_load(SMALL.read_text())
    assert isinstance(yaml.safe_load("x: 1e-9")["x"], str)  # the reason
    cfg["bands"].update(e_sigma="1e-9", members="8")
    numbers_from_text(cfg, schema)
    assert cfg["bands"]["e_sigma"] == 1e-9 and cfg["bands"]["members"] == 8
    assert schema_error(cfg, schema) is None
    cfg["bands"]["e_sigma"] = "nan"  # a number the schema's bounds would not see: still text
    numbers_from_text(cfg, schema)
    assert schema_error(cfg, schema) == "bands.e_sigma: 'nan' is not of type 'number'"
    cfg["bands"]["e_sigma"] = 1e-9
    for value, wrong in (("x", "'x' is not of type 'integer'"), ("8.5", "'8.5' is not of type")):
        cfg["bands"]["members"] = value
        numbers_from_text(cfg, schema)
        line = schema_error(cfg, schema)
        assert line.startswith("bands.members: ") and wrong in line, line
