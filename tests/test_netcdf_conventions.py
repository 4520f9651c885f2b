"""Every kind of file the project writes is CF-clean and carries ACDD attributes; string
labels are CF labels that read back as the index.
"""

import os
import socket
from pathlib import Path

import netCDF4
import numpy as np
import pytest
from cli_checks import ENV, QUICK_STATS, ROOT, S6, SCENES, SMALL

from bouncedisk.cli import main

# ---------------------------------------------------------------------------------- CF and ACDD
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
def test_every_file_kind_is_cf_clean_and_carries_acdd(every_kind, monkeypatch, kind):
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
def test_string_labels_are_cf_labels_that_read_back_as_the_index(every_kind):
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
