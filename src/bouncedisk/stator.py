"""Closed-form stator kinematics (paper eq. 1, nondimensional; MODEL.md "Variables").

Axial: ``u_s = sin(wt)``, ``v_s = w cos(wt)``, ``a_s = −w² sin(wt)``. Torsional:
``φ_s = sin(wt + ψ)``, ``Ω_s = w cos(wt + ψ)``, ``α_s = −w² sin(wt + ψ)``. Normal load in contact
``N = 1 + a_s`` (eq. 17, corrected). These numpy versions serve analysis and plotting; the engine
inlines the same formulas.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def position(t: ArrayLike, w: float) -> np.ndarray:
    """Stator axial displacement ``u_s(t) = sin(w t)``."""
    return np.sin(w * np.asarray(t, dtype=float))


def velocity(t: ArrayLike, w: float) -> np.ndarray:
    """Stator axial velocity ``v_s(t) = w cos(w t)``."""
    return w * np.cos(w * np.asarray(t, dtype=float))


def acceleration(t: ArrayLike, w: float) -> np.ndarray:
    """Stator axial acceleration ``a_s(t) = −w² sin(w t)``."""
    return -(w**2) * np.sin(w * np.asarray(t, dtype=float))


def twist_rate(t: ArrayLike, w: float, psi: float) -> np.ndarray:
    """Stator angular velocity ``Ω_s(t) = w cos(w t + ψ)``."""
    return w * np.cos(w * np.asarray(t, dtype=float) + psi)


def twist_acceleration(t: ArrayLike, w: float, psi: float) -> np.ndarray:
    """Stator angular acceleration ``α_s(t) = −w² sin(w t + ψ)``."""
    return -(w**2) * np.sin(w * np.asarray(t, dtype=float) + psi)


def normal_load(t: ArrayLike, w: float) -> np.ndarray:
    """Contact load ``N = 1 + a_s`` (units of ``m_r g``); contact is possible only where ``N >= 0``."""
    return 1.0 + acceleration(t, w)
