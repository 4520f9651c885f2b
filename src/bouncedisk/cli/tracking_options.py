"""``--track`` / ``--tracking-uri``: a command's work recorded in the tracking store."""

from __future__ import annotations

import argparse
import sys

from .common import command_line, flush_stdout


def _add_track_options(p: argparse.ArgumentParser) -> None:
    """``--track`` / ``--tracking-uri`` for a command whose work can be recorded."""
    p.add_argument(
        "--track",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="record this run in the MLflow tracking store (default: on if BOUNCEDISK_TRACK=1)",
    )
    p.add_argument(
        "--tracking-uri",
        metavar="URI",
        help="tracking store (default: $MLFLOW_TRACKING_URI, else sqlite:///results/mlflow.db)",
    )


def _tracking_store(args: argparse.Namespace):
    """Before the work: the store to record into when tracking is wanted, else None.

    Raises InputError (exit 2, one line naming the URI) when the store cannot be used, so that
    nothing is computed for a record that cannot be written.
    """
    from ..tracking import store as tracking_store
    from ..tracking import writing

    if not writing.tracking_wanted(getattr(args, "track", None)):
        return None
    store = tracking_store.resolve_store(getattr(args, "tracking_uri", None))
    tracking_store.preflight(store)
    return store


def _track(args, store, kind: str, outputs=(), params=None, metrics=None) -> None:
    """After the work: record it as one run (no-op when ``store`` is None)."""
    if store is None:
        return
    from ..io.atomic import keep_outputs
    from ..tracking import store as tracking_store
    from ..tracking import writing

    command = command_line(args)
    flush_stdout()  # the command's own output is complete before its outputs become final
    kept = keep_outputs()
    try:
        run_id = writing.log_command_run(
            kind, store, outputs, params=params, metrics=metrics, command=command
        )
    except KeyboardInterrupt as ex:
        ex.kept_outputs = kept
        raise
    except Exception as ex:  # noqa: BLE001 - drivers and REST raise their own types
        reason = tracking_store.one_line(ex)
        raise tracking_store.TrackingError(
            store.uri, f"recording failed (the outputs were written): {reason}"
        ) from None
    if not getattr(args, "quiet", False):
        print(f"bouncedisk: recorded run {run_id} in {store.uri}", file=sys.stderr)
