"""A plain multi-start search (pyPESTO) of the fit's likelihood, beside the fit's staged search.

On the shipped synthetic motor (the run-up and the load curve, fitted jointly with the noise, as
the pipeline's fit) this runs the standard method of parameter estimation on the fit's own
``χ²`` (:mod:`bouncedisk.fitting.objective`):

1. a scrambled Sobol design of ``design`` points over every search coordinate (the noise
   included), each read on the joint ``χ²`` of all the data, on the fit's members under the
   provisional covariance;
2. the covariance ``C`` measured at the design's best point (:func:`.search.measure_cov`);
3. pyPESTO's multi-start, ``scipy.optimize.least_squares`` (trust-region reflective) on the
   whitened residuals in the unit box of the search ranges, from the ``starts`` best design
   points under ``C`` (12 steps each, forward-difference Jacobians);
4. ``C`` measured again at the best end point, that point refined once more under it.

and, for comparison, the fit's own search (``fit_curve``'s, the pipeline's settings), reporting
each one's best ``χ²``, the ensembles it evaluated and the ``χ²`` at the generating point
(docs/fitting_method.md "The search").

    python benchmarks/plain_multistart.py [--sizes 128:8,768:16] [--record]

``--record`` writes ``benchmarks/out/fit_plain_multistart.json``.
"""

from __future__ import annotations

import argparse
import math
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pypesto
import pypesto.optimize
from scipy.stats import qmc

from bouncedisk.fitting.core import FitSettings, pose_fit
from bouncedisk.fitting.likelihood_basins import rank_key
from bouncedisk.fitting.objective import Evaluation, Objective
from bouncedisk.fitting.search import (
    DIFF_STEP,
    difference_points,
    measure_cov,
    search,
    waterfall,
)
from bouncedisk.fitting.synthetic import read_spec
from bouncedisk.io.load_curves import read_load_curve
from bouncedisk.io.runup_curves import read_curve


@dataclass(frozen=True)
class MultistartSettings:
    """Sizes of the multi-start search (module docstring)."""

    seed: int = 20261121  # the pipeline's prototype.seed
    design: int = 128  # Sobol points over every coordinate
    starts: int = 8  # local searches, from the design's best points
    members: int = 12  # members per evaluation
    pilot_members: int = 32  # members measuring the covariance C
    local_nfev: int = 12  # least-squares steps per start


@dataclass(frozen=True)
class MultistartResult:
    """The best point and every start's end ``χ²``, best first (the waterfall)."""

    best: Evaluation
    waterfall: np.ndarray
    starts: np.ndarray  # the starts' end points, in waterfall order (search coordinates)


def design_points(obj: Objective, n: int, seed: int) -> list[np.ndarray]:
    """``n`` scrambled Sobol points of the search box (every coordinate; seeded)."""
    with warnings.catch_warnings():
        # any size is allowed; the balance scipy warns about is exact only at powers of two
        warnings.filterwarnings("ignore", "The balance properties of Sobol", UserWarning)
        units = qmc.Sobol(len(obj.names), seed=seed).random(n)
    return [obj.from_unit(u, obj.lo) for u in units]


def _problem(obj: Objective, members: int) -> pypesto.Problem:
    """The pyPESTO problem: whitened residuals and their forward-difference Jacobian in the unit
    box; the Jacobian's points are evaluated together (:meth:`.objective.Objective.prefetch`:
    those sharing ``(e, omega_s, e_sigma)`` share one axial run)."""
    dim = len(obj.names)

    def res(u: np.ndarray) -> np.ndarray:
        x = obj.from_unit(u, obj.lo)
        obj.chi2(x, members)  # logged: the search never returns a worse point than it read
        return obj.residuals(x, members)

    def sres(u: np.ndarray) -> np.ndarray:
        pts = difference_points(u, DIFF_STEP)
        obj.prefetch([obj.from_unit(v, obj.lo) for v in (u, *pts)], members)
        r0 = res(u)
        cols = [
            (obj.residuals(obj.from_unit(v, obj.lo), members) - r0) / (v - u).sum() for v in pts
        ]
        return np.column_stack(cols)

    objective = pypesto.Objective(res=res, sres=sres, x_names=list(obj.names))
    return pypesto.Problem(objective, lb=np.zeros(dim), ub=np.ones(dim))


def local_searches(
    obj: Objective, starts: list[np.ndarray], s: MultistartSettings
) -> list[np.ndarray]:
    """pyPESTO's multi-start from ``starts``: each start's end point (search coordinates; each
    was evaluated, and logged, by the residuals)."""
    problem = _problem(obj, s.members)
    problem.set_x_guesses(np.array([obj.to_unit(x) for x in starts]))
    optimizer = pypesto.optimize.ScipyOptimizer(
        method="ls_trf", options={"maxfun": s.local_nfev}, tol=1e-8
    )
    result = pypesto.optimize.minimize(
        problem,
        optimizer,
        n_starts=len(starts),
        progress_bar=False,
        options=pypesto.optimize.OptimizeOptions(allow_failed_starts=True),
    )
    done = [r for r in result.optimize_result.list if r.x is not None]  # a failed start: none
    return [obj.from_unit(np.clip(r.x, 0.0, 1.0), obj.lo) for r in done]


def multistart(
    obj: Objective, s: MultistartSettings, progress: Callable[[str], None] | None = None
) -> MultistartResult:
    """The whole multi-start search (module docstring); the best logged point at ``s.members``
    under the final covariance, and the waterfall under it."""
    say = progress or (lambda _msg: None)
    design = design_points(obj, s.design, s.seed)
    obj.map(lambda x: obj.chi2(x, s.members), design)
    best = obj.best(s.members)
    say(f"design: {len(design)} points over every coordinate, best chi2 {best.chi2:.4g}")
    obj.set_cov(measure_cov(obj, best.x, s.pilot_members))
    scored = [(obj.chi2_now(x, s.members), x) for x in design]
    scored.sort(key=lambda p: rank_key(p[0], p[1]))
    starts = [x for _, x in scored[: s.starts]]
    say(f"covariance measured at the design's best point; {len(starts)} starts")
    ends = local_searches(obj, starts, s)
    obj.set_cov(measure_cov(obj, obj.best(s.members).x, s.pilot_members))
    local_searches(obj, [obj.best(s.members).x], s)
    falls, points = waterfall(obj, ends, s.members)  # the fit's own waterfall, final covariance
    best = obj.best(s.members)
    say(
        f"multi-start: chi2 {best.chi2:.4g}; starts' ends {np.round(falls, 3)} "
        f"({len(obj.read)} ensembles evaluated)"
    )
    return MultistartResult(best, falls, points)


CURVE, LOAD = "data/prototype/synthetic_motor.csv", "data/prototype/synthetic_motor_load.csv"
SPEC = "workflow/config/synthetic_motor.yaml"


def posed() -> Objective:
    """The pipeline's fit problem: the shipped run-up and load curve, the noise fitted."""
    curve, load = read_curve(CURVE), [read_load_curve(LOAD)]
    return pose_fit(curve, FitSettings(seed=MultistartSettings.seed, cores=2), None, load).obj


def generating(obj: Objective) -> np.ndarray:
    """The shipped motor's generating point in the fit's search coordinates."""
    spec = read_spec(SPEC)
    p = spec["parameters"]
    values = {**p, "log10_r_phi": math.log10(p["r_phi"]), "e_sigma": spec["e_sigma"]}
    return np.array([values[n] for n in obj.names], float)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="128:8,768:16", help="design:starts, comma-separated")
    ap.add_argument("--record", action="store_true")
    args = ap.parse_args()
    rows = []
    for size in args.sizes.split(","):
        design, starts = (int(v) for v in size.split(":"))
        obj, t0 = posed(), time.perf_counter()
        r = multistart(obj, MultistartSettings(design=design, starts=starts), print)
        wall = time.perf_counter() - t0
        truth = obj.chi2_now(generating(obj), MultistartSettings.members)
        rows.append(
            (
                f"plain multi-start, {design} design points, {starts} starts: best chi2 (generating "
                "point), starts within 3.84 of the best, ensembles, wall",
                f"{r.best.chi2:.4g} ({truth:.4g}), {int(np.sum(r.waterfall <= r.best.chi2 + 3.84))}"
                f" of {starts}, {len(obj.read)}, {wall:.0f} s",
            )
        )
    obj, t0 = posed(), time.perf_counter()
    best = search(obj, FitSettings(seed=MultistartSettings.seed, scan=64, zoom=0, cores=2)
                  .for_runs(1).search_settings(), print).best  # fmt: skip
    wall = time.perf_counter() - t0
    truth = obj.chi2_now(generating(obj), MultistartSettings.members)
    rows.append(
        (
            "the fit's staged search (the pipeline's scan 64, zoom 0): best chi2 (generating point), "
            "ensembles, wall",
            f"{best.chi2:.4g} ({truth:.4g}), {len(obj.read)}, {wall:.0f} s",
        )
    )
    for m, r in rows:
        print(f"{m}: {r}")
    if args.record:
        from record import write_record

        title = "A plain multi-start search against the staged search of the fit (shipped motor)"
        print(write_record("fit_plain_multistart", title, rows))


if __name__ == "__main__":
    main()
