"""Writing runs: the provenance tags every run carries, and a tracked command's one top-level
run."""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import socket
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from .. import __version__
from ..io.atomic import pid_alive
from ..io.provenance import TAG_GIT_COMMIT, TAG_GIT_DIRTY, TAG_VERSION, git_state, sha256_file
from .extraction import _keys, _netcdf_run_id, _number, describe_output, flatten
from .store import Store, _client, _log_batch, experiment_id, store_lock

ENV_TRACK = "BOUNCEDISK_TRACK"  # "1": simulate/fit/stats track without --track

# tags (``bouncedisk.*``) read back by :mod:`bouncedisk.tracking.reading`
TAG_KIND = "bouncedisk.kind"  # pipeline | simulate | fit | stats | simulation | sweep | ...
TAG_HOST = "bouncedisk.host"
TAG_PID = "bouncedisk.pid"
TAG_PSTART = "bouncedisk.process_start"
TAG_RUN_ID = "bouncedisk.run_id"  # the netCDF ``run_id`` of a tracked command's output
TAG_STATE = "bouncedisk.end_reason"
COPIED = {".png", ".pdf", ".svg", ".md", ".csv", ".json", ".txt", ".html", ".yaml", ".tsv"}


# ------------------------------------------------------------------------------------------
# Provenance of the invocation
# ------------------------------------------------------------------------------------------


def _process_start(pid: int) -> str:
    """Start time of a process in clock ticks since boot (Linux), to tell a reused pid apart."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
        return stat.rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return ""


def process_alive(pid: int, start: str = "") -> bool:
    """Whether process ``pid`` (started at ``start``, if known) still runs on this host."""
    if not pid_alive(pid):
        return False
    return not start or not _process_start(pid) or _process_start(pid) == start


def provenance_tags(kind: str, cwd: Path | None = None) -> dict[str, str]:
    """Tags every tracked run carries: kind, code and tool versions, host and process."""
    g = git_state(cwd)
    tags = {
        TAG_KIND: kind,
        TAG_VERSION: __version__,
        TAG_GIT_COMMIT: g["git_commit"],
        TAG_GIT_DIRTY: g["git_dirty"],
        "python_version": platform.python_version(),
        TAG_HOST: socket.gethostname(),
        TAG_PID: str(os.getpid()),
        TAG_PSTART: _process_start(os.getpid()),
        "mlflow.user": os.environ.get("USER", "") or "unknown",
    }
    if g["git_commit"] != "unknown":
        tags["mlflow.source.git.commit"] = g["git_commit"]
    return tags


# ------------------------------------------------------------------------------------------
# Commands (simulate, fit, stats): one top-level run each
# ------------------------------------------------------------------------------------------


def tracking_wanted(flag: bool | None) -> bool:
    """``--track``/``--no-track`` if given, else ``BOUNCEDISK_TRACK=1`` in the environment."""
    if flag is not None:
        return flag
    return os.environ.get(ENV_TRACK, "").strip().lower() in ("1", "true", "yes", "on")


def log_command_run(
    kind: str,
    store: Store,
    outputs: Iterable[str | Path] = (),
    params: Mapping[str, Any] | None = None,
    metrics: Mapping[str, float] | None = None,
    command: str = "",
    wall_time_s: float | None = None,
    copy_netcdf: bool = False,
) -> str:
    """Record a finished command as one top-level run; returns the MLflow run id.

    ``outputs``: files it wrote (netCDF params and metrics, JSON metrics, figures copied);
    ``params``/``metrics``: anything else (e.g. ``numeric_leaves(stats_result)``).
    """
    all_params: dict[str, str] = {}
    all_metrics: dict[str, float] = {}
    manifest: dict[str, dict] = {}
    run_tag = ""
    for f in map(Path, outputs):
        if not f.is_file():
            continue
        p, m = describe_output(f)
        all_params.update(p)
        all_metrics.update(m)
        manifest[str(f)] = {"sha256": sha256_file(f), "bytes": f.stat().st_size}
        if f.suffix == ".nc" and not run_tag:
            run_tag = _netcdf_run_id(f)
    all_params.update(flatten(params or {}))
    all_metrics.update({k: float(v) for k, v in (metrics or {}).items() if _number(v) is not None})
    if wall_time_s is not None:
        all_metrics["command.wall_time_s"] = float(wall_time_s)
    tags = provenance_tags(kind)
    tags["mlflow.source.name"] = f"bouncedisk {kind}"
    if command:
        tags["bouncedisk.command"] = command[:5000]
    if run_tag:
        tags[TAG_RUN_ID] = run_tag
    name = run_tag or f"{kind}-{_dt.datetime.now(_dt.UTC):%Y%m%dT%H%M%S}"
    with store_lock(store):
        client = _client(store)
        exp = experiment_id(client, store)
        run = client.create_run(exp, tags=tags, run_name=name)
        rid = run.info.run_id
        try:
            _log_batch(client, rid, _keys(all_params), _keys(all_metrics))
            with tempfile.TemporaryDirectory() as tmp:
                mf = Path(tmp) / "outputs.json"
                mf.write_text(json.dumps(manifest, indent=1, sort_keys=True))
                client.log_artifact(rid, str(mf))
            for f in map(Path, outputs):
                if f.is_file() and (f.suffix in COPIED or (copy_netcdf and f.suffix == ".nc")):
                    client.log_artifact(rid, str(f), "outputs")
        except BaseException:
            client.set_terminated(rid, "FAILED")
            raise
        client.set_terminated(rid, "FINISHED")
    return rid
