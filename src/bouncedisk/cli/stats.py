"""The ``bouncedisk stats`` command: run a scene's ensemble, print or write its statistics."""

from __future__ import annotations

import argparse
import sys
import time

from ..io.history import write_with_history
from ..model.errors import InputError
from ..run.cores import available_cores
from .common import _add_set_option, command_line, naming_overrides, print_result
from .tracking_options import _add_track_options, _track, _tracking_store
from .window_warnings import print_window_warnings


def _progress(quiet: bool, label: str):
    """``on_member(done, total)`` printing to stderr after 2 s (never with ``quiet``)."""
    start = time.monotonic()
    last = [0.0]

    def on_member(done: int, total: int) -> None:
        now = time.monotonic()
        if quiet or now - start < 2.0 or (now - last[0] < 1.0 and done < total):
            return
        last[0] = now
        print(f"{label}: {done}/{total} members, {now - start:.0f} s", file=sys.stderr)

    return on_member


def format_summary(summary: dict) -> str:
    """A human-readable table of ``EnsembleStats.summary()``."""
    lines = [
        f"{'members':>18}: {summary['members']}",
        f"{'averaged over':>18}: {summary['duration']:g} time units after {summary['discard']:g}",
    ]
    lines.append(_row(summary, "mean_omega"))
    if "settled" in summary:
        lines.append(_settled_row(summary))
    for name in (
        "mean_slip",
        "impact_rate",
        "chatter_rate",
        "chatter_interval",
        "lyapunov",
    ):
        lines.append(_row(summary, name))
    if summary["lyapunov_reset_fraction"] > 0:
        lines.append(
            f"{'':>18}  ({100 * summary['lyapunov_reset_fraction']:.0f}% of members reset every "
            "cycle: exponent -inf)"
        )
    for name in ("power_out", "power_torsion_in", "power_axial_in", "efficiency_torsion"):
        if name in summary:
            lines.append(_row(summary, name))
    physical = ("mean_omega_rad_s", "power_out_W", "power_torsion_in_W", "power_axial_in_W")
    for name in (*physical, "efficiency"):  # a physical scene's, in SI units
        if name in summary:
            lines.append(_row(summary, name))
    lines.append(
        f"{'energy audit':>18}: largest relative residual {_g(summary['audit_residual_axial'])} "
        f"(axial), {_g(summary['audit_residual_torsion'])} (torsional)"
    )
    period = summary["period"]
    reg = summary["regime"] + (f" ({period[0]} impacts / {period[1]} periods)" if period else "")
    frac = summary["regime_fraction"]
    lo, hi = summary["regime_fraction_ci95"]
    ci = f" (95% CI [{100 * lo:.0f}%, {100 * hi:.0f}%], Wilson)"
    tie = summary.get("regime_tie") or []
    if tie:
        reg = f"tie between {', '.join(tie[:-1])} and {tie[-1]}"
        lines.append(f"{'regime':>18}: {reg}, {100 * frac:.0f}% of members each{ci}")
    else:
        lines.append(f"{'regime':>18}: {reg}, {100 * frac:.0f}% of members{ci}")
    return "\n".join(lines)


def _settled_row(summary: dict) -> str:
    """Whether the window's two halves agree (:mod:`bouncedisk.analysis.settling`): the drift
    (second half's mean speed less the first's) with its interval, and what to do if not."""
    d, (low, high) = summary["drift"], summary["drift_ci95"]
    if d is None:  # no member sampled both halves
        return f"{'settled':>18}: n/a (no member has samples in both halves of its window)"
    ci = f" (95% CI [{low:.3g}, {high:.3g}])" if low is not None else ""
    if summary["settled"]:
        return f"{'settled':>18}: yes, the halves' mean speeds differ by {d:+.3g}{ci}"
    side = "above" if d > 0 else "below"
    return (
        f"{'settled':>18}: NO, the second half's mean speed is {abs(d):.3g} {side} the first's"
        f"{ci}: still running up or down; lengthen stats.discard (and stop.time)"
    )


def _g(x: float | None) -> str:
    return "n/a" if x is None else f"{x:.2g}"


def _row(summary: dict, name: str) -> str:
    """One quantity's line: its mean and interval, and how many members have a value when
    some have none (``members_with_value``)."""
    value, ci = summary[name], summary[f"{name}_ci95"]
    if value is None:
        return f"{name:>18}: n/a"
    n = summary.get("members_with_value", {}).get(name, summary["members"])
    some = n < summary["members"]
    of = f"{n} of {summary['members']} members" if some else "one member"
    if ci[0] is None:
        return f"{name:>18}: {value:.6g}  ({of}: no interval)"
    count = f"  ({of})" if some else ""
    return f"{name:>18}: {value:.6g}  95% CI [{ci[0]:.6g}, {ci[1]:.6g}]{count}"


def stats_command(args: argparse.Namespace) -> dict:
    """Run ``bouncedisk stats`` (see :mod:`bouncedisk.analysis.statistics`); returns the printed summary."""
    from ..analysis.statistics import ensemble_window, run_stats, to_dataset
    from ..io.output_checks import check_output_path
    from ..model.scene import load_scene
    from ..run.runner import deferred_interrupts

    if args.cores is not None and args.cores < 1:
        raise InputError("<arguments>", "--cores", f"must be >= 1, got {args.cores}")
    if args.output is not None:
        check_output_path(args.output, "-o", inputs=[args.scene])
    scene = load_scene(args.scene, args.set or [])
    with naming_overrides(args.set):
        ensemble_window(scene)
    cores = args.cores or available_cores()
    start = time.perf_counter()
    with deferred_interrupts() as req:
        with naming_overrides(args.set):  # a capped member: the --set that set the cap
            result = run_stats(
                scene,
                cores=cores,
                on_member=_progress(args.quiet, scene.name),
                should_stop=lambda: req.signum is not None,
            )
        wall = time.perf_counter() - start
        if args.output:
            write_with_history(to_dataset(scene, result, wall), args.output, command_line(args))
    summary = result.summary()
    print_window_warnings(scene, [summary["regime"]])
    saved = f"per-member values ({wall:.2f} s on {cores} cores)"
    print_result(args, summary, format_summary(summary), saved)
    return summary


def _cmd_stats(args: argparse.Namespace) -> int:
    from ..tracking.extraction import numeric_leaves

    store = _tracking_store(args)
    summary = stats_command(args)
    params = {"scene_file": args.scene, "set": args.set or [], "regime": summary["regime"]}
    outputs = [args.output] if args.output else []
    _track(args, store, "stats", outputs, params=params, metrics=numeric_leaves(summary))
    return 0


def _add_stats(sub) -> None:
    """``bouncedisk stats SCENE [-o STATS.nc] [--json]`` (docs/formats.md "Statistics")."""
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
