"""``bouncedisk runs ui``: MLflow's UI on the project's store, opened on the pipeline's runs.

MLflow 3's UI has two layouts, chosen in the browser, not by the server: the GenAI one (an
"Overview" of traces, empty here) and the machine-learning one (the runs table). The page's
``workflowType`` query parameter chooses for that page; otherwise the choice saved in the
browser's local storage (key :data:`LAYOUT_KEY`) does, and a browser that never chose gets the
GenAI layout, also on a run's page. The experiment's ``mlflow.experimentKind`` tag does not
decide it. So the server started here serves, besides MLflow's own routes, one page
(:data:`LANDING`) that saves the machine-learning choice for its address and goes on to the
experiment's runs table: every later page of that server, in that browser, opens in the same
layout.

The server is MLflow's own application (uvicorn on the FastAPI wrapper of its Flask app, as
``mlflow server`` runs it) in this process, bound to 127.0.0.1 only.
"""

from __future__ import annotations

import asyncio
import inspect
import json
import os
import signal
import socket
import sys
import threading
import warnings
import webbrowser
from collections.abc import Callable

from . import store as tracking_store

HOST = "127.0.0.1"
#: The browser's saved layout choice: MLflow's ``useLocalStorage`` key ``mlflow.workflowType``,
#: version 1 (``<key>_v<version>``), a JSON string.
LAYOUT_KEY = "mlflow.workflowType_v1"
LAYOUT = "machine_learning"
#: The page that saves :data:`LAYOUT` and goes on to the runs table.
LANDING = "/bouncedisk/runs"
#: The signals that stop the server.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def runs_table_path(experiment_id: str) -> str:
    """The address (after the host) of an experiment's runs table in the machine-learning
    layout."""
    return f"/#/experiments/{experiment_id}/runs?workflowType={LAYOUT}"


def landing_page(experiment_id: str) -> str:
    """The HTML of :data:`LANDING`: save the layout, then replace itself by the runs table."""
    target = json.dumps(runs_table_path(experiment_id))
    value = json.dumps(json.dumps(LAYOUT))
    return (
        "<!doctype html><html><head><meta charset='utf-8'><title>bouncedisk runs</title>"
        f"<script>try {{ localStorage.setItem({json.dumps(LAYOUT_KEY)}, {value}); }} "
        f"catch (e) {{}} location.replace({target});</script></head>"
        f"<body><a href={target}>bouncedisk runs</a></body></html>"
    )


def bind(port: int | None) -> socket.socket:
    """A listening socket on 127.0.0.1: ``port``, or a free one (``None``).

    Raises
    ------
    TrackingError
        The port is taken or not allowed.
    """
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        sock.bind((HOST, port or 0))
    except OSError as ex:
        sock.close()
        raise tracking_store.TrackingError(
            f"{HOST}:{port}", f"cannot listen: {ex.strerror or ex}"
        ) from None
    sock.listen(128)
    return sock


def _server_environment(store: tracking_store.Store) -> None:
    """MLflow's server settings for ``store`` (what ``mlflow server`` passes its workers)."""
    from mlflow.server import constants as c

    os.environ[c.BACKEND_STORE_URI_ENV_VAR] = store.uri
    if store.artifact_location:
        os.environ[c.ARTIFACT_ROOT_ENV_VAR] = store.artifact_location
        os.environ[c.ARTIFACTS_DESTINATION_ENV_VAR] = store.artifact_location
        os.environ[c.SERVE_ARTIFACTS_ENV_VAR] = "true"
    os.environ.setdefault("MLFLOW_SERVER_ENABLE_JOB_EXECUTION", "false")  # no job workers


def application(store: tracking_store.Store, experiment_id: str):
    """MLflow's server application on ``store``, with :data:`LANDING` added."""
    os.environ.setdefault("MLFLOW_DISABLE_TELEMETRY", "true")
    os.environ.setdefault("DO_NOT_TRACK", "true")
    _server_environment(store)
    with warnings.catch_warnings():  # MLflow's own deprecation notices are not the user's
        warnings.simplefilter("ignore")
        from mlflow.server import app as flask_app
        from mlflow.server.fastapi_app import app

    page = landing_page(experiment_id)
    if LANDING not in {r.rule for r in flask_app.url_map.iter_rules()}:
        flask_app.add_url_rule(
            LANDING, "bouncedisk_runs", lambda: (page, 200, {"Content-Type": "text/html"})
        )
    return app


def has_display() -> bool:
    """Whether a browser can be shown: always on macOS and Windows, with X or Wayland on
    other systems."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def serve(
    store: tracking_store.Store,
    experiment_id: str,
    port: int | None = None,
    open_browser: bool = True,
    announce: Callable[[str], None] = print,
) -> None:
    """Serve MLflow's UI on ``store`` at 127.0.0.1 until Ctrl-C (or SIGTERM).

    ``announce`` gets the address of :data:`LANDING` (the runs table, in the machine-learning
    layout) once the socket listens; the address is opened in a browser when ``open_browser``
    and a display exists (never an error without one).
    """
    import logging

    import uvicorn

    sock = bind(port)
    app = application(store, experiment_id)
    for name in ("mlflow", "alembic", "sqlalchemy", "uvicorn.error"):
        logging.getLogger(name).setLevel(logging.WARNING)
    url = f"http://{HOST}:{sock.getsockname()[1]}{LANDING}"
    config = uvicorn.Config(app, log_level="warning", access_log=False, lifespan="on")
    server = uvicorn.Server(config)
    # from here a Ctrl-C or SIGTERM only asks the server to stop (uvicorn checks the request
    # once started, and takes the signals over while it serves): no exception can land inside
    # the construction of the event loop or of the serving task
    stop = {}
    if threading.current_thread() is threading.main_thread():  # signals are the main thread's
        for sig in STOP_SIGNALS:
            stop[sig] = signal.getsignal(sig)
            signal.signal(sig, lambda *_: setattr(server, "should_exit", True))
    serving = server.serve(sockets=[sock])
    try:
        announce(url)
        if open_browser and has_display():
            try:
                webbrowser.open(url)
            except Exception:  # noqa: BLE001 - no usable browser: the address is printed
                pass
        asyncio.run(serving)
    finally:
        if inspect.getcoroutinestate(serving) == inspect.CORO_CREATED:
            serving.close()  # never started (asyncio.run refused, e.g. inside a running loop)
        sock.close()
        for sig, handler in stop.items():
            if handler is not None:  # None: a handler not set from Python, left as it is
                signal.signal(sig, handler)
