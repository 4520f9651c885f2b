"""The fit as one call on values: read the run-ups and load curves, fit, write the fit file
(several curves: run-ups of one motor fitted together, :mod:`~bouncedisk.fitting.runs`).

:mod:`bouncedisk.cli.fit` parses the command line and prints; this module takes the parsed
values and reports progress through a callback. Every defect a user can make is an
:class:`~bouncedisk.model.errors.InputError` raised before the fit starts (docs/formats.md: exit
2, one line ``bouncedisk: error: FILE: FIELD: message``, no output file).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import xarray as xr

from ..io.output_checks import check_output_path, sidecar_of
from ..model.errors import InputError
from .core import FitSettings


def check_output(
    output: str, curves: list[str], sidecar: str | None, loads: list[str] = ()
) -> Path:
    """The output path, checked as every command's
    (:func:`~bouncedisk.io.output_checks.check_output_path`): not a folder, not an input (a
    curve, a load curve or a sidecar), a place where a file can be created. A curve that is a
    folder is one line (``fit . -o x.nc``)."""
    inputs: list[str | Path] = [*curves, *loads]
    inputs += [sidecar] if sidecar else [sidecar_of(c, "curve") for c in curves]
    inputs += [sidecar_of(c, "--load") for c in loads]
    return check_output_path(output, "-o", inputs=inputs)


def run_fit(
    curves: list[str],
    output: str,
    settings: FitSettings,
    loads: Sequence[str] = (),
    sidecar: str | None = None,
    progress: Callable[[str], None] | None = None,
) -> xr.Dataset:
    """Read the run-ups (and load curves), fit them, write the fit file; returns its dataset.

    Takes values, not options (:mod:`bouncedisk.cli.fit` parses and prints): ``settings`` is the
    fit's, ``progress`` receives every progress line (``None``: silent). The output path is
    checked before any work (:func:`check_output`); every defect of an input is an
    :class:`~bouncedisk.model.errors.InputError` before the fit starts.
    """
    from ..io.netcdf import write_dataset
    from ..io.runup_curves import read_curve
    from . import core
    from .output import fit_dataset

    say = progress or (lambda msg: None)
    if sidecar is not None and not Path(sidecar).is_file():
        raise InputError(str(sidecar), "--sidecar", "file not found")
    check_output(output, list(curves), sidecar, list(loads))
    read, seen = [], {}
    for path in curves:
        first_time(path, seen, "", "give each run-up once")
        read.append(read_curve(path, sidecar))
    load_data = read_loads(list(loads), seen)
    core.check_fit_inputs(read, load_data)  # together too (one motor, one set-up)
    # every file read and checked: a bad one's error is the command's only line
    c = read[0]
    runs = f"{len(read)} run-ups of " if len(read) > 1 else ""
    say(f"read {', '.join(map(str, [*curves, *loads]))}")
    say(f"{runs}{len(c.time)} samples over {c.time[-1] - c.time[0]:.6g} s")
    fit = core.fit_curve(read, settings, progress, load=load_data)
    ds = fit_dataset(fit)
    write_dataset(ds, output)
    return ds


def read_loads(paths: list[str], seen: dict) -> list:
    """Read and check the load curves (:func:`bouncedisk.io.load_curves.read_load_curve`): each file
    once, none of them a run-up."""
    from ..io.load_curves import read_load_curve

    out = []
    for path in paths:
        first_time(path, seen, "--load", "give each curve once")
        out.append(read_load_curve(path))
    return out


def first_time(path: str, seen: dict, field: str, advice: str) -> None:
    """Refuse an input file given before (``seen``: resolved path -> as given), else record it."""
    key = Path(path).resolve()
    if key in seen:
        raise InputError(str(path), field, f"is the same file as {seen[key]}: {advice}")
    seen[key] = str(path)
