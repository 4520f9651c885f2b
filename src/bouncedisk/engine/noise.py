"""Counter-based random numbers for the ``restitution_noise`` effect (docs/model.md "Long-run statistics").

Member ``m`` of an ensemble with seed ``S`` gets, at its ``k``-th event, the standard normal
``ξ_k = normal(member_key(S, m), k)``: a pure function of ``(S, m, k)``, so a member's noise does
not depend on how many members run, in which order, or on how many cores. The generator is the
SplitMix64 finalizer (Steele, Lea & Flood, "Fast splittable pseudorandom number generators",
OOPSLA 2014) applied to a counter, and Box–Muller for the normal deviate.
"""

from math import cos, log, sqrt

import numpy as np
from numba import njit

from . import _cache  # noqa: F401  (the cache locators, before anything here is decorated)
from .roots import TWO_PI

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_TO_UNIT = 1.0 / 9007199254740992.0  # 2**-53


@njit(cache=True, inline="always")
def _mix64(x):
    """SplitMix64 finalizer: a bijective scrambling of a 64-bit word."""
    z = x
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


@njit(cache=True)
def member_key(seed, member):
    """The 64-bit stream key of ensemble member ``member`` under ``seed`` (both ``>= 0``)."""
    k = _mix64(np.uint64(seed) * _GOLDEN + np.uint64(0x632BE59BD9B4E019))
    return _mix64(k ^ (np.uint64(member) * _GOLDEN + _GOLDEN))


@njit(cache=True, inline="always")
def _unit(key, counter):
    """Uniform deviate in ``(0, 1)`` (53 bits) for ``counter`` in stream ``key``."""
    z = _mix64(key + np.uint64(counter) * _GOLDEN)
    return ((z >> np.uint64(11)) + 0.5) * _TO_UNIT


@njit(cache=True)
def normal(key, k):
    """Standard normal deviate ``ξ_k`` of stream ``key`` (Box–Muller on counters ``2k, 2k+1``)."""
    u1 = _unit(key, 2 * k)
    u2 = _unit(key, 2 * k + 1)
    return sqrt(-2.0 * log(u1)) * cos(TWO_PI * u2)


@njit(cache=True)
def noisy_restitution(e, e_sigma, key, k):
    """Restitution of the ``k``-th event, ``e_k = e + σ_e ξ_k`` clipped to ``[0, 1]`` (docs/model.md)."""
    ek = e + e_sigma * normal(key, k)
    if ek < 0.0:
        return 0.0
    if ek > 1.0:
        return 1.0
    return ek
