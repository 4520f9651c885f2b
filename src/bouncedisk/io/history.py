"""A command's dataset written atomically, its ``history`` the command line that made it."""

from __future__ import annotations

import shlex
import sys


def write_with_history(ds, path) -> None:
    """Write a command's dataset atomically, its ``history`` the command line that made it."""
    from .netcdf import write_dataset

    command = "bouncedisk " + " ".join(shlex.quote(x) for x in sys.argv[1:])
    ds.attrs["history"] = f"{ds.attrs['created']}: {command}"
    write_dataset(ds, path)
