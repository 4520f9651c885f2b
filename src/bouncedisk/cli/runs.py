"""``bouncedisk runs [list | show RUN | diff A B | ui]``: the tracked runs."""

from __future__ import annotations

import argparse

from ..model.errors import InputError

# --- experiment tracking (bouncedisk.tracking; `runs` reads it back through bouncedisk.tracking.reading)

RUNS_ACTIONS = {"list": (0, 0), "show": (1, 1), "diff": (0, 2), "ui": (0, 0)}  # (min, max) ids


def _cmd_runs(args: argparse.Namespace) -> int:
    import json

    from ..tracking import reading as registry

    words = list(args.words)
    if len(words) == 1 and words[0] not in RUNS_ACTIONS:  # `runs frobnicate`: not a run id
        known = ", ".join(RUNS_ACTIONS)
        raise InputError("runs", words[0], f"unknown action (known: {known})")
    action = words.pop(0) if words and words[0] in RUNS_ACTIONS else "list"
    lo, hi = RUNS_ACTIONS[action]
    if not lo <= len(words) <= hi:
        need = {"show": "one run id", "diff": "at most two run ids"}.get(action, "no run id")
        extra = " ".join(words[hi:]) or "(none)"
        raise InputError("runs", action, f"takes {need}; got {extra!r}")
    if action != "ui" and (args.port is not None or args.no_browser):
        raise InputError("runs", action, "--port and --no-browser are options of `runs ui`")
    if action == "ui":
        return _runs_ui(args)
    runs = registry.Runs(args.tracking_uri, args.results, args.experiment)
    if action == "list":
        rows = [registry.row(runs, r) for r in runs.runs]
        print(json.dumps(rows, indent=1) if args.json else registry.format_list(rows))
        if not rows and runs.others and not args.json:
            print(f"(experiment {runs.store.experiment!r}; this store also has "
                  f"{', '.join(map(repr, runs.others))}: give --experiment NAME)")  # fmt: skip
        return 0
    if action == "show":
        rec = registry.show(runs, runs.find(words[0]))
        print(json.dumps(rec, indent=1, default=str) if args.json else registry.format_show(rec))
        return 0
    if len(words) == 2:
        ra, rb = runs.find(words[0]), runs.find(words[1])
    else:
        pipelines = [r for r in runs.runs if r.data.tags.get("bouncedisk.kind") == "pipeline"]
        rb = runs.find(words[0]) if words else (pipelines or runs.runs or [None])[-1]
        ra = runs.previous(rb) if rb is not None else None
        if ra is None:
            raise InputError(
                f"tracking store {runs.store.uri}", "runs diff", "no earlier run to compare with"
            )
    d = registry.diff(runs, ra, rb)
    print(json.dumps(d, indent=1, default=str) if args.json else registry.format_diff(d))
    return 0


def _runs_ui(args: argparse.Namespace) -> int:
    """``bouncedisk runs ui``: MLflow's UI on the store, until Ctrl-C (docs/user_guide/tracking.md)."""
    from ..tracking import reading as registry
    from ..tracking import store as tracking_store
    from ..tracking import ui

    store = tracking_store.resolve_store(args.tracking_uri, args.results, args.experiment)
    if store.is_http:
        raise InputError(
            f"tracking store {store.uri}", "runs ui", "a tracking server serves its own UI: open it"
        )
    runs = registry.Runs(args.tracking_uri, args.results, args.experiment)  # readable store
    exp = tracking_store.experiment_id(runs.client, runs.store, create=False)
    if exp is None:
        raise InputError(
            f"tracking store {store.uri}",
            "runs ui",
            f"no {store.experiment!r} experiment yet: run the pipeline or a command with --track",
        )

    def announce(url: str) -> None:
        print(f"MLflow UI on {store.uri}: the runs at", flush=True)
        print(f"  {url}", flush=True)
        print("(Ctrl-C stops it)", flush=True)

    try:
        ui.serve(runs.store, exp, args.port, not args.no_browser, announce)
    except KeyboardInterrupt:
        pass
    print("MLflow UI stopped", flush=True)
    return 0


def _port(text: str) -> int:
    """A TCP port number for ``--port``."""
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a port number: {text!r}") from None
    if not 1 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"a port is 1-65535, got {port}")
    return port


def _add_runs(sub) -> None:
    """``bouncedisk runs [list | show RUN | diff A B | ui]`` (docs/formats.md "Experiment
    tracking")."""
    p = sub.add_parser(
        "runs",
        help="the tracked runs: list, show RUN, diff A B, ui (MLflow's UI on them)",
        usage="bouncedisk runs [list | show RUN | diff [A [B]] | ui [--port N] [--no-browser]] "
        "[--json] [--tracking-uri URI] [--experiment NAME]",
    )
    p.add_argument("words", nargs="*", metavar="ACTION RUN", help="list | show RUN | diff A B | ui")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument(
        "--port", type=_port, help="runs ui: serve on this port of 127.0.0.1 (default: a free one)"
    )
    p.add_argument(
        "--no-browser", action="store_true", help="runs ui: print the address, open no browser"
    )
    p.add_argument(
        "--tracking-uri",
        metavar="URI",
        help="tracking store (default: $MLFLOW_TRACKING_URI, else sqlite:///RESULTS/mlflow.db)",
    )
    p.add_argument("--results", default="results", help="results folder (default: %(default)s)")
    p.add_argument(
        "--experiment",
        metavar="NAME",
        help="the MLflow experiment (default: bouncedisk; the pipeline's tracking.experiment)",
    )
    p.set_defaults(func=_cmd_runs)
