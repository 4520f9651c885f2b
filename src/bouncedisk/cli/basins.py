"""The ``bouncedisk basins`` command: which motion each start reaches (docs/formats.md "Basins file")."""

from __future__ import annotations

import argparse
import time

from ..io.history import write_with_history
from ..model.errors import InputError
from ..model.limits import SETTLE_RANGE
from ..run.cores import available_cores
from .common import _add_set_option, command_line, naming_overrides, print_result
from .tracking_options import _add_track_options, _track, _tracking_store
from .window_warnings import print_window_warnings


def format_basins(summary: dict) -> str:
    """A human-readable table of :func:`bouncedisk.studies.basins.summary`."""
    lo, hi = summary["window"]
    longer = sum(f > 1 for f in summary["per_start"]["window_factor"])
    extend = summary["extend"]
    again = (
        f"{longer} not settled in it measured again over longer windows, up to {2**extend}x"
        if extend
        else "no longer windows: --extend 0"
    )
    lines = [
        f"{summary['starts']} starts, averaged over [{lo:g}, {hi:g}] time units after switch-on "
        f"({again})",
        f"{'label':>5} {'mean speed':>12} {'95% CI':>21} {'regime':>22} {'starts':>7} "
        f"{'fraction':>9} {'95% CI (Wilson)':>18}",
    ]
    for a in summary["attractors"]:
        period = a["period"]
        regime = a["regime"] + (f" {period[0]}/{period[1]}" if period else "")
        f_lo, f_hi = a["fraction_ci95"]
        s_lo, s_hi = a["mean_speed_ci95"]
        speed_ci = "n/a" if s_lo is None or s_hi is None else f"[{s_lo:.5g}, {s_hi:.5g}]"
        lines.append(
            f"{a['label']:>5} {a['mean_speed']:>12.6g} {speed_ci:>21} {regime:>22} "
            f"{a['starts']:>7} {a['fraction']:>9.3f} {f'[{f_lo:.3f}, {f_hi:.3f}]':>18}"
        )
    u = summary["unsettled"]
    f_lo, f_hi = u["fraction_ci95"]
    lines.append(
        f"{-1:>5} {'not settled':>12} {'':>21} {'':>22} {u['starts']:>7} {u['fraction']:>9.3f} "
        f"{f'[{f_lo:.3f}, {f_hi:.3f}]':>18}"
    )
    lines.append(f"rule: {summary['rule']} (settle = {summary['settle']:g})")
    return "\n".join(lines)


def _values(text: str | None, field: str, what: str, default: list[float]) -> list[float]:
    """Speeds or heights from ``A:B:K`` or ``a,b,c`` (:func:`~bouncedisk.studies.basins.parse_values`)."""
    from ..studies.basins import parse_values

    return default if text is None else parse_values(text, field, what)


def basins_command(args: argparse.Namespace) -> dict:
    """Run ``bouncedisk basins``; returns the printed summary."""
    from ..io.output_checks import check_output_path
    from ..model.scene import load_scene
    from ..run.runner import deferred_interrupts
    from ..studies.basins import DEFAULT_SETTLE, EXTEND, basins, check_scene, start_grid, summary

    settle = DEFAULT_SETTLE if args.settle is None else args.settle
    extend = EXTEND if args.extend is None else args.extend
    if args.cores is not None and args.cores < 1:
        raise InputError("<arguments>", "--cores", f"must be >= 1, got {args.cores}")
    SETTLE_RANGE.check("<arguments>", "--settle", settle)
    if args.output is not None:
        check_output_path(args.output, "-o", inputs=[args.scene])
    scene = load_scene(args.scene, args.set or [])
    with naming_overrides(args.set):
        check_scene(scene)
    speeds = _values(args.speeds, "--speeds", "speed", [scene.initial.omega])
    heights = _values(args.heights, "--heights", "height", [0.0])
    grid = start_grid(args.phases, speeds, heights)
    print_window_warnings(scene, [])  # a window from switch-on holds the start-up transient
    cores = args.cores or available_cores()
    start = time.perf_counter()
    with deferred_interrupts() as req:

        def progress(done: int, total: int) -> None:
            if req.signum is not None:
                raise KeyboardInterrupt

        with naming_overrides(args.set):  # a capped start: the --set that set the cap
            ds = basins(scene, grid, cores=cores, settle=settle, progress=progress, extend=extend)
        wall = time.perf_counter() - start
        ds.attrs["wall_time_s"] = round(wall, 6)
        if args.output:
            write_with_history(ds, args.output, command_line(args))
    out = summary(ds)
    saved = f"per start and per attractor ({wall:.2f} s on {cores} cores)"
    print_result(args, out, format_basins(out), saved)
    return out


def _cmd_basins(args: argparse.Namespace) -> int:
    store = _tracking_store(args)
    out = basins_command(args)
    params = {
        "scene_file": args.scene,
        "set": args.set or [],
        "phases": args.phases,
        "extend": out["extend"],
        "settle": out["settle"],
    }
    metrics = {"n_attractors": len(out["attractors"]), "unsettled": out["unsettled"]["fraction"]}
    _track(args, store, "basins", [args.output] if args.output else [], params, metrics)
    return 0


def _add_basins(sub) -> None:
    """``bouncedisk basins SCENE --phases N [--speeds ..] [--heights ..] [-o F.nc] [--json]``."""
    p = sub.add_parser(
        "basins",
        help="coexisting motions: which attractor each start reaches, basin fractions with 95%% intervals",
    )
    p.add_argument(
        "scene",
        help="scene file (YAML) with torsion and stop.time; stats.discard (default 0) starts "
        "the averages",
    )
    p.add_argument(
        "--phases",
        type=int,
        required=True,
        metavar="N",
        help="stator phases at switch-on, N evenly over one period",
    )
    p.add_argument(
        "--speeds",
        metavar="A:B:K | a,b,c",
        help="initial rotor speeds (default: the scene's initial.omega)",
    )
    p.add_argument(
        "--heights",
        metavar="A:B:M | a,b,c",
        help="initial heights above the stator: 0 in contact, above 0 released at rest (default 0)",
    )
    p.add_argument(
        "--settle",
        type=float,
        default=None,
        help="settle tolerance: a start has settled when its halves' mean speeds differ by at "
        "most settle x scale x min(1, 10 T_s / h) (scale: the largest |mean speed|, >= 1; h: "
        "the start's half-window; T_s: the stator period; chaotic: 10 x settle x scale); "
        "default 0.01 (bouncedisk.studies.basins.DEFAULT_SETTLE)",
    )
    p.add_argument(
        "--extend",
        type=int,
        default=None,
        metavar="K",
        help="a start not settled is measured again over the window doubled (its run "
        "continued), up to K times (0: the scene's window only); default 3, up to 8x "
        "(bouncedisk.studies.basins.EXTEND)",
    )
    p.add_argument("-o", "--output", help="write the starts and the attractors to this netCDF file")
    _add_set_option(p, "parameters.load_torque=0.075")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument(
        "--cores", type=int, default=None, help="starts run on this many cores (default: all)"
    )
    _add_track_options(p)
    p.set_defaults(func=_cmd_basins)
