"""The ``bouncedisk stats`` command: run a scene's ensemble, print or write its statistics."""

from __future__ import annotations

import argparse
import json
import os
import shlex
import sys
import time

from .errors import InputError


def available_cores() -> int:
    """Cores this process may use (its CPU affinity)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


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
    for name in ("mean_omega", "mean_slip", "impact_rate", "chatter_rate", "chatter_interval"):
        lines.append(_row(name, summary[name], summary[f"{name}_ci95"]))
    lines.append(_row("lyapunov", summary["lyapunov"], summary["lyapunov_ci95"]))
    if summary["lyapunov_reset_fraction"] > 0:
        lines.append(
            f"{'':>18}  ({100 * summary['lyapunov_reset_fraction']:.0f}% of members reset every "
            "cycle: exponent -inf)"
        )
    for name in ("power_out", "power_torsion_in", "power_axial_in", "efficiency_torsion"):
        if name in summary:
            lines.append(_row(name, summary[name], summary[f"{name}_ci95"]))
    for name in ("power_out_W", "power_torsion_in_W", "power_axial_in_W", "efficiency"):
        if name in summary:
            lines.append(_row(name, summary[name], summary[f"{name}_ci95"]))
    lines.append(
        f"{'energy audit':>18}: largest relative residual {_g(summary['audit_residual_axial'])} "
        f"(axial), {_g(summary['audit_residual_torsion'])} (torsional)"
    )
    period = summary["period"]
    reg = summary["regime"] + (f" ({period[0]} impacts / {period[1]} periods)" if period else "")
    frac = summary["regime_fraction"]
    tie = summary.get("regime_tie") or []
    if tie:
        reg = f"tie between {', '.join(tie[:-1])} and {tie[-1]}"
        lines.append(f"{'regime':>18}: {reg}, {100 * frac:.0f}% of members each")
    else:
        lines.append(f"{'regime':>18}: {reg}, {100 * frac:.0f}% of members")
    return "\n".join(lines)


def _g(x: float | None) -> str:
    return "n/a" if x is None else f"{x:.2g}"


def _row(name: str, value, ci) -> str:
    if value is None:
        return f"{name:>18}: n/a"
    if ci[0] is None:
        return f"{name:>18}: {value:.6g}  (one member: no interval)"
    return f"{name:>18}: {value:.6g}  95% CI [{ci[0]:.6g}, {ci[1]:.6g}]"


def write_with_history(ds, path) -> None:
    """Write a command's dataset atomically, its ``history`` the command line that made it."""
    from .datasets import write_dataset

    command = "bouncedisk " + " ".join(shlex.quote(x) for x in sys.argv[1:])
    ds.attrs["history"] = f"{ds.attrs['created']}: {command}"
    write_dataset(ds, path)


def stats_command(args: argparse.Namespace) -> dict:
    """Run ``bouncedisk stats`` (see :mod:`bouncedisk.stats`); returns the printed summary."""
    from .outputs import check_output_path
    from .runner import deferred_interrupts
    from .scene import load_scene
    from .stats import ensemble_window, run_stats, to_dataset

    if args.cores is not None and args.cores < 1:
        raise InputError("<arguments>", "--cores", f"must be >= 1, got {args.cores}")
    if args.output is not None:
        check_output_path(args.output, "-o", inputs=[args.scene])
    scene = load_scene(args.scene, args.set or [])
    ensemble_window(scene)
    cores = args.cores or available_cores()
    start = time.perf_counter()
    with deferred_interrupts() as req:
        result = run_stats(
            scene,
            cores=cores,
            on_member=_progress(args.quiet, scene.name),
            should_stop=lambda: req.signum is not None,
        )
        wall = time.perf_counter() - start
        if args.output:
            write_with_history(to_dataset(scene, result, wall), args.output)
    summary = result.summary()
    if args.json:
        print(json.dumps(summary))
    else:
        print(format_summary(summary))
        if args.output:
            print(f"{args.output}: per-member values ({wall:.2f} s on {cores} cores)")
    return summary
