"""``bouncedisk fit CURVE.csv [CURVE.csv ...] -o FIT.nc``: options checked before any work,
progress, output (several curves: run-ups of one motor fitted together, :mod:`~bouncedisk.fitting.runs`).

Every option a user can get wrong is checked before the curve is fitted (docs/formats.md: exit 2,
one line ``bouncedisk: error: FILE: FIELD: message``, no output file).
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from ..model.errors import InputError

ARG = "<arguments>"


def _int_option(text, name: str, low: int, high: int) -> int:
    """An integer option in ``[low, high]`` (given as text so argparse never prints usage)."""
    try:
        value = int(str(text), 10)
    except ValueError:
        raise InputError(ARG, name, f"must be an integer, got {text!r}") from None
    if not low <= value <= high:
        raise InputError(ARG, name, f"must be between {low} and {high}, got {value}")
    return value


def check_output(
    output: str, curves: list[str], sidecar: str | None, loads: list[str] = ()
) -> Path:
    """The output path: a new or replaceable file in a writable folder, not an input (a curve,
    a load curve or a sidecar)."""
    out = Path(output)
    if out.is_dir():
        raise InputError(str(out), "-o", "is a directory; give a file name such as fit.nc")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise InputError(str(out), "-o", f"folder {str(parent)!r} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(str(out), "-o", f"folder {str(parent)!r} is not writable")
    inputs = [Path(c) for c in curves]
    inputs += [Path(sidecar)] if sidecar else [Path(c).with_suffix(".yaml") for c in curves]
    inputs += [q for c in loads for q in (Path(c), Path(c).with_suffix(".yaml"))]
    for p in inputs:
        if out.resolve() == p.resolve():
            raise InputError(str(out), "-o", "is an input file; give another output name")
    # a device, pipe or socket in the way; a read-only file system (os.access misjudges root)
    from ..io.output_checks import check_output_path

    return check_output_path(out, "-o", inputs=inputs)


def validate(args) -> dict:
    """Check every option (before any work); the fit's settings as a dictionary."""
    seed = _int_option(args.seed, "--seed", 0, 2**63 - 1)
    from .core import MIN_BOOTSTRAP

    boot = _int_option(args.bootstrap, "--bootstrap", MIN_BOOTSTRAP, 10_000)
    members = _int_option(args.members, "--members", 4, 1024) if args.members is not None else None
    from .search import SIZE_LIMITS

    search = {
        name: _int_option(text, f"--{name}", *SIZE_LIMITS[name])
        for name in ("scan", "zoom")
        if (text := getattr(args, name, None)) is not None
    }
    cores = _int_option(args.cores, "--cores", 1, 1024) if args.cores is not None else None
    if args.sidecar is not None and not Path(args.sidecar).is_file():
        raise InputError(str(args.sidecar), "--sidecar", "file not found")
    opts = {"seed": seed, "bootstrap": boot, "members": members, **search}
    if getattr(args, "e_sigma", None) is not None:
        opts["e_sigma"] = _e_sigma_option(args.e_sigma)
    loads = list(getattr(args, "load", None) or [])
    check_output(args.output, list(args.curve), args.sidecar, loads)
    if cores is None:
        from ..run.cores import available_cores

        cores = available_cores()
    return {**opts, "cores": cores}


def _e_sigma_option(text) -> float | None:
    """``--e-sigma``: the members' restitution noise ``σ_e`` (docs/model.md), stated in
    ``[0, 0.5]`` (0: the deterministic limit), or ``fit`` (``None``: a fifth search coordinate)."""
    from ..model.params import number

    if str(text).strip().lower() == "fit":
        return None
    value = number(ARG, "--e-sigma", text, nonneg=True)
    if value > 0.5:
        raise InputError(ARG, "--e-sigma", f"must be at most 0.5, got {value}")
    return value


def fit_command(args) -> None:
    """Run ``bouncedisk fit`` (see :mod:`bouncedisk.cli`)."""
    from ..io.netcdf import write_dataset
    from ..io.runup_curves import read_curve
    from .core import FitSettings, fit_curve
    from .output import fit_dataset, summary_text

    opts = validate(args)
    start = time.perf_counter()

    def progress(msg: str) -> None:
        if not args.quiet:
            print(f"fit: [{time.perf_counter() - start:6.1f} s] {msg}", file=sys.stderr, flush=True)

    curves = []
    seen = {}
    for path in args.curve:
        first_time(path, seen, "", "give each run-up once")
        progress(f"reading {path}")
        curves.append(read_curve(path, args.sidecar))
    c = curves[0]
    runs = f"{len(curves)} run-ups of " if len(curves) > 1 else ""
    progress(f"{runs}{len(c.time)} samples over {c.time[-1] - c.time[0]:.6g} s")
    loads = read_loads(getattr(args, "load", None) or [], seen, progress)
    settings = FitSettings(**opts)
    fit = fit_curve(curves, settings, progress, load=loads)
    ds = fit_dataset(fit)
    write_dataset(ds, args.output)
    if not args.quiet:
        print(summary_text(ds))


def read_loads(paths: list[str], seen: dict, progress) -> list:
    """Read and check the load curves (:func:`bouncedisk.io.load_curves.read_load_curve`): each file
    once, none of them a run-up."""
    from ..io.load_curves import read_load_curve

    out = []
    for path in paths:
        first_time(path, seen, "--load", "give each curve once")
        progress(f"reading load curve {path}")
        out.append(read_load_curve(path))
    return out


def first_time(path: str, seen: dict, field: str, advice: str) -> None:
    """Refuse an input file given before (``seen``: resolved path -> as given), else record it."""
    key = Path(path).resolve()
    if key in seen:
        raise InputError(str(path), field, f"is the same file as {seen[key]}: {advice}")
    seen[key] = str(path)
