"""The ``bouncedisk torque-speed`` command: a scene's load characteristic (docs/formats.md)."""

from __future__ import annotations

import argparse
import math
import time

from ..io.history import write_with_history
from ..model.errors import InputError
from ..run.cores import available_cores
from .common import _add_set_option, command_line, naming_overrides, print_result
from .stats import _progress
from .tracking_options import _add_track_options, _track, _tracking_store
from .window_warnings import print_window_warnings

#: How finely the command locates the stall torque and the maximum power by default (as the
#: pipeline's load curves, workflow/config/config.yaml ``resolution``), in units of tau_L.
DEFAULT_RESOLUTION = 0.005
#: The table's columns and derived lines: nondimensional, and for a physical scene in SI units.
_COLUMNS = {
    False: ("loads", "mean_omega", "power_out", "efficiency_torsion"),
    True: ("loads_Nm", "mean_omega_rad_s", "power_out_W", "efficiency"),
}
_HEADS = {
    False: ("load", "mean speed", "power", "eff. drive"),
    True: ("load (N m)", "speed (rad/s)", "power (W)", "eff. motor"),
}
_DERIVED = {
    False: ("no_load_speed", "stall_torque", "max_power", "max_power_load"),
    True: ("no_load_speed_rad_s", "stall_torque_Nm", "max_power_W", "max_power_load_Nm"),
}


def format_curve(summary: dict, physical: bool = False) -> str:
    """A human-readable table of :meth:`bouncedisk.studies.torque_speed.LoadCurve.summary`.

    A physical scene's table is in SI units (loads in N·m, as typed) and its efficiency the
    motor's, ``P_out / (P_ax + P_t)`` ("eff. motor"), else nondimensional with the friction
    drive's ``W_L / W_t`` ("eff. drive"); a value that is unknown or not finite is ``n/a``.
    """
    load, speed, power, eff = (summary[k] for k in _COLUMNS[physical])
    ci95 = summary[f"{_COLUMNS[physical][1]}_ci95"]
    h_load, h_speed, h_power, h_eff = _HEADS[physical]
    lines = [f"{h_load:>10} {h_speed:>13} {'95% CI':>25} {h_power:>10} {h_eff:>10}"]
    for k in range(len(load)):
        lo, hi = ci95[k]
        ci = "n/a" if lo is None or hi is None else f"[{lo:.5g}, {hi:.5g}]"
        lines.append(
            f"{_f(load[k], '.4g'):>10} {_f(speed[k], '.6g'):>13} {ci:>25} "
            f"{_f(power[k], '.4g'):>10} {_f(eff[k], '.4g'):>10}"
        )
    for name in _DERIVED[physical]:
        v, (lo, hi) = summary[name], summary[f"{name}_ci95"]
        ci = "" if lo is None and hi is None else f"  95% CI [{_g(lo)}, {_g(hi)}]"
        value = _why_none(name, summary) if v is None else _g(v)
        lines.append(f"{name:>19}: {value}{ci}")
    if summary.get("unsettled_loads"):
        at = _loads(summary, "unsettled_loads", physical)
        lines.append(f"{'not settled':>19}: {at} (a finite window's mean, not a speed)")
    if summary.get("branches_differ_at"):
        at = _loads(summary, "branches_differ_at", physical)
        lines.append(f"{'two speeds':>19}: the up and down branches differ at {at}")
    return "\n".join(lines)


def _loads(summary: dict, name: str, physical: bool) -> str:
    """A list of loads in the table's unit: ``tau_L = ...``, or N·m for a physical scene."""
    if physical:
        return ", ".join(f"{x:.4g}" for x in summary[f"{name}_Nm"]) + " N m"
    return "tau_L = " + ", ".join(f"{x:.4g}" for x in summary[name])


def _f(x, spec: str) -> str:
    return "n/a" if x is None else format(x, spec)


def _g(x) -> str:
    return "n/a" if x is None else f"{x:.6g}"


def _why_none(name: str, summary: dict) -> str:
    """Why a derived quantity has no value, in the table's words (the summary's states,
    :data:`~bouncedisk.studies.load_summary.STALL_STATES` and ``PEAK_STATES``)."""
    from ..studies.load_summary import PEAK_STATES, STALL_STATES

    if name.startswith("no_load_speed"):
        return "n/a (the loads do not include 0)" if summary["loads"][0] != 0.0 else "n/a"
    if name.startswith("stall_torque"):
        state = summary.get("stall_torque_state", "none")
        return f"n/a ({state}: {STALL_STATES.get(state, state)})"
    state = summary.get("max_power_state", "none")
    return f"n/a ({state}: {PEAK_STATES.get(state, state)})"


def finite_json(x):
    """``x`` with every non-finite float as ``None`` (JSON has no ``Infinity`` or ``NaN``)."""
    if isinstance(x, dict):
        return {k: finite_json(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [finite_json(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def torque_speed_command(args: argparse.Namespace) -> dict:
    """Run ``bouncedisk torque-speed``; returns the printed summary.

    The scene is built once, from the file and the ``--set`` overrides, with the ``load`` effect
    added to whatever effects they give (:func:`~bouncedisk.studies.torque_speed.with_load`).
    """
    from ..analysis.statistics import ensemble_window
    from ..io.output_checks import check_output_path
    from ..run.runner import deferred_interrupts
    from ..studies.load_summary import REFINE_ROUNDS
    from ..studies.torque_speed import refined_torque_speed, scene_loads, to_dataset, with_load

    if args.cores is not None and args.cores < 1:
        raise InputError("<arguments>", "--cores", f"must be >= 1, got {args.cores}")
    resolution = _resolution(args.resolution)
    if args.output is not None:
        check_output_path(args.output, "-o", inputs=[args.scene])
    scene = with_load(_scene(args.scene, list(args.set or [])))
    with naming_overrides(args.set):
        ensemble_window(scene)
    loads = scene_loads(scene, args.loads)
    cores = args.cores or available_cores()
    start = time.perf_counter()
    with deferred_interrupts() as req:
        with naming_overrides(args.set):  # a capped member: the --set that set the cap
            curve = refined_torque_speed(
                scene,
                loads,
                resolution,
                REFINE_ROUNDS if resolution > 0.0 else 0,
                cores=cores,
                on_member=_progress(args.quiet, f"{scene.name} (torque-speed)"),
                should_stop=lambda: req.signum is not None,
            )
        wall = time.perf_counter() - start
        summary = finite_json(curve.summary())
        if args.output:
            write_with_history(
                to_dataset(scene, curve, wall, summary), args.output, command_line(args)
            )
    regimes = summary["regime"] + (summary.get("down") or {}).get("regime", [])
    print_window_warnings(scene, regimes)
    table = format_curve(summary, scene.physical is not None)
    print_result(args, summary, table, f"the curve ({wall:.2f} s on {cores} cores)")
    return summary


def _resolution(text) -> float:
    """``--resolution`` as a number >= 0 (0: the loads as given)."""
    from ..model.params import number

    return number("<arguments>", "--resolution", text, nonneg=True)


def _scene(path: str, sets: list[str]):
    """The scene; one that lists the ``load`` effect without its ``load_torque`` is read with
    ``load_torque: 0`` (a curve sets the torque at each load itself)."""
    from ..model.scene import load_scene

    try:
        return load_scene(path, sets)
    except InputError as ex:
        if not (ex.field.endswith(".load_torque") and "'load' effect" in ex.message):
            raise
        return load_scene(path, [*sets, f"{ex.field}=0"])


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
        help="load torques (nondimensional tau_L; N*m for a physical scene; default: 11 loads "
        "of tau_L from 0 to the momentum bound 1, for any scene)",
    )
    p.add_argument(
        "--resolution",
        default=str(DEFAULT_RESOLUTION),
        metavar="R",
        help="add loads where the stall torque and the maximum power lie until each is located "
        f"to R (nondimensional tau_L) or to the ensemble's spread (default {DEFAULT_RESOLUTION:g},"
        " as the pipeline; 0: the loads as given)",
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
    params = {
        "scene_file": args.scene,
        "set": args.set or [],
        "loads": args.loads or "",
        "resolution": args.resolution,
    }
    scalars = ("no_load_speed", "stall_torque", "max_power", "max_power_load")
    metrics = {k: summary[k] for k in scalars if summary[k] is not None}
    _track(args, store, "torque-speed", [args.output] if args.output else [], params, metrics)
    return 0
