"""Stator kinematics and normal load: the one numpy copy (docs/model.md "Variables and scales").

The stator moves as prescribed (paper eq. 1, nondimensional): axial ``u_s = sin(w t)``,
``v_s = w cos(w t)``, ``a_s = −w² sin(w t)``; twist ``φ_s = sin(w t + ψ)``,
``Ω_s = w cos(w t + ψ)`` (``α_s`` is needed by the compiled kernel only). The normal load in
contact is ``N = 1 + a_s`` (eq. 17, corrected in docs/model.md).

Every function takes the stator phase ``θ = w t`` (the engine records events by their phase), so
a caller with a time passes ``w * t``. A Python ``float`` goes through :mod:`math` (fast in
scalar loops such as a ``solve_ivp`` right-hand side), anything else through numpy. All code
outside the compiled engine uses this module; compiled code (the kernel, the Moreau–Jean
comparator) uses :mod:`bouncedisk.engine.laws`.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "acceleration",
    "normal_load",
    "position",
    "twist",
    "twist_rate",
    "velocity",
]


def _phase(x):
    """A Python scalar as it is; anything else (list, tuple, array) as a float array."""
    return x if type(x) is float or type(x) is int else np.asarray(x, dtype=float)


def _sin(x):
    return math.sin(x) if type(x) is float or type(x) is int else np.sin(x)


def _cos(x):
    return math.cos(x) if type(x) is float or type(x) is int else np.cos(x)


def position(theta: ArrayLike) -> float | np.ndarray:
    """Stator axial displacement ``u_s = sin θ`` (eq. 1)."""
    return _sin(theta)


def velocity(theta: ArrayLike, w: float) -> float | np.ndarray:
    """Stator axial velocity ``v_s = w cos θ`` (eq. 1, differentiated)."""
    return w * _cos(theta)


def acceleration(theta: ArrayLike, w: float) -> float | np.ndarray:
    """Stator axial acceleration ``a_s = −w² sin θ`` (eq. 1, differentiated twice)."""
    return -(w * w * _sin(theta))


def normal_load(theta: ArrayLike, w: float) -> float | np.ndarray:
    """Contact load ``N = 1 + a_s`` in units of ``m_r g`` (eq. 17); contact needs ``N >= 0``."""
    return 1.0 + acceleration(theta, w)


def twist(theta: ArrayLike, psi: float) -> float | np.ndarray:
    """Stator twist ``φ_s = sin(θ + ψ)`` (eq. 1), in units of ``Φ0``."""
    return _sin(_phase(theta) + psi)


def twist_rate(theta: ArrayLike, w: float, psi: float) -> float | np.ndarray:
    """Stator angular velocity ``Ω_s = w cos(θ + ψ)`` (eq. 1, differentiated)."""
    return w * _cos(_phase(theta) + psi)
