"""Where the fit's search loses a tuning motor's generating basin: each stage's points against the truth.

Run:  python benchmarks/search_trace.py --seed S --motors N --motor K [--second-voltage F]
          [--second-drive F] [--scan N] [--scan-noise S] [--cores 2]

Draws tuning motor ``K`` of ``benchmarks/validation_motors.py``'s design with another seed
(``--seed`` is required: the validation motors are never traced), makes its run-up and load
curves as that benchmark does, and runs the default joint fit with the search's stages
(:mod:`bouncedisk.fitting.search`) wrapped to report, for each stage:

- the scan (run-ups alone): the rank of the scan point nearest the truth in ``(e, omega_s)``
  (box units) and its ``chi2``, the best point's, and the truth's own ``chi2`` on the same
  data and members;
- the joint candidates, the re-ranking and the starts' ends: the distance of the nearest to the
  truth and the best ``chi2``, against the truth's under the covariance then;
- at the re-ranking, with the noise fitted, the truth read with its ``e_sigma`` set to each of
  :data:`TRUTH_NOISE` (how sharp the likelihood is in the noise at the truth).

``--scan-noise`` runs the scan at another stated noise than the fit's (a diagnosis: does the
scan see the truth's basin at that noise?).

A stage that keeps a point near the truth while a later one drops it names the stage that loses
the basin; a truth whose ``chi2`` is below every candidate's names a basin the scan never
reached.
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np
import validation_motors as vm

from bouncedisk.fitting import FitSettings, core, fit_curve
from bouncedisk.fitting import search as S
from bouncedisk.io.load_curves import read_load_curve
from bouncedisk.io.runup_curves import read_curve

TRUTH: dict[str, float] = {}
#: Restitution noise levels at which the re-ranking stage also reads the truth (the other
#: coordinates the generating ones): how sharp the likelihood is in the noise there.
TRUTH_NOISE = (0.0, 0.001, 0.01, 0.03)


def truth_x(obj) -> np.ndarray:
    """The generating point in the objective's coordinates."""
    return np.array([TRUTH[n] for n in obj.names], dtype=float)


def quiet_chi2(obj, x: np.ndarray, members: int) -> float:
    """``chi2`` at ``x`` neither logged nor counted as one of the fit's evaluations."""
    read = set(obj.read)
    value = obj.chi2_now(x, members)
    obj.read.intersection_update(read)
    return value


def wrapped(angle: float) -> float:
    """An angle difference in (-pi, pi]."""
    return float(-((-angle + math.pi) % (2 * math.pi) - math.pi))


def axial_distance(obj, x: np.ndarray) -> float:
    """Distance from the truth in ``(e, omega_s)``, in units of the search box."""
    i = [obj.names.index("e"), obj.names.index("omega_s")]
    return float(np.linalg.norm((x[i] - truth_x(obj)[i]) / obj.span[i]))


def nearest(obj, xs) -> tuple[int, float]:
    """Index and axial distance of the point of ``xs`` nearest the truth."""
    d = [axial_distance(obj, x) for x in xs]
    k = int(np.argmin(d))
    return k, d[k]


def near_scan(obj, ranked, s) -> None:
    """The scan point nearest the truth, as the candidate stage receives it: whether it
    reproduces the run-ups (:func:`~bouncedisk.fitting.uncertainty.scan_acceptable`), its
    ``(psi, log10 R_phi)`` against the truth's, and its joint ``chi2`` as it is, with ``R_phi``
    matched to the load curve, and with the truth's ``(psi, R_phi)``."""
    from bouncedisk.fitting.uncertainty import scan_acceptable

    k, d = nearest(obj, [ev.x for ev in ranked])
    x = ranked[k].x
    ok = any(np.array_equal(x, y) for y in scan_acceptable(obj, s.global_members))
    t = truth_x(obj)
    i = [obj.names.index(n) for n in ("psi", "log10_r_phi")]
    given = x.copy()
    given[i] = t[i]
    chis = [quiet_chi2(obj, y, s.global_members) for y in (x, S.load_matched(obj, x), given)]
    say("near", f"rank {k} at {d:.3f}: run-ups reproduced {ok}; psi, log10 R_phi "
        f"{x[i[0]]:.3f}, {x[i[1]]:.3f} (truth {t[i[0]]:.3f}, {t[i[1]]:.3f}; psi off by "
        f"{abs(wrapped(x[i[0]] - t[i[0]])):.3f} rad); joint chi2 "
        f"{chis[0]:.4g}, R_phi matched {chis[1]:.4g}, the truth's psi and R_phi {chis[2]:.4g}")  # fmt: skip


def say(stage: str, text: str) -> None:
    """Print one stage's line."""
    print(f"[{stage}] {text}", flush=True)


def wrap() -> None:
    """Wrap the search's stages (module docstring) to print what each keeps."""
    scan, cands, rerank, local = S.global_stage, S.joint_candidates, S.rerank, S.local_stage

    def global_stage(obj, s, progress=None):
        """The stage, then what it kept."""
        ranked = scan(obj, s, progress)
        k, d = nearest(obj, [ev.x for ev in ranked])
        truth = quiet_chi2(obj, truth_x(obj), s.global_members)
        say("scan", f"{len(ranked)} one-member evaluations; nearest the truth: rank {k} at {d:.3f} "
            f"chi2 {ranked[k].chi2:.4g}; best {ranked[0].chi2:.4g}; truth {truth:.4g}")  # fmt: skip
        return ranked

    def joint_candidates(obj, ranked, s, progress=None):
        """The stage, then what it kept."""
        near_scan(obj, ranked, s)
        out = cands(obj, ranked, s, progress)
        k, d = nearest(obj, out)
        truth = quiet_chi2(obj, truth_x(obj), s.global_members)
        best = min(quiet_chi2(obj, x, s.global_members) for x in out)
        say("candidates", f"{len(out)}; nearest the truth: #{k} at {d:.3f}; best joint chi2 "
            f"{best:.4g}; truth {truth:.4g} ({s.global_members} member)")  # fmt: skip
        return out

    def rerank_(obj, cs, s):
        """The stage, then what it kept, and the truth read at each of :data:`TRUTH_NOISE`."""
        scores = rerank(obj, cs, s)
        k, d = nearest(obj, cs)
        truth = quiet_chi2(obj, truth_x(obj), s.members)
        say("rerank", f"nearest #{k} at {d:.3f} chi2 {scores[k]:.4g}; best {min(scores):.4g}; "
            f"truth {truth:.4g} ({s.members} members)")  # fmt: skip
        if "e_sigma" in obj.names:
            j, read = obj.names.index("e_sigma"), []
            for level in TRUTH_NOISE:
                x = truth_x(obj)
                x[j] = level
                read.append(f"{level:g}: {quiet_chi2(obj, x, s.members):.4g}")
            say("truth noise", "the truth's chi2 with its e_sigma set to " + ", ".join(read))
        return scores

    def local_stage(obj, starts, members, nfev, progress=None):
        """The stage, then what it kept."""
        best, ends = local(obj, starts, members, nfev, progress)
        k, d = nearest(obj, starts)
        ke, de = nearest(obj, ends)
        truth = quiet_chi2(obj, truth_x(obj), members)
        say("local", f"{len(starts)} starts, nearest at {d:.3f}; ends nearest at {de:.3f} "
            f"(chi2 {quiet_chi2(obj, ends[ke], members):.4g}); best {best.chi2:.4g} at "
            f"{axial_distance(obj, best.x):.3f}; truth {truth:.4g}")  # fmt: skip
        return best, ends

    S.global_stage, S.joint_candidates, S.rerank, S.local_stage = (
        global_stage, joint_candidates, rerank_, local_stage)  # fmt: skip


def main() -> None:
    """Trace one tuning motor's fit (module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--seed", type=int, required=True, help="a tuning draw (never the validation's)"
    )
    ap.add_argument("--motors", type=int, default=8, help="size of the draw")
    ap.add_argument("--motor", type=int, required=True, help="the motor traced")
    ap.add_argument("--second-voltage", type=float, default=None)
    ap.add_argument("--second-drive", type=float, default=None)
    ap.add_argument("--scan", type=int, default=FitSettings.scan)
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument(
        "--scan-noise",
        type=float,
        default=None,
        help="the restitution noise the scan runs at (default the fit's stated one)",
    )
    args = ap.parse_args()
    if args.scan_noise is not None:
        if not 0.0 <= args.scan_noise <= 0.1:
            ap.error(f"--scan-noise: {args.scan_noise}: between 0 and 0.1 (the search's range)")
        core.MODEL_E_SIGMA = args.scan_noise  # read by pose_fit: the scan's stated noise
    if args.seed == vm.VALIDATION_SEED:
        ap.error("--seed: the validation motors are not traced")
    m = vm.draw(args.motors, args.seed)[args.motor]
    TRUTH.update({**vm._theta(m), "e_sigma": m["e_sigma"]})  # as recover() reads the truth
    conditions = vm.conditions_from(args.second_drive, args.second_voltage)
    wrap()
    with tempfile.TemporaryDirectory() as tmp:
        run, loads = vm.make_data(Path(tmp), m, args.motor, conditions)
        settings = FitSettings(seed=vm.FIT_SEED, cores=args.cores, scan=args.scan)
        fit = fit_curve(read_curve(run), settings, load=[read_load_curve(x) for x in loads])
    say("fit", f"chi2 {fit.chi2:.4g}; truth {TRUTH}")


if __name__ == "__main__":
    main()
