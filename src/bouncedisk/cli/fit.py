"""``bouncedisk fit CURVE.csv ... -o FIT.nc``: the options of the fit command, parsed and checked
here (before any work), progress and the summary printed here; the fit itself takes values
(:func:`bouncedisk.fitting.command.run_fit`)."""

from __future__ import annotations

import argparse
import sys
import time

from ..model.errors import InputError
from ..model.limits import BOOTSTRAP_RANGE, E_SIGMA
from .tracking_options import _add_track_options, _track, _tracking_store

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


def fit_settings(args: argparse.Namespace):
    """Every option of the fit as a value (before any work): its
    :class:`~bouncedisk.fitting.core.FitSettings`."""
    from ..fitting import core
    from ..fitting.search import SIZE_LIMITS
    from ..run.cores import available_cores

    opts = {
        "seed": _int_option(args.seed, "--seed", 0, 2**63 - 1),
        "bootstrap": _int_option(
            args.bootstrap, "--bootstrap", BOOTSTRAP_RANGE.low, BOOTSTRAP_RANGE.high
        ),
        "members": _int_option(args.members, "--members", 4, 1024)
        if args.members is not None
        else None,
    }
    for name in ("scan", "zoom"):
        if (text := getattr(args, name, None)) is not None:
            opts[name] = _int_option(text, f"--{name}", *SIZE_LIMITS[name])
    cores = _int_option(args.cores, "--cores", 1, 1024) if args.cores is not None else None
    if getattr(args, "e_sigma", None) is not None:
        opts["e_sigma"] = _e_sigma_option(args.e_sigma)
    return core.FitSettings(**opts, cores=cores if cores is not None else available_cores())


def _e_sigma_option(text) -> float | None:
    """``--e-sigma``: the members' restitution noise ``σ_e`` (docs/model.md), stated within
    :data:`~bouncedisk.model.limits.E_SIGMA` (0: the deterministic limit), or ``fit`` (``None``:
    a fifth search coordinate)."""
    from ..model.params import number

    if str(text).strip().lower() == "fit":
        return None
    try:
        value = number(ARG, "--e-sigma", text)
    except InputError:
        raise InputError(
            ARG, "--e-sigma", f"must be a number or 'fit' (the default), got {text!r}"
        ) from None
    return E_SIGMA.check(ARG, "--e-sigma", value)


def _cmd_fit(args: argparse.Namespace) -> int:
    from ..fitting.command import run_fit
    from ..fitting.output import summary_text

    store = _tracking_store(args)
    settings = fit_settings(args)
    start = time.perf_counter()

    def progress(msg: str) -> None:
        print(f"fit: [{time.perf_counter() - start:6.1f} s] {msg}", file=sys.stderr, flush=True)

    ds = run_fit(
        list(args.curve),
        args.output,
        settings,
        list(args.load or []),
        args.sidecar,
        None if args.quiet else progress,
    )
    if not args.quiet:
        print(summary_text(ds))
    _track(
        args,
        store,
        "fit",
        [args.output],
        params={
            "curve": ", ".join(args.curve),
            "seed": args.seed,
            "identified": ds.attrs["identified"],
        },
    )
    return 0


def _add_fit(sub) -> None:
    """``bouncedisk fit CURVE.csv [CURVE.csv ...] -o FIT.nc`` (docs/formats.md)."""
    p = sub.add_parser("fit", help="fit the model to a measured velocity-time curve")
    p.add_argument(
        "curve",
        nargs="+",
        help="CSV with time_s, omega_rad_s[, sigma_rad_s]; several: run-ups of one motor, "
        "fitted together (docs/user_guide/fitting.md)",
    )
    p.add_argument("-o", "--output", required=True, help="fit netCDF file to write")
    p.add_argument(
        "--load",
        action="append",
        default=[],
        metavar="LOAD.csv",
        help="a load curve of the same motor (torque_Nm, speed_rad_s[, speed_sd_rad_s] and a "
        "sidecar with the rotor and window_s), fitted jointly with the run-ups; one file per "
        "--load, repeated for several: --load A.csv --load B.csv",
    )
    p.add_argument(
        "--sidecar",
        help="YAML sidecar of every run-up (default: each CURVE with .yaml; a load curve's is "
        "always its CSV with .yaml)",
    )
    p.add_argument("--seed", default="12345", help="random seed, >= 0 (default: %(default)s)")
    p.add_argument(
        "--bootstrap",
        default="40",
        help=f"block-bootstrap resamples of the data, {BOOTSTRAP_RANGE.text()} (default: %(default)s, "
        "the fewest the fit accepts)",
    )
    p.add_argument(
        "--members",
        default=None,
        help="model members per evaluation, >= 4 (default: 12; 32 for several run-ups)",
    )
    p.add_argument(
        "--scan",
        default=None,
        help="Sobol scan points of (e, omega_s), >= 8 (default: 192; fewer: a quicker, coarser "
        "search)",
    )
    p.add_argument(
        "--zoom",
        default=None,
        help="scan points around each of the best scan points, >= 0 (default: 16)",
    )
    p.add_argument("--cores", default=None, help="threads for the members (default: all)")
    p.add_argument(
        "--e-sigma",
        default=None,
        help="restitution noise of the model's members: 'fit' fits it over [0, 0.1] (default), "
        f"a number {E_SIGMA.text()} states it (0: the deterministic limit) "
        "(docs/user_guide/fitting.md)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress or summary")
    _add_track_options(p)
    p.set_defaults(func=_cmd_fit)
