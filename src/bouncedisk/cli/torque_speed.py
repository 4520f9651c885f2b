"""The ``bouncedisk torque-speed`` command: a scene's load characteristic (docs/formats.md)."""

from __future__ import annotations

import argparse
import json
import time

from ..io.history import write_with_history
from ..model.errors import InputError
from ..run.cores import available_cores
from .common import _add_set_option, command_line
from .stats import _progress
from .tracking_options import _add_track_options, _track, _tracking_store
from .window_warnings import print_window_warnings

#: Loads of a curve when ``--loads`` is not given: from no load to the momentum bound
#: ``τ_L = 1`` (docs/model.md "The motor under load"), in units of the scene's load torque.
DEFAULT_LOADS = "0:1:11"


def format_curve(summary: dict) -> str:
    """A human-readable table of :meth:`bouncedisk.studies.torque_speed.LoadCurve.summary`."""
    lines = [f"{'load':>8} {'mean speed':>12} {'95% CI':>25} {'power':>10} {'efficiency':>10}"]
    for k, load in enumerate(summary["loads"]):
        lo, hi = summary["mean_omega_ci95"][k]
        ci = "n/a" if lo is None else f"[{lo:.5g}, {hi:.5g}]"
        eff = summary["efficiency_torsion"][k]
        lines.append(
            f"{load:>8.4g} {summary['mean_omega'][k]:>12.6g} {ci:>25} "
            f"{summary['power_out'][k]:>10.4g} {'n/a' if eff is None else f'{eff:.4g}':>10}"
        )
    for name in ("no_load_speed", "stall_torque", "max_power", "max_power_load"):
        v, (lo, hi) = summary[name], summary[f"{name}_ci95"]
        ci = "" if lo is None and hi is None else f"  95% CI [{_g(lo)}, {_g(hi)}]"
        lines.append(f"{name:>14}: {_g(v)}{ci}")
    if summary.get("branches_differ_at"):
        at = ", ".join(f"{x:.4g}" for x in summary["branches_differ_at"])
        lines.append(f"{'two speeds':>14}: the up and down branches differ at loads {at}")
    return "\n".join(lines)


def _g(x) -> str:
    return "n/a (speed stays positive)" if x is None else f"{x:.6g}"


def torque_speed_command(args: argparse.Namespace) -> dict:
    """Run ``bouncedisk torque-speed``; returns the printed summary."""
    from ..analysis.statistics import ensemble_window
    from ..io.output_checks import check_output_path
    from ..model.scene import load_scene
    from ..run.runner import deferred_interrupts
    from ..studies.torque_speed import parse_loads, to_dataset, torque_speed

    if args.cores is not None and args.cores < 1:
        raise InputError("<arguments>", "--cores", f"must be >= 1, got {args.cores}")
    loads = parse_loads(args.loads or DEFAULT_LOADS)
    if args.output is not None:
        check_output_path(args.output, "-o", inputs=[args.scene])
    overrides = list(args.set or [])
    scene = load_scene(args.scene, _with_load(args.scene, overrides))
    ensemble_window(scene)
    if scene.physical is not None:  # loads in N·m, like physical.load_torque
        loads = loads / scene.physical.scales().torque
    cores = args.cores or available_cores()
    start = time.perf_counter()
    with deferred_interrupts() as req:
        curve = torque_speed(
            scene,
            loads,
            cores=cores,
            on_member=_progress(args.quiet, f"{scene.name} (torque-speed)"),
            should_stop=lambda: req.signum is not None,
        )
        wall = time.perf_counter() - start
        if args.output:
            write_with_history(to_dataset(scene, curve, wall), args.output, command_line(args))
    summary = curve.summary()
    regimes = summary["regime"] + (summary.get("down") or {}).get("regime", [])
    print_window_warnings(scene, regimes)
    if args.json:
        print(json.dumps(summary))
    else:
        print(format_curve(summary))
        if args.output:
            print(f"{args.output}: the curve ({wall:.2f} s on {cores} cores)")
    return summary


def _with_load(scene_file: str, overrides: list[str]) -> list[str]:
    """The overrides plus what turns the ``load`` effect on (its value is set per load), read
    from the scene as the user's overrides leave it (``--set effects=...`` included)."""
    from ..model.scene import apply_overrides, read_yaml

    raw = apply_overrides(read_yaml(scene_file), overrides)
    effects = raw.get("effects") or []
    if isinstance(effects, str):  # --set effects=a,b,c
        effects = [e.strip() for e in effects.split(",") if e.strip()]
    if isinstance(effects, list) and "load" not in effects:
        overrides.append("effects=" + ",".join([*map(str, effects), "load"]))
    section = "physical" if "physical" in raw else "parameters"
    if "load_torque" not in (raw.get(section) or {}):
        overrides.append(f"{section}.load_torque=0")
    return overrides


def _add_torque_speed(sub) -> None:
    """``bouncedisk torque-speed SCENE [--loads ...] [-o CURVE.nc] [--json]`` (docs/formats.md)."""
    p = sub.add_parser(
        "torque-speed",
        help="the motor's load characteristic: speed, power and efficiency against load torque",
    )
    p.add_argument(
        "scene", help="scene file (YAML) with torsion, stop.time and an ensemble (members, seed)"
    )
    p.add_argument(
        "--loads",
        metavar="START:STOP:N | A,B,C",
        help=f"load torques (nondimensional tau_L; N*m for a physical scene; default {DEFAULT_LOADS})",
    )
    p.add_argument("-o", "--output", help="write the curve (per branch, load and member) here")
    _add_set_option(p, "ensemble.members=32")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument(
        "--cores", type=int, default=None, help="members run on this many cores (default: all)"
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress")
    _add_track_options(p)
    p.set_defaults(func=_cmd_torque_speed)


def _cmd_torque_speed(args: argparse.Namespace) -> int:
    store = _tracking_store(args)
    summary = torque_speed_command(args)
    params = {"scene_file": args.scene, "set": args.set or [], "loads": args.loads or ""}
    scalars = ("no_load_speed", "stall_torque", "max_power", "max_power_load")
    metrics = {k: summary[k] for k in scalars if summary[k] is not None}
    _track(args, store, "torque-speed", [args.output] if args.output else [], params, metrics)
    return 0
