"""``bouncedisk simulate SCENE -o OUT.nc``: one scene, one netCDF file."""

from __future__ import annotations

import argparse

from .common import _add_set_option, command_line
from .tracking_options import _add_track_options, _track, _tracking_store


def _cmd_simulate(args: argparse.Namespace) -> int:
    from ..io.output_checks import check_output_path, default_max_output, parse_size
    from ..model.scene import load_scene
    from ..run.runner import run_scene

    out = check_output_path(args.output, "-o", inputs=[args.scene])
    limit = parse_size(args.max_output) if args.max_output is not None else default_max_output()
    scene = load_scene(args.scene, args.set or [])
    store = _tracking_store(args)
    summary = run_scene(
        scene, out, progress=not args.quiet, command=command_line(args), max_output_bytes=limit
    )
    if not args.quiet:
        members = scene.ensemble.members
        which = f", member 0 of {members} (stats runs them all)" if members > 1 else ""
        print(
            f"{out}: {summary.n_impacts} impacts, {summary.n_chatter} chattering tails, "
            f"status {summary.status!r}, {summary.wall_time_s:.3f} s (run {summary.run_id}){which}"
        )
    _track(args, store, "simulate", [out], params={"scene_file": args.scene, "set": args.set or []})
    return 0


def _add_simulate(sub) -> None:
    """``bouncedisk simulate SCENE -o OUT.nc`` (docs/formats.md)."""
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
