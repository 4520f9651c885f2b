"""``bouncedisk runs [list | show RUN | diff A B]``: the tracked runs."""

from __future__ import annotations

import argparse
import sys

from ..model.errors import InputError
from .common import EXIT_USER

# --- experiment tracking (bouncedisk.tracking; `runs` reads it back through bouncedisk.tracking.reading)

RUNS_ACTIONS = {"list": (0, 0), "show": (1, 1), "diff": (0, 2)}  # action: (min, max) run ids


def _cmd_runs(args: argparse.Namespace) -> int:
    import json

    from ..tracking import reading as registry

    words = list(args.words)
    action = words.pop(0) if words and words[0] in RUNS_ACTIONS else "list"
    lo, hi = RUNS_ACTIONS[action]
    if not lo <= len(words) <= hi:
        need = {"list": "no run id", "show": "one run id", "diff": "at most two run ids"}[action]
        extra = " ".join(words[hi:]) or "(none)"
        raise InputError("runs", action, f"takes {need}; got {extra!r}")
    runs = registry.Runs(args.tracking_uri, args.results)
    if action == "list":
        rows = [registry.row(runs, r) for r in runs.runs]
        print(json.dumps(rows, indent=1) if args.json else registry.format_list(rows))
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


def _one_line_error(prefix: str):
    """An argparse ``error`` that prints one line and exits 2 (no usage block)."""

    def error(message: str):
        print(f"bouncedisk: error: {prefix}: {message}", file=sys.stderr)
        sys.exit(EXIT_USER)

    return error


def _add_runs(sub) -> None:
    """``bouncedisk runs [list | show RUN | diff A B]`` (docs/formats.md "Experiment tracking")."""
    p = sub.add_parser(
        "runs",
        help="the tracked runs: list, show RUN, diff A B",
        usage="bouncedisk runs [list | show RUN | diff [A [B]]] [--json] [--tracking-uri URI]",
    )
    p.add_argument("words", nargs="*", metavar="ACTION RUN", help="list | show RUN | diff A B")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument(
        "--tracking-uri",
        metavar="URI",
        help="tracking store (default: $MLFLOW_TRACKING_URI, else sqlite:///RESULTS/mlflow.db)",
    )
    p.add_argument("--results", default="results", help="results folder (default: %(default)s)")
    p.error = _one_line_error("runs")
    p.set_defaults(func=_cmd_runs)
