"""``bouncedisk fit CURVE.csv ... -o FIT.nc``: the options of the fit command."""

from __future__ import annotations

import argparse

from .tracking_options import _add_track_options, _track, _tracking_store


def _cmd_fit(args: argparse.Namespace) -> int:
    from .. import fitting

    store = _tracking_store(args)
    fitting.fit_command(args)
    _track(
        args,
        store,
        "fit",
        [args.output],
        params={"curve": ", ".join(args.curve), "seed": args.seed},
    )
    return 0


def _add_fit(sub) -> None:
    """``bouncedisk fit CURVE.csv [CURVE.csv ...] -o FIT.nc`` (docs/formats.md)."""
    p = sub.add_parser("fit", help="fit the model to a measured velocity-time curve")
    p.add_argument(
        "curve",
        nargs="+",
        help="CSV with time_s, omega_rad_s[, sigma_rad_s]; several: run-ups of one motor, "
        "fitted together (README, 'Fitting')",
    )
    p.add_argument("-o", "--output", required=True, help="fit netCDF file to write")
    p.add_argument(
        "--load",
        nargs="+",
        default=[],
        metavar="LOAD.csv",
        help="load curves of the same motor (torque_Nm, speed_rad_s[, speed_sd_rad_s] and a "
        "sidecar with the rotor and window_s), fitted jointly with the run-ups",
    )
    p.add_argument("--sidecar", help="YAML sidecar of every curve (default: CURVE with .yaml)")
    p.add_argument("--seed", default="12345", help="random seed, >= 0 (default: %(default)s)")
    p.add_argument(
        "--bootstrap",
        default="40",
        help="block-bootstrap resamples of the data, >= 2 (default: %(default)s)",
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
        help="restitution noise of the model's members: a number in [0, 0.5] states it (default: "
        "0.03; 0: the deterministic limit), 'fit' fits it over [0, 0.1] (docs/user_guide/fitting.md)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress or summary")
    _add_track_options(p)
    p.set_defaults(func=_cmd_fit)
