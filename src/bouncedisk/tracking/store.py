"""The tracking store: where it is, whether it can be used (cheap, no mlflow import), the MLflow
client, locks and batches.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import re
import sqlite3
import tempfile
import time
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

from ..model.errors import InputError, error_line

ENV_URI = "MLFLOW_TRACKING_URI"
DB_NAME = "mlflow.db"
ARTIFACTS_NAME = "mlartifacts"
EXPERIMENT = "bouncedisk"
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
#: ``MLFLOW_HTTP_REQUEST_*`` variables; the environment wins). With MLflow's own defaults (120 s,
#: 7 retries with doubling backoff) a stalled server holds a command for tens of minutes.
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
            + ", ".join(f"{s}://" for s in SCHEMES if s != "file"),
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
            raise TrackingError(store.uri, f"cannot be used: {one_line(ex)}") from None


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
        raise TrackingError(uri, f"not a usable SQLite database: {one_line(ex)}") from None
    except OSError as ex:
        what = "not writable" if create else "not readable"
        raise TrackingError(uri, f"{what}: {ex.strerror or one_line(ex)}") from None


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
        raise TrackingError(uri, f"unreachable: {one_line(reason)}") from None


_AUTOFLUSH = re.compile(r"^\(raised as a result of Query-invoked autoflush;[^)]*\)\s*")


def one_line(ex: object) -> str:
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
    # no progress bars on stderr when `bouncedisk runs` reads a run's artifacts
    os.environ.setdefault("MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR", "false")
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


#: Experiment tags that make MLflow 3's UI open the experiment on its runs table (the
#: machine-learning view), not on the GenAI overview of traces this project never writes.
EXPERIMENT_TAGS = {"mlflow.experimentKind": "custom_model_development"}


def experiment_id(client, store: Store, create: bool = True) -> str | None:
    """Id of the store's experiment (created, with its artifact location and
    :data:`EXPERIMENT_TAGS`, when missing; the tags added to an older experiment that lacks them
    when ``create``)."""
    exp = client.get_experiment_by_name(store.experiment)
    if exp is not None:
        if create:
            for key, value in EXPERIMENT_TAGS.items():
                if exp.tags.get(key) != value:
                    client.set_experiment_tag(exp.experiment_id, key, value)
        return exp.experiment_id
    if not create:
        return None
    try:
        return client.create_experiment(
            store.experiment, artifact_location=store.artifact_location, tags=EXPERIMENT_TAGS
        )
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


def error_report(ex: BaseException) -> str:
    """The one-line report of a tracking error (``bouncedisk: error: ...``), which the
    Snakefile's handlers print."""
    line = ex.line() if isinstance(ex, InputError) else one_line(ex)
    return error_line(line)
