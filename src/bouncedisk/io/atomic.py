"""Atomic file writes: a file appears complete under its final name, or not at all.

- The temporary lives beside the output (``.NAME.HOST-PID.XXXXXXXX.tmp.SFX``), so the rename is
  atomic; a temporary left by a killed process (SIGKILL, power loss) is removed by the next
  write of the same output on the same host once its process is gone.
- ``-o`` naming a symbolic link writes through to the link's target (as ``cp`` and shells do);
  the link itself stays.
- A write that fails (disk full, quota, I/O error, a netCDF library's ``HDF error``) becomes one
  ``OSError`` naming the output file, not the temporary.
- While a command runs under :func:`recording_outputs` (the ``bouncedisk`` command does), every
  output renamed into place is remembered, so that a later failure or interrupt (stdout on a
  full disk, Ctrl-C while printing) removes it again: nothing is left behind on any error.
- :func:`stop_checks` lets a caller veto the rename (a pending SIGINT/SIGTERM, see
  :func:`bouncedisk.run.runner.deferred_interrupts`): an interrupt before the rename leaves no
  output.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import shutil
import socket
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

#: Free bytes below which a failed write is reported as a full disk.
NEARLY_FULL = 1 << 20

#: Checks run just before every rename; each may raise (``KeyboardInterrupt``) to veto it.
_STOP_CHECKS: list[Callable[[], None]] = []
#: Outputs renamed into place during :func:`recording_outputs` (None: not recording).
_COMMITTED: list[Path] | None = None


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9]", "_", socket.gethostname())[:40] or "host"


def pid_alive(pid: int) -> bool:
    """Whether a process ``pid`` runs on this host (another user's included)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's live process
        return True
    return True


def clean_stale_temporaries(target: Path) -> list[Path]:
    """Remove temporaries of ``target`` left by dead processes of this host; return them.

    Only files named as :func:`atomic_path` names them, whose host is this one and whose process
    no longer exists, are removed (a live writer's temporary, or another host's on a shared
    file system, is left alone).
    """
    pattern = re.compile(rf"^\.{re.escape(target.name)}\.(?P<host>[A-Za-z0-9_]+)-(?P<pid>\d+)\.")
    host = _host()
    removed = []
    with contextlib.suppress(OSError):
        for entry in os.scandir(target.parent):
            m = pattern.match(entry.name)
            if not m or ".tmp" not in entry.name[m.end() :] or m["host"] != host:
                continue
            if int(m["pid"]) == os.getpid() or pid_alive(int(m["pid"])):
                continue
            with contextlib.suppress(OSError):
                os.unlink(entry.path)
                removed.append(Path(entry.path))
    return removed


def write_error(target: Path, ex: BaseException) -> OSError | None:
    """The one-line ``OSError`` naming ``target`` for a failed write, or None if not a write error.

    netCDF/HDF5 report a full disk as ``RuntimeError: NetCDF: HDF error``: when the folder has
    (almost) no free space left, that is what it was.
    """
    if isinstance(ex, OSError):
        code = ex.errno or errno.EIO
        reason = ex.strerror or str(ex) or type(ex).__name__
    elif isinstance(ex, RuntimeError) and ("NetCDF" in str(ex) or "HDF" in str(ex)):
        code, reason = errno.EIO, " ".join(str(ex).split())
    else:
        return None
    try:
        free = shutil.disk_usage(target.parent).free
    except OSError:
        free = None
    if free is not None and free < NEARLY_FULL and code != errno.EROFS:
        code, reason = errno.ENOSPC, os.strerror(errno.ENOSPC)
    return OSError(code, f"cannot write: {reason}", str(target))


def write_target(path: str | Path) -> Path:
    """Where writing ``path`` goes: the final target of a symbolic link, else ``path`` itself."""
    p = Path(path)
    return Path(os.path.realpath(p)) if p.is_symlink() else p


def temporary_affixes(target: Path, suffix: str | None = None) -> tuple[str, str]:
    """The prefix and suffix of the temporary name :func:`atomic_path` writes ``target`` under
    (``tempfile`` puts 8 random characters between them): hidden, beside ``target``, naming
    the host and the process (:func:`clean_stale_temporaries` reads them)."""
    sfx = suffix if suffix is not None else "".join(target.suffixes[-1:])
    return f".{target.name}.{_host()}-{os.getpid()}.", f".tmp{sfx}"


def temporary_name_bytes(target: Path, suffix: str | None = None) -> int:
    """Length in bytes of the temporary name :func:`atomic_path` gives ``target`` (with
    ``suffix``, as :func:`atomic_path` takes it)."""
    prefix, end = temporary_affixes(target, suffix)
    return len(os.fsencode(prefix)) + 8 + len(os.fsencode(end))


@contextlib.contextmanager
def atomic_path(path: str | Path, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it over ``path`` only on success.

    The temporary file lives in the same directory (so the rename is atomic on POSIX) and is
    removed if the block raises, including on ``KeyboardInterrupt``. A symbolic link is written
    through (its target is replaced, the link kept). Before the rename every
    :func:`stop_checks` check runs; a write error raises ``OSError`` naming ``path``.
    """
    target = write_target(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    clean_stale_temporaries(target)
    prefix, end = temporary_affixes(target, suffix)
    try:
        fd, tmp = tempfile.mkstemp(prefix=prefix, suffix=end, dir=target.parent)
    except OSError as ex:
        raise write_error(target, ex) from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        try:
            yield tmp_path
        except (OSError, RuntimeError) as ex:
            err = write_error(target, ex)
            if err is None:
                raise
            raise err from None
        for check in list(_STOP_CHECKS):
            check()
        # mkstemp makes private files; give the result the usual permissions (umask applied)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp_path, 0o666 & ~umask)
        os.replace(tmp_path, target)
        if _COMMITTED is not None:
            _COMMITTED.append(target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


@contextlib.contextmanager
def stop_checks(check: Callable[[], None]) -> Iterator[None]:
    """During the block, run ``check()`` before every rename (it raises to veto the output)."""
    _STOP_CHECKS.append(check)
    try:
        yield
    finally:
        _STOP_CHECKS.remove(check)


@contextlib.contextmanager
def recording_outputs() -> Iterator[list[Path]]:
    """Remember the outputs renamed into place during the block; yield their list.

    The caller removes them with :func:`remove_outputs` when the command fails afterwards, or
    calls :func:`keep_outputs` once they are final (e.g. before recording them elsewhere).
    """
    global _COMMITTED
    old, _COMMITTED = _COMMITTED, []
    try:
        yield _COMMITTED
    finally:
        _COMMITTED = old


def keep_outputs() -> list[Path]:
    """Declare the outputs written so far final (no longer removed on a later error)."""
    if _COMMITTED is None:
        return []
    kept = list(_COMMITTED)
    _COMMITTED.clear()
    return kept


def remove_outputs() -> list[Path]:
    """Remove the outputs written so far during :func:`recording_outputs`; return them."""
    if _COMMITTED is None:
        return []
    gone = []
    for p in _COMMITTED:
        with contextlib.suppress(FileNotFoundError):
            p.unlink()
            gone.append(p)
    _COMMITTED.clear()
    return gone
