"""The ``bouncedisk`` command (INTERFACES.md "Package and commands").

Errors a user can cause print one line ``bouncedisk: error: FILE: FIELD: what is wrong`` and exit
with status 2; nothing is written then. An interrupted run (Ctrl-C) leaves no output and exits 130.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import shlex
import signal
import sys

from . import __version__
from .errors import InputError

EXIT_USER = 2
EXIT_FAIL = 1
EXIT_INTERRUPT = 130


def _cmd_simulate(args: argparse.Namespace) -> int:
    from .outputs import check_output_path, default_max_output, parse_size
    from .runner import run_scene
    from .scene import load_scene

    out = check_output_path(args.output, "-o", inputs=[args.scene])
    limit = parse_size(args.max_output) if args.max_output else default_max_output()
    scene = load_scene(args.scene, args.set or [])
    store = _tracking_store(args)
    command = "bouncedisk " + " ".join(shlex.quote(a) for a in sys.argv[1:])
    summary = run_scene(
        scene, out, progress=not args.quiet, command=command, max_output_bytes=limit
    )
    if not args.quiet:
        print(
            f"{out}: {summary.n_impacts} impacts, {summary.n_chatter} chattering tails, "
            f"status {summary.status!r}, {summary.wall_time_s:.3f} s (run {summary.run_id})"
        )
    _track(args, store, "simulate", [out], params={"scene_file": args.scene, "set": args.set or []})
    return 0


def _cmd_stats(args: argparse.Namespace) -> int:
    from .statscli import stats_command
    from .tracking import numeric_leaves

    store = _tracking_store(args)
    summary = stats_command(args)
    params = {"scene_file": args.scene, "set": args.set or [], "regime": summary["regime"]}
    outputs = [args.output] if args.output else []
    _track(args, store, "stats", outputs, params=params, metrics=numeric_leaves(summary))
    return 0


def _cmd_torque_speed(args: argparse.Namespace) -> int:
    from .loadcli import torque_speed_command

    store = _tracking_store(args)
    summary = torque_speed_command(args)
    params = {"scene_file": args.scene, "set": args.set or [], "loads": args.loads or ""}
    scalars = ("no_load_speed", "stall_torque", "max_power", "max_power_load")
    metrics = {k: summary[k] for k in scalars if summary[k] is not None}
    _track(args, store, "torque-speed", [args.output] if args.output else [], params, metrics)
    return 0


def _cmd_info(args: argparse.Namespace) -> int:
    from .datasets import open_simulation

    ds = open_simulation(args.file, lazy=True)  # the header only: memory stays flat
    from .provenance import RUN_ATTRS, SCENE_ATTRS

    keys = dict.fromkeys(("scene_name", "run_id", *SCENE_ATTRS, *RUN_ATTRS, "n_chatter"))
    rows = [(k, ds.attrs[k]) for k in keys if k in ds.attrs]
    rows.append(("variables", ", ".join(sorted(ds.data_vars))))
    width = max(len(k) for k, _ in rows)  # one column of names, however long the longest
    for k, v in rows:
        print(f"{k:>{width}}: {v}")
    ds.close()
    return 0


# --- experiment tracking (bouncedisk.tracking; `runs` reads it back through bouncedisk.registry)

RUNS_ACTIONS = {"list": (0, 0), "show": (1, 1), "diff": (0, 2)}  # action: (min, max) run ids


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
    from . import tracking

    if not tracking.tracking_wanted(getattr(args, "track", None)):
        return None
    store = tracking.resolve_store(getattr(args, "tracking_uri", None))
    tracking.preflight(store)
    return store


def _track(args, store, kind: str, outputs=(), params=None, metrics=None) -> None:
    """After the work: record it as one run (no-op when ``store`` is None)."""
    if store is None:
        return
    from . import tracking
    from .atomic import keep_outputs

    command = "bouncedisk " + " ".join(shlex.quote(a) for a in sys.argv[1:])
    flush_stdout()  # the command's own output is complete before its outputs become final
    kept = keep_outputs()
    try:
        run_id = tracking.log_command_run(
            kind, store, outputs, params=params, metrics=metrics, command=command
        )
    except KeyboardInterrupt as ex:
        ex.kept_outputs = kept
        raise
    except Exception as ex:  # noqa: BLE001 - drivers and REST raise their own types
        reason = tracking._one_line(ex)
        raise tracking.TrackingError(
            store.uri, f"recording failed (the outputs were written): {reason}"
        ) from None
    if not getattr(args, "quiet", False):
        print(f"bouncedisk: recorded run {run_id} in {store.uri}", file=sys.stderr)


def _cmd_runs(args: argparse.Namespace) -> int:
    import json

    from . import registry

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


def _cmd_check(args: argparse.Namespace) -> int:
    from . import checks

    if args.output:
        from .outputs import check_output_path

        check_output_path(args.output, "-o")
    results_dir = checks.check_results_folder(args.results) if args.results is not None else None
    results = checks.run_checks(results_dir)
    text = checks.to_markdown(results)
    if args.output:
        from .atomic import write_text_atomic

        write_text_atomic(args.output, text)
    print(checks.to_text(results))
    return 0 if all(r.passed for r in results) else EXIT_FAIL


def _cmd_fit(args: argparse.Namespace) -> int:
    from . import fitting

    store = _tracking_store(args)
    fitting.fit_command(args)
    _track(
        args,
        store,
        "fit",
        [args.output],
        params={"curve": ", ".join(args.curve), "seed": args.seed},
    )
    return 0


class OneLineParser(argparse.ArgumentParser):
    """Argument errors as one line ``bouncedisk: error: ...`` and exit status 2 (no usage block).

    Subparsers inherit the class (``add_subparsers`` uses the parent's type).
    """

    def error(self, message: str):
        """Print one line naming the command and the problem, then exit 2."""
        message = " ".join(message.split())
        self.exit(
            EXIT_USER, f"bouncedisk: error: {self.prog}: {message} (see {self.prog} --help)\n"
        )


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``bouncedisk`` command and its subcommands."""
    parser = OneLineParser(
        prog="bouncedisk",
        description="Exact event-driven simulation of a rotor bouncing on a vibrating, "
        "twisting stator.",
    )
    parser.add_argument("--version", action="version", version=f"bouncedisk {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in (_add_simulate, _add_stats, _add_info, _add_runs, _add_check, _add_fit):
        add(sub)
    _add_torque_speed(sub)
    return parser


def _add_torque_speed(sub) -> None:
    """``bouncedisk torque-speed`` (:mod:`bouncedisk.loadcli`)."""
    from .loadcli import add_torque_speed

    add_torque_speed(sub, _add_set_option, _add_track_options)
    sub.choices["torque-speed"].set_defaults(func=_cmd_torque_speed)


def _add_set_option(p: argparse.ArgumentParser, example: str) -> None:
    """``--set KEY=VALUE`` (repeatable): override a scene field."""
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help=f"override a scene field, e.g. --set {example} (repeatable)",
    )


def _add_simulate(sub) -> None:
    """``bouncedisk simulate SCENE -o OUT.nc`` (INTERFACES.md)."""
    p = sub.add_parser("simulate", help="run one scene and write one netCDF file")
    p.add_argument("scene", help="scene file (YAML)")
    p.add_argument("-o", "--output", required=True, help="netCDF file to write")
    _add_set_option(p, "parameters.e=0.6")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress or summary")
    p.add_argument(
        "--max-output",
        metavar="SIZE",
        help="refuse a run whose file would exceed SIZE (e.g. 500M, 4G; default: "
        "$BOUNCEDISK_MAX_OUTPUT or 4G)",
    )
    _add_track_options(p)
    p.set_defaults(func=_cmd_simulate)


def _add_stats(sub) -> None:
    """``bouncedisk stats SCENE [-o STATS.nc] [--json]`` (INTERFACES.md "Statistics")."""
    p = sub.add_parser(
        "stats", help="long-run statistics of a scene's ensemble, with 95%% confidence intervals"
    )
    p.add_argument("scene", help="scene file (YAML) with stop.time; ensemble: {members, seed}")
    p.add_argument("-o", "--output", help="also write per-member values to this netCDF file")
    _add_set_option(p, "ensemble.members=32")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument(
        "--cores", type=int, default=None, help="members run on this many cores (default: all)"
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress")
    _add_track_options(p)
    p.set_defaults(func=_cmd_stats)


def _add_info(sub) -> None:
    """``bouncedisk info FILE``."""
    p = sub.add_parser("info", help="summarise a simulation netCDF file")
    p.add_argument("file")
    p.set_defaults(func=_cmd_info)


def _add_runs(sub) -> None:
    """``bouncedisk runs [list | show RUN | diff A B]`` (INTERFACES.md "Experiment tracking")."""
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


def _add_check(sub) -> None:
    """``bouncedisk check [--results DIR]``: the paper's claims."""
    p = sub.add_parser("check", help="verify the paper's claims (exit 0 only if all pass)")
    p.add_argument("--results", help="folder of built results to check (default: simulate)")
    p.add_argument("-o", "--output", help="also write the report as Markdown")
    p.set_defaults(func=_cmd_check)


def _add_fit(sub) -> None:
    """``bouncedisk fit CURVE.csv [CURVE.csv ...] -o FIT.nc`` (INTERFACES.md)."""
    p = sub.add_parser("fit", help="fit the model to a measured velocity-time curve")
    p.add_argument(
        "curve",
        nargs="+",
        help="CSV with time_s, omega_rad_s[, sigma_rad_s]; several: run-ups of one motor, "
        "fitted together (README, 'Fitting')",
    )
    p.add_argument("-o", "--output", required=True, help="fit netCDF file to write")
    p.add_argument(
        "--load",
        nargs="+",
        default=[],
        metavar="LOAD.csv",
        help="load curves of the same motor (torque_Nm, speed_rad_s[, speed_sd_rad_s] and a "
        "sidecar with the rotor and window_s), fitted jointly with the run-ups",
    )
    p.add_argument("--sidecar", help="YAML sidecar of every curve (default: CURVE with .yaml)")
    p.add_argument("--seed", default="12345", help="random seed, >= 0 (default: %(default)s)")
    p.add_argument(
        "--bootstrap",
        default="40",
        help="block-bootstrap resamples of the data, >= 2 (default: %(default)s)",
    )
    p.add_argument(
        "--members",
        default=None,
        help="model members per evaluation, >= 4 (default: 12; 32 for several run-ups)",
    )
    p.add_argument(
        "--scan",
        default=None,
        help="Sobol scan points of (e, omega_s), >= 8 (default: 192; fewer: a quicker, coarser "
        "search)",
    )
    p.add_argument(
        "--zoom",
        default=None,
        help="scan points around each of the best scan points, >= 0 (default: 16)",
    )
    p.add_argument("--cores", default=None, help="threads for the members (default: all)")
    p.add_argument(
        "--e-sigma",
        default=None,
        help="restitution noise of the model's members, in (0, 0.5] (default: 0.03; README, "
        "'Fitting': a curve and the model fitted to it share it)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress or summary")
    _add_track_options(p)
    p.set_defaults(func=_cmd_fit)


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def _install_signal_handlers() -> None:
    """Ctrl-C (SIGINT) and SIGTERM stop a run cleanly: temporaries removed, no output written.

    SIGINT is set explicitly because a process started in the background by a non-interactive
    shell inherits it ignored, and Python then installs no handler of its own.
    """
    try:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, _interrupt)
    except ValueError:  # not the main thread (embedded use): leave the host's handlers alone
        pass


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script."""
    _install_signal_handlers()
    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    if extra and args.command == "runs":  # run ids after options: `runs diff A --json B`
        bad = [x for x in extra if x.startswith("-")]
        if bad:
            print(f"bouncedisk: error: runs: unknown option {bad[0]}", file=sys.stderr)
            return EXIT_USER
        args.words += extra
    elif extra:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    from . import atomic

    stdout, sys.stdout = sys.stdout, _NamedStdout(sys.stdout)
    try:
        with atomic.recording_outputs():
            code, kept = _run_command(args)
    finally:
        sys.stdout = stdout
    if kept:  # interrupted or failed while recording the run: the outputs stay
        names = ", ".join(str(p) for p in kept)
        print(f"bouncedisk: the outputs were written and kept: {names}", file=sys.stderr)
    return code


def flush_stdout() -> None:
    """Flush standard output; a failure (``> /dev/full``) is an ``OSError`` naming ``<stdout>``."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        raise
    except OSError as ex:
        raise OSError(ex.errno, ex.strerror or str(ex), "<stdout>") from None


def _discard_stdout() -> None:
    """Point standard output at /dev/null: what could not be written raises no second error
    when Python flushes it at exit."""
    if getattr(sys.stdout, "_stream", sys.stdout) is not sys.__stdout__:
        return  # a caller's stream (tests, embedding): theirs to handle
    with contextlib.suppress(OSError, ValueError, io.UnsupportedOperation):
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.__stdout__.fileno())


class _NamedStdout:
    """Standard output whose write errors name it: ``OSError`` with filename ``<stdout>``."""

    def __init__(self, stream):
        self._stream = stream

    def __getattr__(self, name: str):
        return getattr(self._stream, name)

    def _call(self, name: str, *a):
        try:
            return getattr(self._stream, name)(*a)
        except BrokenPipeError:
            raise
        except OSError as ex:
            raise OSError(ex.errno, ex.strerror or str(ex), "<stdout>") from None

    def write(self, text: str) -> int:
        return self._call("write", text)

    def flush(self) -> None:
        self._call("flush")


def _run_command(args: argparse.Namespace) -> tuple[int, list]:
    """Run a subcommand; on any failure remove the outputs it wrote (``atomic``).

    Standard output is flushed before the command counts as done, so that a full disk or a
    closed pipe there is an error too. Returns the exit status and the outputs that were
    declared final (by tracking) before a failure, to be named to the user.
    """
    from . import atomic

    try:
        code = args.func(args)
        flush_stdout()
        return code, []
    except BaseException as ex:
        if not isinstance(ex, BrokenPipeError | SystemExit):  # a reader that stopped early: done
            atomic.remove_outputs()
        code = _report(ex)
        kept = getattr(ex, "kept_outputs", [])
        return code, kept


def _report(exc: BaseException) -> int:
    """Print one line for a failed command; return its exit status (or re-raise)."""
    try:
        raise exc
    except InputError as ex:
        print(f"bouncedisk: error: {ex.line()}", file=sys.stderr)
        return EXIT_USER
    except KeyboardInterrupt as ex:
        if getattr(ex, "kept_outputs", None):
            print("bouncedisk: interrupted while recording the run", file=sys.stderr)
        else:
            print("bouncedisk: interrupted; no output written", file=sys.stderr)
        return EXIT_INTERRUPT
    except BrokenPipeError:
        _discard_stdout()
        return 0
    except MemoryError:
        print(
            "bouncedisk: error: out of memory: the request needs more memory than this machine "
            "has; ask for less (fewer impacts, a larger outputs.trajectory.dt)",
            file=sys.stderr,
        )
        return EXIT_USER
    except OSError as ex:  # a file the user named cannot be read or written
        if ex.filename == "<stdout>":
            _discard_stdout()
        where = f"{ex.filename}: " if ex.filename else ""
        reason = ex.strerror or " ".join(str(ex).split()) or type(ex).__name__
        print(f"bouncedisk: error: {where}{reason}", file=sys.stderr)
        return EXIT_USER
    except Exception as ex:  # engine failures: one line, no traceback
        from .engine import EngineError

        if isinstance(ex, EngineError):
            print(f"bouncedisk: error: {ex}", file=sys.stderr)
            return EXIT_FAIL
        raise


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
