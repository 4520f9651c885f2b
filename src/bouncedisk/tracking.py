"""Experiment tracking on MLflow: what every pipeline invocation and tracked command did.

Writing side (reading and comparing runs is :mod:`bouncedisk.registry`).

- A pipeline invocation that does work gets one *parent* run, created RUNNING when Snakemake
  starts its jobs (:meth:`PipelineTracker.start`) and ended FINISHED (:meth:`PipelineTracker.finish`),
  FAILED or KILLED (:meth:`PipelineTracker.fail`). Every job that ran gets a *nested* run.
  Everything is logged once, from the main Snakemake process, from the jobs' outputs, logs and
  benchmark files: the jobs themselves never import mlflow (seconds each) nor touch the store.
- ``bouncedisk simulate|fit|stats --track`` log one top-level run of their own
  (:func:`preflight` before the work, :func:`log_command_run` after it).

What is recorded is extracted generically (:func:`describe_output`), so new outputs are picked
up without code changes: params from the string and input-like global attributes of netCDF
files; metrics from their numeric global attributes, scalar variables (and the numeric
attributes of those, e.g. ``ci_low``), numeric leaves of JSON files, numeric columns of
Snakemake benchmark files, and the rows of a Markdown checks table (``reproduction.md``).

The store is ``sqlite:///<results>/mlflow.db`` with artifacts in ``<results>/mlartifacts/``
unless ``tracking.uri`` (pipeline config) or ``MLFLOW_TRACKING_URI`` names another one. Nothing
here reaches the network except the tracking server a user configures (MLflow's telemetry is
switched off before mlflow is imported).
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime as _dt
import hashlib
import json
import math
import os
import platform
import re
import socket
import sqlite3
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

from . import __version__
from .errors import InputError
from .provenance import TAG_GIT_COMMIT, TAG_GIT_DIRTY, TAG_VERSION

ENV_URI = "MLFLOW_TRACKING_URI"
ENV_TRACK = "BOUNCEDISK_TRACK"  # "1": simulate/fit/stats track without --track
DB_NAME = "mlflow.db"
ARTIFACTS_NAME = "mlartifacts"
EXPERIMENT = "bouncedisk"
HASH_CACHE = ".tracking-hashes.json"

# tags (``bouncedisk.*``) read back by :mod:`bouncedisk.registry`
TAG_KIND = "bouncedisk.kind"  # pipeline | simulate | fit | stats | simulation | sweep | ...
TAG_HOST = "bouncedisk.host"
TAG_PID = "bouncedisk.pid"
TAG_PSTART = "bouncedisk.process_start"
TAG_RUN_ID = "bouncedisk.run_id"  # the netCDF ``run_id`` of a tracked command's output
TAG_STATE = "bouncedisk.end_reason"
PIPELINE = "pipeline"

# global attributes that change on every run without meaning anything (never params)
VOLATILE_ATTRS = {
    "created",
    "date_created",
    "date_modified",
    "history",
    "Conventions",
    "title",
    "source",
    "references",
    # ACDD metadata: dates of this writing, the id (the run id), who made it (not inputs)
    "date_issued",
    "date_metadata_modified",
    "id",
    "naming_authority",
    "processing_level",
    "product_version",
    "standard_name_vocabulary",
    "summary",
    "keywords",
    "creator_name",
    "creator_email",
    "creator_url",
    "creator_type",
    "creator_institution",
    "institution",
    "project",
    "license",
    "acknowledgement",
    "publisher_name",
    "publisher_email",
    "publisher_url",
    "publisher_type",
    "publisher_institution",
}
# numeric global attributes that are inputs (params), not results (metrics)
PARAM_ATTRS = {
    "e",
    "omega_s",
    "r_phi",
    "psi",
    "gamma",
    "tol",
    "step",
    "inertia_ratio",
    "mu_ratio",
    "e_sigma",
    "seed",
    "members",
    "discard",
    "duration",
    "bootstrap",
    "n_bootstrap",
    "scan_points",
    "zoom_points",
    "tail",
    "shard",
    "n_shards",
    "transient_events",
    "max_events",
    "base_samples",
    "total_points",
}
PARAM_PREFIXES = ("initial_", "physical_", "ensemble_", "stop_")
# what a nested run's kind is, from its rule's name (figures first, then the first prefix that
# matches); others are "job"
KINDS = (
    ("simulate", "simulation"),
    ("sweep", "sweep"),
    ("stats", "statistics"),
    ("ensemble", "statistics"),
    ("fit", "fit"),
    ("check", "check"),
    ("reproduction", "check"),
    ("compile", "build"),
    ("poincare", "study"),
    ("clipped", "study"),
    ("work_precision", "study"),
    ("scaling", "study"),
    ("sensitivity", "study"),
    ("synthetic", "data"),
)
COPIED = {".png", ".pdf", ".svg", ".md", ".csv", ".json", ".txt", ".html", ".yaml", ".tsv"}
MAX_PARAM = 500  # characters of a param value kept (MLflow allows 6000)
#: Schemes of tracking URIs (SQLAlchemy dialects may add ``+driver``); ``file:`` stores are
#: refused by :func:`preflight`, others (``databricks``, ``nonsense``) here.
SCHEMES = ("sqlite", "http", "https", "postgresql", "mysql", "mssql", "file")
SQLITE_SUFFIXES = (".db", ".sqlite", ".sqlite3")
#: Tables every MLflow SQL store has (MLflow 2 and 3): a SQLite file without ``alembic_version``
#: is not a store; one missing another of them is damaged (MLflow would re-create the table with
#: an old schema, i.e. migrate it).
MLFLOW_TABLES = {
    "alembic_version",
    "experiments",
    "experiment_tags",
    "runs",
    "tags",
    "params",
    "metrics",
    "latest_metrics",
}
#: Seconds one request to a tracking server may take, retries, and backoff factor (MLflow's
#: ``MLFLOW_HTTP_REQUEST_*`` variables; the environment wins). MLflow's own defaults are 120 s
#: and 7 retries with doubling backoff: a stalled server held a command for tens of minutes.
HTTP_TIMEOUT_S = 10
HTTP_RETRIES = 1
HTTP_BACKOFF = 1
#: Seconds a writer waits for another writer's lock on a SQLite store.
LOCK_TIMEOUT_S = 300.0


class TrackingError(InputError):
    """The tracking store cannot be used: one line naming its URI (exit status 2)."""

    def __init__(self, uri: str, message: str):
        super().__init__(f"tracking store {uri}", "", message)


# ------------------------------------------------------------------------------------------
# The store: where it is, and whether it can be used (cheap: no mlflow import)
# ------------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Store:
    """A tracking store: its URI, the artifact location of new experiments, the experiment."""

    uri: str
    artifact_location: str | None = None
    experiment: str = EXPERIMENT

    @property
    def sqlite_path(self) -> Path | None:
        """The database file of a ``sqlite:///`` URI (None for other stores)."""
        if not self.uri.startswith("sqlite:///"):
            return None
        path = urllib.parse.urlsplit(self.uri).path  # "/rel" or "//abs"
        return Path(path[1:]) if path.startswith("/") else Path(path)

    @property
    def is_http(self) -> bool:
        return self.uri.startswith(("http://", "https://"))


def resolve_store(
    uri: str | None = None, results: str | Path = "results", experiment: str | None = None
) -> Store:
    """The store to use: ``uri`` if given, else ``MLFLOW_TRACKING_URI``, else the local default.

    The default is ``sqlite:///<results>/mlflow.db`` with artifacts in ``<results>/mlartifacts``;
    any other SQLite file keeps its artifacts in ``mlartifacts/`` beside it; a server or database
    store decides for itself.
    """
    uri = (uri or os.environ.get(ENV_URI) or "").strip()
    if not uri:
        uri = f"sqlite:///{Path(results).resolve() / DB_NAME}"
    elif "://" not in uri:  # a plain path: a SQLite file (a bare word is a mistyped URI)
        if not (uri.endswith(SQLITE_SUFFIXES) or Path(uri).is_file()):
            raise TrackingError(
                uri,
                "not a tracking URI: give sqlite:///PATH.db, a PATH.db file, http(s)://HOST:PORT "
                "or a database URI (postgresql://...)",
            )
        uri = f"sqlite:///{Path(uri).resolve()}"
    scheme = uri.partition("://")[0].lower().partition("+")[0]
    if scheme not in SCHEMES:
        raise TrackingError(
            uri,
            f"unknown scheme {scheme + '://'!r}; use one of "
            + ", ".join(f"{s}://" for s in SCHEMES),
        )
    store = Store(uri, None, experiment or EXPERIMENT)
    db = store.sqlite_path
    if db is not None:
        art = (db.resolve().parent / ARTIFACTS_NAME).as_uri()
        store = dataclasses.replace(store, artifact_location=art)
    return store


def preflight(store: Store, create: bool = True, timeout: float = 10.0) -> None:
    """Fail early, naming the URI, when the store cannot be used.

    ``create=True`` (writers): a SQLite store must be creatable or writable; a server must
    answer. ``create=False`` (readers): the store must already exist. Raises
    :class:`TrackingError`.
    """
    db = store.sqlite_path
    if db is not None:
        _preflight_sqlite(store.uri, db, create)
    elif store.is_http:
        _preflight_http(store.uri, timeout)
    elif store.uri.startswith("file:") or "://" not in store.uri:
        raise TrackingError(
            store.uri, "file stores are not supported; use sqlite:///PATH or a server"
        )
    else:  # a database or another scheme: ask MLflow itself (costs its import)
        try:
            _client(store).search_experiments(max_results=1)
        except Exception as ex:  # noqa: BLE001 - every driver raises its own types
            raise TrackingError(store.uri, f"cannot be used: {_one_line(ex)}") from None


def _preflight_sqlite(uri: str, db: Path, create: bool) -> None:
    if not create and not db.exists():
        raise TrackingError(
            uri, "no tracking store here (run the pipeline, or give --tracking-uri)"
        )
    if db.exists() and db.is_dir():
        raise TrackingError(uri, "is a directory, not a SQLite file")
    if create and not db.parent.exists() and not db.parent.parent.is_dir():
        # the store's own folder may be created (results/), not a chain of folders
        raise TrackingError(uri, f"folder {str(db.parent.parent)!r} does not exist")
    try:
        if create:
            db.parent.mkdir(parents=True, exist_ok=True)
            fd, probe = tempfile.mkstemp(prefix=".write-probe.", dir=db.parent)
            os.close(fd)
            os.unlink(probe)
        if db.exists():
            con = sqlite3.connect(
                f"file:{db}?mode={'rw' if create else 'ro'}", uri=True, timeout=30
            )
            try:
                tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master")}
                missing = ", ".join(sorted(MLFLOW_TABLES - tables))
                if tables and "alembic_version" not in tables:
                    raise TrackingError(
                        uri,
                        "is a SQLite database but not an MLflow tracking store (no MLflow "
                        "tables); it is left untouched",
                    )
                if tables and missing:
                    raise TrackingError(
                        uri, f"damaged MLflow tracking store: missing table(s) {missing}"
                    )
                if not create and not tables:
                    raise TrackingError(
                        uri, "is empty, not an MLflow tracking store (reading never creates one)"
                    )
                if create:
                    con.execute("BEGIN IMMEDIATE")
                    con.rollback()
            finally:
                con.close()
    except sqlite3.Error as ex:
        raise TrackingError(uri, f"not a usable SQLite database: {_one_line(ex)}") from None
    except OSError as ex:
        what = "not writable" if create else "not readable"
        raise TrackingError(uri, f"{what}: {ex.strerror or _one_line(ex)}") from None


def _http_request(uri: str, path: str, timeout: float, body: dict | None = None) -> Any:
    url = uri.rstrip("/") + path
    data = json.dumps(body).encode() if body is not None else None
    req = urllib.request.Request(url, data=data, method="POST" if data else "GET")
    req.add_header("Content-Type", "application/json")
    token = os.environ.get("MLFLOW_TRACKING_TOKEN")
    user, pw = (
        os.environ.get("MLFLOW_TRACKING_USERNAME"),
        os.environ.get("MLFLOW_TRACKING_PASSWORD"),
    )
    if token:
        req.add_header("Authorization", f"Bearer {token}")
    elif user and pw:
        import base64

        req.add_header(
            "Authorization", "Basic " + base64.b64encode(f"{user}:{pw}".encode()).decode()
        )
    with urllib.request.urlopen(req, timeout=timeout) as r:  # noqa: S310 - the user's server
        return json.loads(r.read() or b"{}")


def _preflight_http(uri: str, timeout: float) -> None:
    try:
        _http_request(uri, "/api/2.0/mlflow/experiments/search?max_results=1", timeout)
    except urllib.error.HTTPError as ex:
        what = "not authorized" if ex.code in (401, 403) else "not an MLflow tracking server"
        raise TrackingError(uri, f"{what} (HTTP {ex.code})") from None
    except (urllib.error.URLError, OSError, ValueError) as ex:
        reason = getattr(ex, "reason", ex)
        raise TrackingError(uri, f"unreachable: {_one_line(reason)}") from None


_AUTOFLUSH = re.compile(r"^\(raised as a result of Query-invoked autoflush;[^)]*\)\s*")


def _one_line(ex: object) -> str:
    """The first meaningful line of an error (SQLAlchemy's autoflush preamble dropped)."""
    text = _AUTOFLUSH.sub("", str(ex).strip())
    return (text.splitlines()[0] if text else type(ex).__name__)[:200]


# ------------------------------------------------------------------------------------------
# MLflow itself (imported lazily: it costs seconds)
# ------------------------------------------------------------------------------------------


def _client(store: Store):
    """An MlflowClient on ``store``: no telemetry, no INFO chatter from MLflow's migrations."""
    os.environ.setdefault("MLFLOW_DISABLE_TELEMETRY", "true")
    os.environ.setdefault("DO_NOT_TRACK", "true")
    # every request to a server has a bounded time (read by MLflow at each request)
    os.environ.setdefault("MLFLOW_HTTP_REQUEST_TIMEOUT", str(HTTP_TIMEOUT_S))
    os.environ.setdefault("MLFLOW_HTTP_REQUEST_MAX_RETRIES", str(HTTP_RETRIES))
    os.environ.setdefault("MLFLOW_HTTP_REQUEST_BACKOFF_FACTOR", str(HTTP_BACKOFF))
    import logging

    from mlflow.tracking import MlflowClient  # configures its loggers: quiet them after

    # MLflow logs its failures with tracebacks (tens of lines) before raising them; the caller
    # reports the exception in one line
    for name in ("mlflow", "alembic", "sqlalchemy", "urllib3"):
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)
    return MlflowClient(tracking_uri=store.uri)


@contextlib.contextmanager
def store_lock(store: Store) -> Iterator[None]:
    """Serialize writers of one SQLite store across processes (creation, migrations, batches)."""
    db = store.sqlite_path
    if db is None:
        yield
        return
    import fcntl

    db.parent.mkdir(parents=True, exist_ok=True)
    with open(db.parent / f".{db.name}.lock", "a") as fh:
        deadline = time.monotonic() + LOCK_TIMEOUT_S
        while True:
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise TrackingError(
                        store.uri, f"locked by another writer for over {LOCK_TIMEOUT_S:g} s"
                    ) from None
                time.sleep(0.05)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def experiment_id(client, store: Store, create: bool = True) -> str | None:
    """Id of the store's experiment (created, with its artifact location, when missing)."""
    exp = client.get_experiment_by_name(store.experiment)
    if exp is not None:
        return exp.experiment_id
    if not create:
        return None
    try:
        return client.create_experiment(store.experiment, artifact_location=store.artifact_location)
    except Exception:  # noqa: BLE001 - another writer created it first
        exp = client.get_experiment_by_name(store.experiment)
        if exp is None:
            raise
        return exp.experiment_id


def _log_batch(
    client,
    run_id: str,
    params: Mapping[str, str],
    metrics: Mapping[str, float],
    tags: Mapping[str, str] | None = None,
) -> None:
    """Log params/metrics/tags in batches within MLflow's limits (100 params, 1000 total)."""
    from mlflow.entities import Metric, Param, RunTag

    now = int(time.time() * 1000)
    ps = [Param(k, v) for k, v in params.items()]
    ms = [Metric(k, float(v), now, 0) for k, v in metrics.items()]
    ts = [RunTag(k, v) for k, v in (tags or {}).items()]
    while ps or ms or ts:
        p, ps = ps[:100], ps[100:]
        t, ts = ts[:100], ts[100:]
        m, ms = ms[: 1000 - len(p) - len(t)], ms[1000 - len(p) - len(t) :]
        client.log_batch(run_id, metrics=m, params=p, tags=t)


# ------------------------------------------------------------------------------------------
# Generic extraction from output files
# ------------------------------------------------------------------------------------------


def _number(v: Any) -> float | None:
    """A finite float from a Python/numpy scalar (bools as 0/1), else None."""
    try:
        import numpy as np

        if isinstance(v, np.ndarray):
            if v.ndim != 0:
                return None
            v = v.item()
        if isinstance(v, np.generic):
            v = v.item()
    except ImportError:  # pragma: no cover
        pass
    if isinstance(v, bool):
        return float(v)
    if isinstance(v, int | float):
        f = float(v)
        return f if math.isfinite(f) else None
    return None


def _seq(v: Any) -> list | None:
    """A short 1-D numeric sequence (e.g. a [low, high] interval) as a list, else None."""
    try:
        import numpy as np

        if isinstance(v, np.ndarray) and v.ndim == 1:
            v = v.tolist()
    except ImportError:  # pragma: no cover
        pass
    if isinstance(v, list | tuple) and 0 < len(v) <= 10 and all(_number(x) is not None for x in v):
        return list(v)
    return None


def _seq_keys(name: str, n: int) -> list[str]:
    if n == 2 and "ci" in name.lower():
        return [f"{name}.low", f"{name}.high"]
    return [f"{name}.{i}" for i in range(n)]


def is_param_attr(name: str) -> bool:
    """Whether a numeric global attribute is an input (param) rather than a result (metric)."""
    return name in PARAM_ATTRS or name.startswith(PARAM_PREFIXES)


def _clean_key(key: str) -> str:
    """A valid MLflow key (letters, digits, ``_ - . / space``)."""
    return re.sub(r"[^A-Za-z0-9_\-./ ]", "_", key)[:250]


def _param_value(v: Any) -> str:
    if isinstance(v, float):
        text = repr(v)
    elif isinstance(v, str):
        text = v
    else:
        text = json.dumps(v, default=str, sort_keys=True)
    return text[:MAX_PARAM]


def netcdf_fields(path: Path) -> tuple[dict[str, str], dict[str, float]]:
    """Params and metrics of one netCDF file (global attributes, scalar data variables).

    Reads attributes and scalars only, with netCDF4 directly: opening through xarray costs
    tenths of a second per file, and a pipeline has dozens.
    """
    import netCDF4

    params: dict[str, str] = {}
    metrics: dict[str, float] = {}
    with netCDF4.Dataset(path, "r") as nc:
        for k in nc.ncattrs():
            if k in VOLATILE_ATTRS or "run_id" in k:
                continue
            v = nc.getncattr(k)
            num, seq = _number(v), _seq(v)
            if isinstance(v, str):
                params[k] = _param_value(v)
            elif num is not None:
                if is_param_attr(k):
                    params[k] = _param_value(num)
                else:
                    metrics[k] = num
            elif seq is not None:
                for key, x in zip(_seq_keys(k, len(seq)), seq, strict=True):
                    if is_param_attr(k):
                        params[key] = _param_value(float(x))
                    else:
                        metrics[key] = float(x)
        # scalar coordinates (named in a "coordinates" attribute) are not results
        coords = set()
        for var in nc.variables.values():
            if "coordinates" in var.ncattrs():
                coords.update(str(var.getncattr("coordinates")).split())
        for name, var in nc.variables.items():
            if var.ndim != 0 or var.dtype.kind not in "biuf" or name in coords:
                continue
            var.set_auto_maskandscale(False)
            num = _number(var[...])
            if num is not None:
                metrics[str(name)] = num
            for k in var.ncattrs():
                n = _number(var.getncattr(k))
                if n is not None and not k.startswith("_"):
                    metrics[f"{name}.{k}"] = n
    return params, metrics


def json_metrics(path: Path) -> dict[str, float]:
    """Numeric leaves of a JSON file, keys joined with dots."""
    out: dict[str, float] = {}

    def walk(prefix: str, v: Any) -> None:
        if isinstance(v, dict):
            for k, x in v.items():
                walk(f"{prefix}.{k}" if prefix else str(k), x)
        elif (seq := _seq(v)) is not None and not isinstance(v, bool):
            for key, x in zip(_seq_keys(prefix, len(seq)), seq, strict=True):
                out[key] = float(x)
        elif (n := _number(v)) is not None and prefix:
            out[prefix] = n

    try:
        walk("", json.loads(path.read_text(encoding="utf-8")))
    except (ValueError, UnicodeDecodeError):
        return {}
    return out


_NUM = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _slug(text: str, n: int = 60) -> str:
    s = re.sub(r"[^a-z0-9]+", "_", text.lower()).strip("_")
    return s[:n].rstrip("_") or "check"


def checks_metrics(path: Path) -> dict[str, float]:
    """Rows of a Markdown checks table (``| claim | measured | … | result |``) as metrics.

    Each check gives ``check.<claim>.passed`` (1/0) and ``check.<claim>.measured`` (the first
    number of the measured text, if any); the table gives ``checks.passed|failed|total``.
    """
    out: dict[str, float] = {}
    header: list[str] | None = None
    passed = total = 0
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return {}
    for line in lines:
        if not line.strip().startswith("|"):
            header = None if not line.strip() else header
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            header = [c.lower() for c in cells]
            continue
        if set("".join(cells)) <= set("-: "):
            continue
        if "claim" not in header or "result" not in header or len(cells) != len(header):
            continue
        row = dict(zip(header, cells, strict=True))
        ok = "pass" in row["result"].lower() and "fail" not in row["result"].lower()
        slug = _slug(row["claim"])
        key, i = slug, 2
        while f"check.{key}.passed" in out:
            key, i = f"{slug}_{i}", i + 1
        out[f"check.{key}.passed"] = float(ok)
        m = _NUM.search(row.get("measured", "").split(":", 1)[-1])
        if m:
            with contextlib.suppress(ValueError):
                out[f"check.{key}.measured"] = float(m.group())
        passed += ok
        total += 1
    if total:
        out.update(
            {"checks.passed": passed, "checks.failed": total - passed, "checks.total": total}
        )
    return out


def benchmark_metrics(path: Path) -> dict[str, float]:
    """Numeric columns of the last row of a Snakemake benchmark file (``s``, ``max_rss`` MB …)."""
    try:
        lines = [ln for ln in path.read_text(encoding="utf-8").splitlines() if ln.strip()]
    except (OSError, UnicodeDecodeError):
        return {}
    if len(lines) < 2:
        return {}
    head, last = lines[0].split("\t"), lines[-1].split("\t")
    out = {}
    for k, v in zip(head, last, strict=False):
        with contextlib.suppress(ValueError):
            f = float(v)
            if math.isfinite(f) and k != "h:m:s":
                out[f"benchmark.{k}"] = f
    return out


def describe_output(path: str | Path) -> tuple[dict[str, str], dict[str, float]]:
    """Params and metrics of any output file, by its kind (empty for figures and tables)."""
    p = Path(path)
    if not p.is_file():
        return {}, {}
    try:
        if p.suffix == ".nc":
            return netcdf_fields(p)
        if p.suffix == ".json":
            return {}, json_metrics(p)
        if p.suffix == ".md":
            return {}, checks_metrics(p)
    except Exception as ex:  # noqa: BLE001 - a damaged output must not lose the whole record
        return {"tracking_warning": f"{p.name}: {_one_line(ex)}"}, {}
    return {}, {}


def sha256_file(path: Path, block: int = 1 << 20) -> str:
    """SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while chunk := fh.read(block):
            h.update(chunk)
    return h.hexdigest()


class _HashCache:
    """sha256 of files, reused while (size, mtime) are unchanged (``<results>/.tracking-hashes.json``)."""

    def __init__(self, path: Path | None):
        self.path = path
        self.data: dict[str, list] = {}
        if path is not None and path.is_file():
            with contextlib.suppress(ValueError, OSError):
                self.data = json.loads(path.read_text())

    def get(self, f: Path) -> str:
        st = f.stat()
        key = str(f.resolve())
        hit = self.data.get(key)
        if hit and hit[0] == st.st_size and hit[1] == st.st_mtime_ns:
            return hit[2]
        digest = sha256_file(f)
        self.data[key] = [st.st_size, st.st_mtime_ns, digest]
        return digest

    def save(self) -> None:
        if self.path is None:
            return
        with contextlib.suppress(OSError):
            tmp = self.path.with_name(self.path.name + ".tmp")
            tmp.write_text(json.dumps(self.data))
            os.replace(tmp, self.path)


# ------------------------------------------------------------------------------------------
# Provenance of the invocation
# ------------------------------------------------------------------------------------------


def _git(*args: str, cwd: Path | None = None) -> str | None:
    try:
        r = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return r.stdout.strip() if r.returncode == 0 else None


def git_state(cwd: Path | None = None) -> dict[str, str]:
    """Commit of the working tree at ``cwd`` (default: the package's source tree) and whether
    tracked files differ from it."""
    cwd = cwd or Path(__file__).resolve().parent
    commit = _git("rev-parse", "HEAD", cwd=cwd)
    if commit is None:
        return {"git_commit": "unknown", "git_dirty": "unknown"}
    dirty = _git("status", "--porcelain", "--untracked-files=no", cwd=cwd)
    return {"git_commit": commit, "git_dirty": "true" if dirty else "false"}


def _process_start(pid: int) -> str:
    """Start time of a process in clock ticks since boot (Linux), to tell a reused pid apart."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
        return stat.rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return ""


def process_alive(pid: int, start: str = "") -> bool:
    """Whether process ``pid`` (started at ``start``, if known) still runs on this host."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
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


def _leaves(obj: Any, prefix: str = "") -> Iterator[tuple[str, Any]]:
    """The non-mapping values of a nested mapping, each under its dotted key."""
    if isinstance(obj, Mapping):
        for k, v in obj.items():
            yield from _leaves(v, f"{prefix}.{k}" if prefix else str(k))
    else:
        yield prefix, obj


def numeric_leaves(obj: Any, prefix: str = "") -> dict[str, float]:
    """Flatten a JSON-like result (e.g. ``bouncedisk stats --json``) into metrics."""
    out: dict[str, float] = {}
    for key, leaf in _leaves(obj, prefix):
        if not key:
            continue
        if (seq := _seq(leaf)) is not None:
            out.update(dict(zip(_seq_keys(key, len(seq)), map(float, seq), strict=True)))
        elif (n := _number(leaf)) is not None:
            out[key] = n
    return out


def flatten(obj: Any, prefix: str = "") -> dict[str, str]:
    """A nested mapping as dotted ``key: text`` params."""
    return {key: _param_value(leaf) for key, leaf in _leaves(obj, prefix)}


def config_sha256(config: Mapping) -> str:
    """Hash of a pipeline config, leaving out where results and runs are kept."""
    relevant = {k: v for k, v in config.items() if k not in ("results", "tracking")}
    return hashlib.sha256(json.dumps(relevant, sort_keys=True, default=str).encode()).hexdigest()


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


def _netcdf_run_id(path: Path) -> str:
    try:
        import netCDF4

        with netCDF4.Dataset(path, "r") as nc:
            return str(getattr(nc, "run_id", ""))
    except Exception:  # noqa: BLE001
        return ""


def _keys(d: Mapping[str, Any]) -> dict[str, Any]:
    return {_clean_key(k): v for k, v in d.items() if k}


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

    def key(self, results: Path) -> str:
        """Name of the job in the store: its first output, relative to results, sans suffix."""
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
                exp,
                start_time=int(self.t0 * 1000),
                tags=tags,
                run_name=f"pipeline-{_dt.datetime.fromtimestamp(self.t0, _dt.UTC):%Y%m%dT%H%M%SZ}",
            )
            self.run_id = run.info.run_id
            _log_batch(client, self.run_id, _keys(params), {})
        self._client, self._exp = client, exp
        import netCDF4  # noqa: F401 - warm the import that finish() needs, while the jobs run

        self.timings["tracking.open_s"] = time.perf_counter() - t
        self.timings["tracking.open_cpu_s"] = time.thread_time() - cpu

    def _wait(self) -> None:
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self._error is not None:
            err, self._error = self._error, None
            if isinstance(err, TrackingError):
                raise err
            raise TrackingError(self.store.uri, f"recording failed: {_one_line(err)}") from None

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


def print_error(ex: BaseException) -> None:
    """The one-line report of a tracking error, for the Snakefile's handlers."""
    line = ex.line() if isinstance(ex, InputError) else _one_line(ex)
    print(f"bouncedisk: error: {line}", file=sys.stderr, flush=True)
