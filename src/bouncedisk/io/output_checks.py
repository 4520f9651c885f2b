"""Output files before they are written: a usable path, and a size within the disk limit.

Every command that writes a file calls :func:`check_output_path` before doing any work, so a
mistyped ``-o`` (a folder, the input itself, a read-only place) costs one line and exit 2, not a
traceback after a long run. :func:`check_output_size` refuses a simulation whose output would
exceed the disk limit (``--max-output``, or the ``BOUNCEDISK_MAX_OUTPUT`` environment variable,
default :data:`DEFAULT_MAX_OUTPUT`) before it runs; the writer also stops a run that crosses the
limit anyway (a time stop with an unknown number of impacts).
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import tempfile
from collections.abc import Iterable
from pathlib import Path

from ..model.errors import InputError
from .atomic import temporary_name_bytes

#: Default limit on the size of one simulation file (uncompressed bytes of its variables).
DEFAULT_MAX_OUTPUT = 4 * 1024**3
ENV_MAX_OUTPUT = "BOUNCEDISK_MAX_OUTPUT"
_UNITS = {"": 1, "b": 1, "k": 1024, "m": 1024**2, "g": 1024**3, "t": 1024**4}
_SIZE_RE = re.compile(r"^\s*([0-9.eE+_-]+)\s*([kKmMgGtT]?)(?:i?[bB])?\s*$")

#: Bytes per row of each dimension of a simulation file (see :mod:`bouncedisk.io.netcdf`).
EVENT_BYTES = 4 * 8 + 1 + 8  # t_impact, phase, v_rel, u_impact, kind, period_index
EVENT_TORSION_BYTES = 2 * 8  # omega_before, omega_after
SAMPLE_BYTES = 4 * 8  # time, u_rotor, v_rotor, u_stator
SAMPLE_TORSION_BYTES = 8  # omega_rotor
STROBE_BYTES = 4 * 8  # period, strobe_t, strobe_u, strobe_v
STROBE_TORSION_BYTES = 8  # strobe_omega


def parse_size(text: str, source: str = "--max-output") -> int:
    """Bytes from ``4G``, ``500M``, ``1.5e9``, ``2GiB`` or ``123456`` (binary multiples)."""
    m = _SIZE_RE.match(str(text))
    try:
        value = float(m.group(1)) if m else math.nan
    except ValueError:
        value = math.nan
    if not m or not math.isfinite(value) or value <= 0:
        raise InputError(source, "", f"expected a size such as 4G, 500M or 1e9 bytes, got {text!r}")
    return int(value * _UNITS[m.group(2).lower()])


def default_max_output() -> int:
    """The disk limit: ``BOUNCEDISK_MAX_OUTPUT`` if set, else :data:`DEFAULT_MAX_OUTPUT`."""
    env = os.environ.get(ENV_MAX_OUTPUT)
    return parse_size(env, ENV_MAX_OUTPUT) if env else DEFAULT_MAX_OUTPUT


def human(n: float) -> str:
    """``1.2 GiB`` style text for a byte count (binary multiples, as :func:`parse_size`)."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if abs(n) < 1024 or unit == "TiB":
            return f"{int(n)} B" if unit == "B" else f"{n:.3g} {unit}"
        n /= 1024.0
    return f"{n:.3g} TiB"  # pragma: no cover


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def check_output_path(
    path: str | Path, option: str = "-o", inputs: Iterable[str | Path] = ()
) -> Path:
    """Validate an output file path before any work is done.

    Refuses a folder, one of the command's input files, and a place where no file can be
    created (read-only folder or file system, a file in the way of the folder). Parent folders
    that do not exist yet are allowed (they are created on writing) when they can be created.

    Raises
    ------
    InputError
        One line naming the path and the option.
    """
    if str(path).strip() == "":
        raise InputError("<arguments>", option, "is empty; give a file name such as out.nc")
    try:
        return _checked_output(Path(path), str(path), option, inputs)
    except OSError as ex:  # what the system says of the path (a folder's name too long)
        reason = ex.strerror or type(ex).__name__
        raise InputError(str(path), option, f"cannot be written: {reason}") from None
    except RuntimeError:  # pathlib's resolve() on a loop of symbolic links
        raise InputError(str(path), option, "cannot be written: a loop of symbolic links") from None


def _checked_output(out: Path, src: str, option: str, inputs: Iterable[str | Path]) -> Path:
    """:func:`check_output_path` after the empty name; an ``OSError`` is the caller's to word."""
    if out.is_dir():
        raise InputError(src, option, "is a directory; give a file name such as out.nc")
    for inp in inputs:
        if _same_file(out, Path(inp)) or out.resolve() == Path(inp).resolve():
            raise InputError(
                src, option, f"is the input file {str(inp)!r}; writing there would overwrite it"
            )
    _check_not_special(out, src, option)
    if out.exists() and not out.is_file():
        raise InputError(src, option, "exists and is not a regular file")
    # a symbolic link is written through: its target's folder must accept the file
    dest = Path(os.path.realpath(out)) if out.is_symlink() else out
    if out.is_symlink() and not dest.parent.is_dir():  # no folders made at a link's whim
        raise InputError(
            src,
            option,
            f"is a symbolic link to {str(dest)!r}, whose folder does not exist; create it or "
            "give another file name",
        )
    # the nearest folder that exists must accept a new file (this also catches read-only file
    # systems and root-owned folders, which os.access misjudges for root)
    parent = dest.parent
    while not parent.exists():
        if parent == parent.parent:
            break
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(src, option, f"{str(parent)!r} is a file, not a folder")
    _check_name_lengths(dest, parent, src, option)
    try:
        fd, probe = tempfile.mkstemp(prefix=".bouncedisk-", suffix=".probe", dir=parent)
    except OSError as ex:
        reason = ex.strerror or type(ex).__name__
        raise InputError(
            src, option, f"cannot create a file in {str(parent)!r}: {reason}"
        ) from None
    os.close(fd)
    with contextlib.suppress(OSError):
        os.unlink(probe)
    return out


def _check_name_lengths(dest: Path, parent: Path, src: str, option: str) -> None:
    """The folders to create below ``parent`` and the temporary name the file is written under
    (:func:`~.atomic.temporary_name_bytes`) within the file system's longest name, before any
    work: the system says so only once the folder exists and the run is done."""
    try:
        longest = os.pathconf(parent, "PC_NAME_MAX")
    except (OSError, ValueError):  # a file system that states no limit
        return
    if longest <= 0:
        return
    for part in dest.relative_to(parent).parts[:-1]:
        if len(os.fsencode(part)) > longest:
            raise InputError(
                src, option, f"cannot be written: a folder name of more than {longest} bytes"
            )
    # the writers of netCDF and CSV files name their temporaries with their format's suffix
    temporary = max(temporary_name_bytes(dest, s) for s in (None, ".nc", ".csv"))
    if temporary > longest:
        name = len(os.fsencode(dest.name))
        extra = temporary - name
        raise InputError(
            src,
            option,
            f"cannot be written: its name is {name} bytes, at most {longest - extra} here (the "
            f"file is written under a name {extra} bytes longer first, and renamed)",
        )


def sidecar_of(path: str | Path, option: str = "") -> Path:
    """The YAML sidecar of a data file (same name, suffix ``.yaml``), for reading or for
    refusing it as an output.

    Raises
    ------
    InputError
        One line naming the path and ``option`` when the path is a folder or has no file name
        (``.``, ``/``, ``..``), instead of pathlib's ``ValueError``.
    """
    p = Path(path)
    if str(path).strip() == "" or p.name in ("", ".", "..") or p.is_dir():
        raise InputError(str(path), option, "is a directory, not a data file such as curve.csv")
    return p.with_suffix(".yaml")


#: Folders of devices and process files: never an output (``/dev/stdout``, ``/proc/self/fd/1``).
SPECIAL_FOLDERS = (Path("/dev"), Path("/proc"))


def _link_chain(path: Path, hops: int = 40) -> list[Path]:
    """``path`` and every path its symbolic links lead through, absolute, in order."""
    chain = [Path(os.path.abspath(path))]
    while len(chain) <= hops and chain[-1].is_symlink():
        nxt = Path(os.readlink(chain[-1]))
        chain.append(Path(os.path.abspath(chain[-1].parent / nxt)))
    chain.append(Path(os.path.realpath(path)))
    return chain


def _check_not_special(out: Path, src: str, option: str) -> None:
    """Refuse a device or process file, given directly or through a symbolic link."""
    for p in _link_chain(out):
        if any(p == d or d in p.parents for d in SPECIAL_FOLDERS):
            raise InputError(
                src,
                option,
                f"is a device or process file ({p}); outputs are written atomically to a "
                "regular file: give a file name such as out.nc",
            )


class OutputTooLarge(InputError):
    """A run's output would exceed the disk limit."""


def too_large(path: str | Path, size: float, limit: int, what: str) -> OutputTooLarge:
    """The one-line error for an output over the limit."""
    return OutputTooLarge(
        str(path),
        "outputs",
        f"{what} would write about {human(size)}, over the limit of {human(limit)}; "
        f"ask for less (a larger outputs.trajectory.dt, fewer impacts, a shorter stop) or raise "
        f"the limit with --max-output or {ENV_MAX_OUTPUT}",
    )


def file_row_bytes(torsion: bool, physical: bool) -> tuple[int, int, int]:
    """Bytes per event, trajectory sample and stroboscopic sample of a simulation file.

    ``physical`` files add ``t_impact_s`` and ``time_s`` (8 bytes each).
    """
    ev = EVENT_BYTES + (EVENT_TORSION_BYTES if torsion else 0) + (8 if physical else 0)
    tr = SAMPLE_BYTES + (SAMPLE_TORSION_BYTES if torsion else 0) + (8 if physical else 0)
    sb = STROBE_BYTES + (STROBE_TORSION_BYTES if torsion else 0)
    return ev, tr, sb


def row_bytes(scene) -> tuple[int, int, int]:
    """Bytes per event, per trajectory sample and per stroboscopic sample of a scene's file."""
    ev, tr, sb = file_row_bytes(scene.has("torsion"), scene.physical is not None)
    return (ev if scene.outputs.events else 0), tr, sb


def _samples(t0: float, t1: float, dt: float) -> float:
    return math.floor((t1 - t0) / dt) + 1.0 if t1 >= t0 else 0.0


def check_output_size(scene, path: str | Path, limit: int) -> float:
    """Refuse, before it runs, a scene whose file would exceed ``limit`` bytes.

    Events count ``stop.impacts`` rows; trajectory and stroboscopic samples follow from the
    time span. When a scene samples over an impact stop, the span is not known in advance: an
    events-only run of the engine (no samples, a fraction of the cost) finds it, and stops as
    soon as the span alone would exceed the limit. Returns the estimate in bytes (a time stop's
    events are not counted: the writer enforces the limit on them while the run streams).

    Raises
    ------
    OutputTooLarge
        One line with the estimate, the limit and how to change either.
    """
    from ..engine import EngineConfig, iterate
    from ..engine.driver import Returning
    from ..model.engine_config import engine_config

    ev_b, tr_b, sb_b = row_bytes(scene)
    size = 0.0
    if scene.stop.impacts is not None:
        size += float(scene.stop.impacts) * ev_b
    if size > limit:
        raise too_large(path, size, limit, f"{scene.stop.impacts} events")
    traj = scene.outputs.trajectory
    strobe = scene.outputs.stroboscopic
    if traj is None and not strobe:
        return size
    w = scene.params.omega_s
    t0 = scene.initial.t
    tr0 = traj.t_start if traj and traj.t_start is not None else t0
    t_end = scene.stop.time
    if traj is not None and traj.t_stop is not None and not strobe:
        t_end = traj.t_stop if t_end is None else min(t_end, traj.t_stop)

    def sampled(t1: float) -> float:
        n = 0.0
        if traj is not None:
            hi = t1 if traj.t_stop is None else min(t1, traj.t_stop)
            n += _samples(tr0, hi, traj.dt) * tr_b
        if strobe:
            n += max(0.0, (t1 - t0) * w / (2.0 * math.pi) + 1.0) * sb_b
        return n

    if t_end is not None:
        total = size + sampled(t_end)
        if total > limit:
            raise too_large(path, total, limit, "the trajectory and stroboscopic samples")
        return total
    # impact stop: find when the run ends with an events-only run, stopping early if too large
    cfg = engine_config(scene)
    cfg = EngineConfig(**{**cfg.__dict__, "traj_dt": 0.0, "stroboscopic": False})
    t_now = t0
    chunks = Returning(iterate(cfg, scene.initial))
    try:
        for chunk in chunks:
            t_now = chunk.t_now
            if size + sampled(t_now) > limit:
                break
        else:
            t_now = float(chunks.value[1]["t"])
    except Exception:  # the real run reports engine failures with their context
        return size
    total = size + sampled(t_now)
    if total > limit:
        raise too_large(path, total, limit, "the trajectory and stroboscopic samples")
    return total
