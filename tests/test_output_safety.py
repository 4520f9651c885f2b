"""Outputs are whole or absent: interrupts, full disks, standard output on a full disk,
symbolic links, devices, stale temporaries of killed runs and FIFOs.
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import netCDF4
import pytest
from cli_checks import ENV, QUICK_STATS, S6, SMALL, leftovers, write_scene

from bouncedisk.cli import main
from bouncedisk.io import atomic


# ------------------------------------------------------------------------------ interrupts stop
def _kill_self_during(monkeypatch, module, name: str, sig=signal.SIGINT) -> None:
    """Send ``sig`` to this process as ``module.name`` runs (then let it finish)."""
    orig = getattr(module, name)

    def wrapped(*a, **k):
        os.kill(os.getpid(), sig)
        return orig(*a, **k)

    monkeypatch.setattr(module, name, wrapped)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_interrupt_while_writing_stats_leaves_no_output(tmp_path, capsys, monkeypatch, sig):
    from bouncedisk.io import netcdf as datasets

    out = tmp_path / "s.nc"
    _kill_self_during(monkeypatch, datasets, "finalize", sig)  # inside write_dataset
    assert main(["stats", S6, *QUICK_STATS, "--json", "-q", "-o", str(out)]) == 130
    cap = capsys.readouterr()
    assert cap.out == ""  # no JSON
    assert "interrupted; no output written" in cap.err
    assert not leftovers(tmp_path, "s.nc")


def test_interrupt_after_the_members_leaves_no_output(tmp_path, capsys, monkeypatch):
    from bouncedisk.analysis import statistics as stats

    out = tmp_path / "s.nc"
    _kill_self_during(monkeypatch, stats, "to_dataset")  # the members are done
    assert main(["stats", S6, *QUICK_STATS, "--json", "-q", "-o", str(out)]) == 130
    assert capsys.readouterr().out == ""
    assert not leftovers(tmp_path, "s.nc")


def test_interrupt_while_printing_removes_the_output(tmp_path, capsys, monkeypatch):
    from bouncedisk.analysis import statistics as stats

    out = tmp_path / "s.nc"
    _kill_self_during(monkeypatch, stats.EnsembleStats, "summary")  # after the rename
    assert main(["stats", S6, *QUICK_STATS, "--json", "-q", "-o", str(out)]) == 130
    assert not leftovers(tmp_path, "s.nc")


def test_interrupt_while_simulating_leaves_no_output(tmp_path, capsys, monkeypatch):
    from bouncedisk.io import netcdf as datasets

    out = tmp_path / "out.nc"
    _kill_self_during(monkeypatch, datasets.SimulationWriter, "set_attrs", signal.SIGTERM)
    assert main(["simulate", write_scene(tmp_path), "-o", str(out), "-q"]) == 130
    assert not leftovers(tmp_path, "out.nc")


# ----------------------------------------------------------------------------------- full disks
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
def test_disk_full_is_one_line_naming_the_file(full_folder, tmp_path, command):
    folder, mounted = full_folder
    out = folder / ("x.md" if command == "check" else "x.nc")
    if command == "simulate":
        argv = ["simulate", write_scene(tmp_path, BIG), "-o", str(out), "-q"]
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
    assert not leftovers(folder, out.name)


def test_write_error_names_the_output(tmp_path):
    err = atomic.write_error(tmp_path / "x.nc", RuntimeError("NetCDF: HDF error"))
    assert err.filename == str(tmp_path / "x.nc") and "HDF error" in err.strerror
    assert atomic.write_error(tmp_path / "x.nc", RuntimeError("engine")) is None


# -------------------------------------------------------------------------- nothing left behind
@pytest.mark.parametrize("command", ["stats", "simulate"])
def test_stdout_on_a_full_disk_leaves_no_output(tmp_path, command):
    out = tmp_path / "x.nc"
    if command == "stats":
        argv = ["stats", S6, *QUICK_STATS, "--json", "-q", "-o", str(out)]
    else:
        argv = ["simulate", write_scene(tmp_path), "-o", str(out)]
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
    assert not leftovers(tmp_path, "x.nc")


# ------------------------------------------------------------------------------- symbolic links
def test_symlink_output_is_written_through(tmp_path, capsys):
    scene = write_scene(tmp_path)
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
def test_device_or_process_file_is_refused(tmp_path, capsys, name):
    if name == "link":
        name = str(tmp_path / "l.nc")
        Path(name).symlink_to("/proc/self/fd/1")
    stdout = tmp_path / "stdout.txt"
    code = f"import sys; from bouncedisk.cli import main; sys.exit(main(['simulate', {write_scene(tmp_path)!r}, '-o', {name!r}, '-q']))"
    with open(stdout, "w") as fh:  # stdout a regular file: /proc/self/fd/1 leads to it
        r = subprocess.run(
            [sys.executable, "-c", code], stdout=fh, stderr=subprocess.PIPE, text=True, env=ENV
        )
    assert r.returncode == 2 and "is a device or process file" in r.stderr
    assert stdout.stat().st_size == 0
    if name.endswith("l.nc"):
        assert Path(name).is_symlink()


# ---------------------------------------------------------------------------- stale temporaries
def test_temporary_of_a_killed_run_is_removed_by_the_next(tmp_path):
    out = tmp_path / "big.nc"
    long = SMALL.replace("{impacts: 50}", "{impacts: 5000000}")
    scene = write_scene(tmp_path, long.replace(", trajectory: {dt: 0.05}", ""))
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
    assert main(["simulate", write_scene(tmp_path), "-o", str(out), "-q"]) == 0
    assert out.is_file()
    assert not any(t.exists() for t in tmps)
    assert live.exists() and other.exists()


# ---------------------------------------------------------------------------------------- FIFOs
@pytest.mark.parametrize("command", ["info", "simulate"])
def test_fifo_input_is_refused_at_once(tmp_path, command):
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
        + ("bouncedisk netCDF file" if command == "info" else "scene file")
    )
