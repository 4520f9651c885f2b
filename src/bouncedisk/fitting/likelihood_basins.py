"""Acceptable basins of a fit and the rule that picks the reported one: round-off cannot move it.

A synthetic likelihood of a chaotic model is rugged (periodic windows): several separate regions
of the parameter space may reproduce the data about equally well. Which of them a search reports
must not hang on the last bits of a sum (docs/user_guide/reproducible.md):

* every candidate ranking uses :func:`rank_key`: ``χ²`` rounded to :data:`CHI2_DIGITS`
  significant digits, ties going to the smaller point in coordinate order — a total order that
  does not depend on the order points were evaluated in (threads) or on last-bit differences;
* :func:`list_basins` groups every evaluated point within the interval threshold of the best into
  basins (points within :data:`SEPARATION` of a basin's best point, as a fraction of every
  coordinate's range, belong to it), best first by :func:`rank_key`. The rule: the fit reports
  the first. With more than one basin the data do not single one out, and the fit file lists each
  (parameters, ``χ²``) and says so.

Reusable by any likelihood over the same search coordinates (a joint fit of several data kinds):
it needs the evaluated points, their ``χ²`` under one metric, the ranges and the threshold.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Significant digits of ``χ²`` that rank candidates; beyond them a tie goes to the point order.
CHI2_DIGITS = 10
#: Two acceptable points are in different basins if some coordinate differs by more than this
#: fraction of its search range (the search's own separation of distinct candidates).
SEPARATION = 0.05


def rank_key(chi2: float, x: np.ndarray) -> tuple:
    """Sort key of a candidate: ``χ²`` to :data:`CHI2_DIGITS` digits, then the coordinates."""
    c = float(chi2)
    rounded = float(f"{c:.{CHI2_DIGITS - 1}e}") if np.isfinite(c) else float("inf")
    return (rounded, *(float(v) for v in np.asarray(x, float)))


def ranked(chi2: np.ndarray, xs: np.ndarray) -> np.ndarray:
    """Indices of the candidates ``(chi2[i], xs[i])`` best first, by :func:`rank_key`."""
    return np.array(sorted(range(len(chi2)), key=lambda i: rank_key(chi2[i], xs[i])), dtype=int)


@dataclass(frozen=True)
class Basin:
    """One acceptable region: its best point, that point's ``χ²`` and how many points it holds."""

    x: np.ndarray
    chi2: float
    points: int


def list_basins(
    xs: np.ndarray, chi2: np.ndarray, span: np.ndarray, threshold: float
) -> list[Basin]:
    """The basins of the points within ``threshold`` of the lowest ``χ²``, best first.

    Points are taken best first (:func:`ranked`); each joins the first basin whose best point is
    within :data:`SEPARATION` of it in every coordinate (as a fraction of ``span``), or opens a
    new basin.
    """
    xs = np.atleast_2d(np.asarray(xs, float))
    chi2 = np.asarray(chi2, float)
    if len(chi2) == 0:
        return []
    ok = chi2 <= float(np.min(chi2)) + threshold
    xs, chi2 = xs[ok], chi2[ok]
    best: list[int] = []
    count: list[int] = []
    for i in ranked(chi2, xs):
        for b, j in enumerate(best):
            if np.max(np.abs(xs[i] - xs[j]) / span) <= SEPARATION:
                count[b] += 1
                break
        else:
            best.append(int(i))
            count.append(1)
    return [Basin(xs[j].copy(), float(chi2[j]), n) for j, n in zip(best, count, strict=True)]
