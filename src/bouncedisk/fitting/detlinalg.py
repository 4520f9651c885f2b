"""Small dense linear algebra in a fixed order of operations: the same bits on every machine.

LAPACK and BLAS (``np.linalg``, ``@``) sum in an order that depends on the kernel OpenBLAS picks
for a CPU (AVX-512, AVX2, …) and on its thread count, so their results differ in the last bits
between machines; in a fit a last-bit difference can choose another basin
(docs/user_guide/reproducible.md). The fit's matrices are tiny (the statistics' covariance, 11 × 11; the Jacobian,
11 × 5), so everything here is plain Python arithmetic on IEEE doubles with exactly rounded sums
(:func:`math.fsum`): correctly rounded, hence independent of summation order, vectorization and
threads. Used by the objective (:mod:`.objective`), the profiles (:mod:`.uncertainty`) and any
likelihood built on them.
"""

from __future__ import annotations

import math

import numpy as np


def dot(a: np.ndarray, b: np.ndarray) -> float:
    """``Σ a_i b_i``, exactly rounded (:func:`math.fsum` of the products)."""
    return math.fsum((np.asarray(a, float) * np.asarray(b, float)).tolist())


def matvec(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``A x`` row by row with :func:`dot`."""
    a = np.atleast_2d(np.asarray(a, float))
    return np.array([dot(row, x) for row in a])


def gram(j: np.ndarray) -> np.ndarray:
    """``Jᵀ J`` (symmetric, every entry one :func:`dot`)."""
    j = np.asarray(j, float)
    n = j.shape[1]
    out = np.empty((n, n))
    for p in range(n):
        for q in range(p, n):
            out[p, q] = out[q, p] = dot(j[:, p], j[:, q])
    return out


def cholesky(c: np.ndarray) -> np.ndarray:
    """Lower-triangular ``L`` with ``L Lᵀ = C`` (Cholesky–Banachiewicz).

    Raises
    ------
    numpy.linalg.LinAlgError
        ``C`` is not positive definite.
    """
    c = np.asarray(c, float)
    n = len(c)
    low = np.zeros((n, n))
    for i in range(n):
        for k in range(i + 1):
            s = math.fsum([float(c[i, k])] + [-float(low[i, m] * low[k, m]) for m in range(k)])
            if i == k:
                if not s > 0.0:
                    raise np.linalg.LinAlgError("matrix is not positive definite")
                low[i, i] = math.sqrt(s)
            else:
                low[i, k] = s / low[k, k]
    return low


def log_det(low: np.ndarray) -> float:
    """``log det C`` from the Cholesky factor ``L`` of ``C`` (:func:`cholesky`): ``2 Σ log L_ii``,
    summed exactly rounded."""
    return 2.0 * math.fsum(np.log(np.diag(np.asarray(low, float))).tolist())


def lower_inverse(low: np.ndarray) -> np.ndarray:
    """``L⁻¹`` of a lower-triangular ``L`` by forward substitution."""
    low = np.asarray(low, float)
    n = len(low)
    inv = np.zeros((n, n))
    for col in range(n):
        for i in range(col, n):
            s = math.fsum(
                [1.0 if i == col else 0.0]
                + [-float(low[i, m] * inv[m, col]) for m in range(col, i)]
            )
            inv[i, col] = s / low[i, i]
    return inv


def sym_eig(a: np.ndarray, sweeps: int = 60) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending) and eigenvectors (columns) of a symmetric matrix (cyclic Jacobi).

    The drop-in for :func:`numpy.linalg.eigh` on the fit's small matrices; rotations in a fixed
    order until every off-diagonal entry is negligible against its diagonal pair.
    """
    a = np.array(a, float)
    n = len(a)
    v = np.eye(n)
    for _ in range(sweeps):
        rotated = False
        for p in range(n - 1):
            for q in range(p + 1, n):
                apq = float(a[p, q])
                if apq == 0.0 or abs(apq) <= 1e-300 + 2.2e-16 * 1e-3 * math.sqrt(
                    abs(float(a[p, p]) * float(a[q, q]))
                ):
                    a[p, q] = a[q, p] = 0.0
                    continue
                rotated = True
                theta = (float(a[q, q]) - float(a[p, p])) / (2.0 * apq)
                t = math.copysign(1.0, theta) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                ap, aq = a[:, p].copy(), a[:, q].copy()
                a[:, p], a[:, q] = c * ap - s * aq, s * ap + c * aq
                ap, aq = a[p, :].copy(), a[q, :].copy()
                a[p, :], a[q, :] = c * ap - s * aq, s * ap + c * aq
                vp, vq = v[:, p].copy(), v[:, q].copy()
                v[:, p], v[:, q] = c * vp - s * vq, s * vp + c * vq
        if not rotated:
            break
    w = np.diag(a).copy()
    order = np.argsort(w, kind="stable")
    return w[order], v[:, order]


def pinv_sym(a: np.ndarray, rcond: float) -> np.ndarray:
    """Pseudo-inverse of a symmetric positive semi-definite matrix: eigenvalues at most
    ``rcond`` times the largest are dropped."""
    w, v = sym_eig(a)
    keep = w > rcond * max(float(w.max()), 0.0)
    out = np.zeros_like(v)
    for k in np.flatnonzero(keep):
        out += np.outer(v[:, k], v[:, k]) / w[k]
    return out


def pinv(m: np.ndarray, rcond: float) -> np.ndarray:
    """Pseudo-inverse of a tall matrix ``M`` (singular values at most ``rcond`` times the
    largest dropped): ``(Mᵀ M)⁺ Mᵀ``."""
    m = np.asarray(m, float)
    inner = pinv_sym(gram(m), rcond * rcond)
    return np.array([[dot(inner[i], m[r]) for r in range(m.shape[0])] for i in range(m.shape[1])])
