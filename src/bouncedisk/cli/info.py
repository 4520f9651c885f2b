"""``bouncedisk info FILE``: what a simulation file holds."""

from __future__ import annotations

import argparse


def _cmd_info(args: argparse.Namespace) -> int:
    from ..io.netcdf import open_simulation

    ds = open_simulation(args.file, lazy=True)  # the header only: memory stays flat
    from ..io.provenance import RUN_ATTRS, SCENE_ATTRS

    keys = dict.fromkeys(("scene_name", "run_id", *SCENE_ATTRS, *RUN_ATTRS, "n_chatter"))
    rows = [(k, ds.attrs[k]) for k in keys if k in ds.attrs]
    rows.append(("variables", ", ".join(sorted(ds.data_vars))))
    width = max(len(k) for k, _ in rows)  # one column of names, however long the longest
    for k, v in rows:
        print(f"{k:>{width}}: {v}")
    ds.close()
    return 0


def _add_info(sub) -> None:
    """``bouncedisk info FILE``."""
    p = sub.add_parser("info", help="summarise a simulation netCDF file")
    p.add_argument("file")
    p.set_defaults(func=_cmd_info)
