"""Writing a pipeline invocation: one parent run, a nested run per job, stale runs marked."""

from __future__ import annotations

import contextlib
import dataclasses
import datetime as _dt
import json
import re
import socket
import tempfile
import threading
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .extraction import (
    HASH_CACHE,
    KINDS,
    _HashCache,
    _keys,
    benchmark_metrics,
    config_sha256,
    describe_output,
    flatten,
)
from .store import (
    EXPERIMENT,
    TrackingError,
    _client,
    _log_batch,
    experiment_id,
    one_line,
    preflight,
    resolve_store,
    store_lock,
)
from .writing import (
    COPIED,
    TAG_HOST,
    TAG_KIND,
    TAG_PID,
    TAG_PSTART,
    TAG_STATE,
    process_alive,
    provenance_tags,
)

PIPELINE = "pipeline"


def mark_stale_runs(client, exp_id: str) -> int:
    """End as KILLED the RUNNING runs of this host whose process is gone (e.g. SIGKILL)."""
    host = socket.gethostname()
    n = 0
    runs = client.search_runs(
        [exp_id], filter_string="attributes.status = 'RUNNING'", max_results=1000
    )
    for r in runs:
        t = r.data.tags
        if t.get(TAG_HOST) != host or not t.get(TAG_PID, "").isdigit():
            continue
        if not process_alive(int(t[TAG_PID]), t.get(TAG_PSTART, "")):
            client.set_tag(r.info.run_id, TAG_STATE, "its process ended without ending the run")
            client.set_terminated(r.info.run_id, "KILLED")
            n += 1
    return n


# ------------------------------------------------------------------------------------------
# The pipeline: one parent run per invocation that does work, a nested run per job
# ------------------------------------------------------------------------------------------


@dataclasses.dataclass
class JobRecord:
    """What the tracker needs to know of one Snakemake job (plain data: src/ never imports
    snakemake; the Snakefile builds these from its DAG)."""

    rule: str
    outputs: list[str]
    wildcards: dict[str, str] = dataclasses.field(default_factory=dict)
    params: dict[str, Any] = dataclasses.field(default_factory=dict)
    benchmark: str | None = None
    logs: list[str] = dataclasses.field(default_factory=list)
    ran: bool = True
    #: the job's name in the store where its first output does not name it: a batch of
    #: figures (rule ``figure_<batch>``, several figures in one job) is ``figures/<batch>``
    name: str | None = None

    def key(self, results: Path) -> str:
        """Name of the job in the store: :attr:`name` if set, else its first output, relative
        to results, sans suffix."""
        if self.name:
            return self.name
        if not self.outputs:
            return self.rule
        p = Path(self.outputs[0])
        with contextlib.suppress(ValueError):
            p = p.resolve().relative_to(results.resolve())
        return str(p.with_suffix("")) if p.suffix else str(p)

    @property
    def kind(self) -> str:
        figure = any(o.endswith((".png", ".pdf", ".svg")) for o in self.outputs)
        if figure or "figure" in self.rule or re.match(r"fig\d", self.rule):
            return "figure"
        for prefix, kind in KINDS:
            if self.rule.startswith(prefix):
                return kind
        return "job"


@dataclasses.dataclass
class PipelineSettings:
    """The ``tracking:`` section of the pipeline config."""

    enabled: bool = True
    uri: str | None = None
    experiment: str = EXPERIMENT
    copy_netcdf: bool = False

    @classmethod
    def from_config(cls, config: Mapping) -> PipelineSettings:
        """From ``config["tracking"]``: a mapping, or a bare ``false``/``true``."""
        t = config.get("tracking", {})
        if not isinstance(t, Mapping):
            return cls(enabled=_switch(t, True))
        return cls(
            enabled=_switch(t.get("enabled"), True),
            uri=t.get("uri") or None,
            experiment=t.get("experiment") or EXPERIMENT,
            copy_netcdf=_switch(t.get("copy_netcdf"), False),
        )


def _switch(v: Any, default: bool) -> bool:
    """A config switch: a bool, or its text as ``--config`` passes nested values."""
    if v is None:
        return default
    if isinstance(v, str):
        return v.strip().lower() in ("true", "yes", "on", "1")
    return bool(v)


class PipelineTracker:
    """Record one pipeline invocation. Call :meth:`start` before the jobs (from Snakemake's
    ``onstart``), then :meth:`finish` (``onsuccess``) or :meth:`fail` (``onerror``).

    :meth:`start` checks the store synchronously (cheap), then imports mlflow and creates the
    RUNNING parent run in a background thread while the jobs run, so that the seconds it costs
    overlap the work. A process killed outright (SIGKILL) leaves its run RUNNING: readers show it
    as KILLED once its process is gone, and the next invocation on this host ends it as KILLED.
    """

    def __init__(
        self,
        settings: PipelineSettings,
        results: str | Path,
        config: Mapping,
        cores: int | None = None,
        snakemake_version: str = "",
        command: str = "",
    ):
        self.settings = settings
        self.results = Path(results)
        self.config = dict(config)
        self.cores = cores
        self.snakemake_version = snakemake_version
        self.command = command
        self.store = resolve_store(settings.uri, self.results, settings.experiment)
        self.t0 = time.time()
        self.jobs: list[JobRecord] = []
        self.run_id: str | None = None
        self._client = None
        self._exp: str | None = None
        self._thread: threading.Thread | None = None
        self._error: BaseException | None = None
        self.interrupted = False
        # seconds spent on tracking in the main process (the open overlaps the jobs)
        self.timings: dict[str, float] = {}

    # -- start -----------------------------------------------------------------------------

    def start(self, jobs: list[JobRecord], background: bool = True) -> None:
        """Check the store (raises :class:`TrackingError`) and open the parent run."""
        t = time.perf_counter()
        preflight(self.store, create=True)
        self.jobs = jobs
        self.t0 = time.time()
        self.timings["tracking.start_s"] = time.perf_counter() - t
        if background:
            self._thread = threading.Thread(target=self._open_guarded, daemon=True)
            self._thread.start()
        else:
            self._open()

    def _open_guarded(self) -> None:
        try:
            self._open()
        except BaseException as ex:  # noqa: BLE001 - reported by finish/fail
            self._error = ex

    def _open(self) -> None:
        t, cpu = time.perf_counter(), time.thread_time()
        tags = provenance_tags(PIPELINE, Path.cwd())  # the workflow's tree: scenes, config
        tags.update(
            {
                "mlflow.source.name": "snakemake",
                "snakemake_version": self.snakemake_version,
                "cores": str(self.cores or ""),
                "bouncedisk.results": str(self.results),
                "bouncedisk.jobs_planned": str(sum(j.ran for j in self.jobs)),
            }
        )
        if self.command:
            tags["bouncedisk.command"] = self.command[:5000]
        relevant = {k: v for k, v in self.config.items() if k not in ("results", "tracking")}
        params = {f"config.{k}": v for k, v in flatten(relevant).items()}
        params["config_sha256"] = config_sha256(self.config)
        params["cores"] = str(self.cores or "")
        with store_lock(self.store):
            client = _client(self.store)
            exp = experiment_id(client, self.store)
            mark_stale_runs(client, exp)
            run = client.create_run(
                exp, start_time=int(self.t0 * 1000), tags=tags, run_name=self._run_name()
            )
            self.run_id = run.info.run_id
            _log_batch(client, self.run_id, _keys(params), {})
        self._client, self._exp = client, exp
        import netCDF4  # noqa: F401 - warm the import that finish() needs, while the jobs run

        self.timings["tracking.open_s"] = time.perf_counter() - t
        self.timings["tracking.open_cpu_s"] = time.thread_time() - cpu

    def _run_name(self) -> str:
        """The parent run's name: its start (UTC) and how many jobs it holds as nested runs, so
        that the runs table says there is something to expand (docs/user_guide/tracking.md)."""
        n = sum(j.ran for j in self.jobs)
        when = _dt.datetime.fromtimestamp(self.t0, _dt.UTC)
        return f"pipeline ({n} job{'s' if n != 1 else ''}) {when:%Y-%m-%dT%H:%M:%SZ}"

    def _wait(self) -> None:
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self._error is not None:
            err, self._error = self._error, None
            if isinstance(err, TrackingError):
                raise err
            raise TrackingError(self.store.uri, f"recording failed: {one_line(err)}") from None

    # -- end -------------------------------------------------------------------------------

    def fail(self, killed: bool = False) -> None:
        """End the parent run FAILED (a job failed) or KILLED (interrupted)."""
        self._wait()
        if self.run_id is None:
            return
        status = "KILLED" if (killed or self.interrupted) else "FAILED"
        with store_lock(self.store):
            self._client.set_tag(self.run_id, TAG_STATE, status.lower())
            self._client.log_metric(self.run_id, "pipeline.wall_time_s", time.time() - self.t0)
            self._client.set_terminated(self.run_id, status)

    def finish(self) -> str:
        """Log every job that ran as a nested run, a snapshot of all outputs on the parent run,
        and end it FINISHED. Returns the parent run id."""
        t = time.perf_counter()
        self._wait()
        assert self.run_id is not None and self._client is not None
        client, rid = self._client, self.run_id
        cache = _HashCache(self.results / HASH_CACHE if self.results.is_dir() else None)
        snap_params: dict[str, str] = {}
        snap_metrics: dict[str, float] = {}
        manifest: dict[str, dict] = {}
        summary: dict[str, float] = {}
        nested = []
        for job in self.jobs:
            key = job.key(self.results)
            params, metrics, files = self._describe_job(job, cache, manifest)
            for k, v in params.items():
                snap_params[f"{key}/{k}"] = v
            for k, v in metrics.items():
                snap_metrics[f"{key}/{k}"] = v
                if k.startswith("checks."):
                    summary[k] = summary.get(k, 0.0) + v
            if job.ran:
                nested.append((job, key, params, metrics, files))
        summary["pipeline.jobs_run"] = len(nested)
        summary["pipeline.wall_time_s"] = time.time() - self.t0
        with store_lock(self.store), tempfile.TemporaryDirectory() as tmp:
            for job, key, params, metrics, files in nested:
                self._log_nested(job, key, params, metrics, files)
            _log_batch(client, rid, _keys(snap_params), {**_keys(snap_metrics), **summary})
            mf = Path(tmp) / "outputs.json"
            mf.write_text(json.dumps(manifest, indent=1, sort_keys=True))
            client.log_artifact(rid, str(mf))
            cfg = Path(tmp) / "config.json"
            cfg.write_text(json.dumps(self.config, indent=1, sort_keys=True, default=str))
            client.log_artifact(rid, str(cfg))
            for job in self.jobs:
                for o in map(Path, job.outputs):
                    if o.suffix == ".md" and o.is_file():
                        client.log_artifact(rid, str(o))
            self.timings["tracking.finish_s"] = time.perf_counter() - t
            _log_batch(client, rid, {}, self.timings)
            client.set_terminated(rid, "FINISHED")
        cache.save()
        self.timings["tracking.finish_s"] = time.perf_counter() - t
        return rid

    def _describe_job(self, job: JobRecord, cache: _HashCache, manifest: dict):
        params: dict[str, str] = {}
        metrics: dict[str, float] = {}
        files: list[Path] = []
        ncs = [o for o in job.outputs if o.endswith(".nc")]
        for o in map(Path, job.outputs):
            if not o.is_file():
                continue
            files.append(o)
            p, m = describe_output(o)
            pre = f"{o.stem}." if (o.suffix == ".nc" and len(ncs) > 1) else ""
            params.update({pre + k: v for k, v in p.items()})
            metrics.update({pre + k: v for k, v in m.items()})
            try:
                rel = str(o.resolve().relative_to(self.results.resolve()))
            except ValueError:
                rel = str(o)
            manifest[rel] = {"sha256": cache.get(o), "bytes": o.stat().st_size, "rule": job.rule}
        if job.benchmark:
            metrics.update(benchmark_metrics(Path(job.benchmark)))
        return params, metrics, files

    def _log_nested(self, job, key, params, metrics, files) -> None:
        client = self._client
        end = max((f.stat().st_mtime for f in files), default=time.time())
        start = end - metrics.get("benchmark.s", 0.0)
        tags = {
            "mlflow.parentRunId": self.run_id,
            TAG_KIND: job.kind,
            "bouncedisk.rule": job.rule,
            "bouncedisk.job": key,
        }
        p = {f"wildcards.{k}": v for k, v in job.wildcards.items()}
        p.update({f"rule.{k}": v for k, v in flatten(job.params).items()})
        p.update(params)
        run = client.create_run(
            self._exp, start_time=int(start * 1000), tags=tags, run_name=f"{job.rule}: {key}"
        )
        _log_batch(client, run.info.run_id, _keys(p), _keys(metrics))
        for f in files:
            if f.suffix in COPIED or (self.settings.copy_netcdf and f.suffix == ".nc"):
                client.log_artifact(run.info.run_id, str(f), "outputs")
        for lg in map(Path, job.logs):
            if lg.is_file() and lg.stat().st_size < 5_000_000:
                client.log_artifact(run.info.run_id, str(lg), "logs")
        client.set_terminated(run.info.run_id, "FINISHED", end_time=int(end * 1000))
