"""Paths the user names: a folder where a data file is due, a dangling link as an output, an
empty size."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from bouncedisk.cli import main
from bouncedisk.io.load_curves import read_load_curve
from bouncedisk.io.output_checks import check_output_path, sidecar_of
from bouncedisk.io.runup_curves import read_curve
from bouncedisk.model.errors import InputError

SCENE = "parameters: {e: 0.5, omega_s: 1.5}\nstop: {impacts: 5}\noutputs: {events: true}\n"


@pytest.mark.parametrize("path", [".", "..", "/", ""])
def test_a_folder_has_no_sidecar(path):
    """Before: ValueError "PosixPath('.') has an empty name" from pathlib."""
    with pytest.raises(InputError, match="is a directory, not a data file"):
        sidecar_of(path, "--load")


def test_sidecar_of_a_data_file():
    assert sidecar_of("a/curve.csv") == Path("a/curve.yaml")


@pytest.mark.parametrize("reader", [read_curve, read_load_curve])
def test_reading_a_folder_as_a_curve_is_one_line(reader, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputError) as ex:
        reader(".")
    assert ex.value.line() == ".: is a directory, not a data file such as curve.csv"


def test_output_through_a_dangling_link_makes_no_folders(tmp_path):
    """Before: `-o` to a dangling symlink created its target's missing parent folder."""
    target = tmp_path / "missing" / "deeper" / "out.nc"
    link = tmp_path / "link.nc"
    os.symlink(target, link)
    with pytest.raises(InputError, match="whose folder does not exist"):
        check_output_path(link)
    assert not (tmp_path / "missing").exists()
    target.parent.mkdir(parents=True)
    assert check_output_path(link) == link  # a link into an existing folder is written through


def test_an_empty_max_output_is_refused(tmp_path, capsys):
    """Before: `--max-output ""` silently used the default limit."""
    (tmp_path / "s.yaml").write_text(SCENE)
    out = tmp_path / "o.nc"
    assert main(["simulate", str(tmp_path / "s.yaml"), "-o", str(out), "--max-output", ""]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("bouncedisk: error: --max-output")
    assert not out.exists()


@pytest.mark.parametrize("name", ["x" * 300 + ".nc", "d/" + "y" * 300 + "/out.nc"])
def test_a_name_too_long_names_the_option(name, tmp_path, monkeypatch, capsys):
    """A file or folder name longer than the file system allows: the option's one line, exit 2,
    no folder made (the system's own error names no field)."""
    monkeypatch.chdir(tmp_path)
    scene = tmp_path / "s.yaml"
    scene.write_text(SCENE)
    assert main(["simulate", str(scene), "-o", name, "-q"]) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert ": -o: cannot be written: " in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.yaml"]


def test_the_longest_name_accepted_is_one_the_writer_can_use(tmp_path, monkeypatch):
    """The netCDF and CSV writers name their temporaries with their format's suffix whatever
    the output's own: the longest name without a suffix that the check accepts is one
    ``atomic_path`` can write with either."""
    from bouncedisk.io.atomic import atomic_path, temporary_name_bytes

    monkeypatch.chdir(tmp_path)
    limit = os.pathconf(tmp_path, "PC_NAME_MAX")
    extra = max(temporary_name_bytes(Path("x"), s) for s in (".nc", ".csv")) - 1
    longest = "y" * (limit - extra)
    with pytest.raises(InputError, match="at most"):
        check_output_path(longest + "y")
    assert check_output_path(longest) == Path(longest)
    for suffix in (".nc", ".csv"):
        with atomic_path(longest, suffix=suffix) as tmp:
            tmp.write_bytes(suffix.encode())
        assert Path(longest).read_bytes() == suffix.encode()
