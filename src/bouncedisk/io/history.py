"""A command's dataset written atomically, its ``history`` the command line that made it."""

from __future__ import annotations


def write_with_history(ds, path, command: str) -> None:
    """Write a command's dataset atomically, its ``history`` the command line that made it.

    ``command`` is the command line as the CLI received it (``bouncedisk stats ...``); the
    ``history`` attribute is ``"<created>: <command>"`` (docs/formats.md "netCDF files").
    """
    from .netcdf import write_dataset

    ds.attrs["history"] = f"{ds.attrs['created']}: {command}"
    write_dataset(ds, path)
