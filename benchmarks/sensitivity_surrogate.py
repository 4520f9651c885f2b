"""Can a smooth surrogate resolve the study's total indices? Polynomial chaos on its points.

A Legendre polynomial-chaos expansion of total degree ``p`` in the study's four parameters
(scaled to [-1, 1]), fitted by least squares to a points file (``results/sensitivity/points.nc``),
gives every Sobol' index in closed form from its coefficients (Sudret, Reliab. Eng. Syst. Saf. 93,
964, 2008). Its indices are only as good as the expansion: the leave-one-out error
``mean(LOO residual²) / var(y)`` (closed form from the hat matrix) is the share of each output's
variance the expansion does not predict, and an index can be off by up to that share.

Run:  python benchmarks/sensitivity_surrogate.py [results/sensitivity/points.nc]
      [--config workflow/config/config.yaml] [--degrees 3 5 7]

Prints, per output and degree, the number of terms, the leave-one-out error and the expansion's
first-order and total indices. Measured on the default pipeline's 768 points (docs/user_guide/
sensitivity.md, "Why not a surrogate"): the smallest leave-one-out error of any output is 0.35
(no-load speed, degree 5), 0.44–0.63 for the others, and it grows with the degree (over-fitting):
the outputs are not smooth in the parameters (regime changes), so a smooth surrogate does not
resolve their indices.
"""

from __future__ import annotations

import argparse
import itertools

import numpy as np
import xarray as xr
import yaml
from numpy.polynomial import legendre

from bouncedisk.studies.sensitivity_settings import PARAMETERS, study_settings


def basis(u: np.ndarray, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal Legendre products of total degree ``<= degree`` at ``u`` (points, d) in
    [-1, 1]: the design matrix and the multi-indices (terms, d)."""
    d = u.shape[1]
    index = np.array(
        [m for m in itertools.product(range(degree + 1), repeat=d) if sum(m) <= degree]
    )
    eye = np.eye(degree + 1)
    one_d = [np.stack([legendre.legval(u[:, j], eye[k]) * np.sqrt(2 * k + 1)
                       for k in range(degree + 1)], axis=1) for j in range(d)]  # fmt: skip
    cols = [np.prod([one_d[j][:, m[j]] for j in range(d)], axis=0) for m in index]
    return np.column_stack(cols), index


def expansion(u: np.ndarray, y: np.ndarray, degree: int) -> dict:
    """Least-squares expansion of ``y``: leave-one-out error and the indices ``S1``, ``ST``."""
    a, index = basis(u, degree)
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    hat = np.einsum("ij,ji->i", a, np.linalg.pinv(a))
    loo = (y - a @ coef) / (1.0 - hat)
    var = float(np.var(y))
    c2 = coef**2
    c2[0] = 0.0  # the mean
    only = [(index[:, j] > 0) & (index.sum(axis=1) == index[:, j]) for j in range(u.shape[1])]
    return {"terms": len(index), "loo": float(np.mean(loo**2)) / var,
            "S1": [float(c2[m].sum()) / var for m in only],
            "ST": [float(c2[index[:, j] > 0].sum()) / var for j in range(u.shape[1])]}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("points", nargs="?", default="results/sensitivity/points.nc")
    ap.add_argument("--config", default="workflow/config/config.yaml", help="its ranges")
    ap.add_argument("--degrees", type=int, nargs="+", default=[3, 5, 7])
    args = ap.parse_args()
    with open(args.config, encoding="utf-8") as f:
        settings = study_settings(yaml.safe_load(f))
    with xr.open_dataset(args.points) as ds:
        x = ds["x"].values
        outputs = [o for o in str(ds.attrs["outputs"]).split(",") if o]
        ys = {o: ds[o].values for o in outputs}
    lo, hi = np.array([settings.ranges[n] for n in PARAMETERS]).T
    u = 2.0 * (x - lo) / (hi - lo) - 1.0
    print(f"{len(x)} points; leave-one-out error, S1 and ST per parameter")
    for o in outputs:
        for p in args.degrees:
            r = expansion(u, ys[o], p)
            print(f"{o:24s} degree {p} ({r['terms']:3d} terms): LOO {r['loo']:.3f}  "
                  f"S1 {np.round(r['S1'], 3)}  ST {np.round(r['ST'], 3)}")  # fmt: skip


if __name__ == "__main__":
    main()
