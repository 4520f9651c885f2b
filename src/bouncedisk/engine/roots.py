"""Certified first roots of quadratic-plus-harmonic event functions.

Every event function of the bouncing-disk model has the form

.. math::

    f(\\tau) = f_0 + c_1\\tau + c_2\\tau^2 + A(\\cos\\varphi - \\cos\\theta_0)
               + B(\\sin\\varphi - \\sin\\theta_0), \\qquad \\varphi = \\theta_0 + w\\tau,

written in difference form so that :math:`f(0) = f_0` exactly and small departures are free of
cancellation. Examples: the flight gap (MODEL.md "Events", paper eq. 20), the contact slip
(eq. 23 corrected) and the stick margins (paper §2.5).

Its second derivative :math:`f'' = 2c_2 - w^2(A\\cos\\varphi + B\\sin\\varphi)` changes sign at
phases known in closed form. Between two such inflection points ``f`` is convex or concave, and a
convex or concave function has a first root that can be isolated exactly from the values and
slopes at the interval ends. So the first root after ``τ = 0`` is found with no risk of
skipping a grazing (tangential) root, and the cost per interval is O(1) evaluations plus a
bracketed Newton solve. No function here allocates.
"""

from math import asin, atan2, cos, floor, hypot, inf, pi, sin

from numba import njit

TWO_PI = 2.0 * pi


@njit(cache=True, inline="always")
def mod_two_pi(x: float) -> float:
    """Reduce ``x`` to ``[0, 2π)``."""
    r = x - TWO_PI * floor(x / TWO_PI)
    if r >= TWO_PI:
        r -= TWO_PI
    if r < 0.0:
        r = 0.0
    return r


@njit(cache=True, inline="always")
def hev(f0, c1, c2, a, b, th0, s0, k0, w, tau):
    """Evaluate ``f, f', f''`` of the difference-form function at ``tau``.

    ``s0, k0`` are ``sin θ0, cos θ0``. Uses ``sin φ − sin θ0 = 2 cos(θ0 + h/2) sin(h/2)`` and
    ``cos φ − cos θ0 = −2 sin(θ0 + h/2) sin(h/2)`` with ``h = wτ``.
    """
    half = 0.5 * w * tau
    sh = sin(half)
    mid = th0 + half
    sm = sin(mid)
    cm = cos(mid)
    ds = 2.0 * cm * sh
    dc = -2.0 * sm * sh
    sp = s0 + ds
    cp = k0 + dc
    f = f0 + tau * (c1 + c2 * tau) + a * dc + b * ds
    fp = c1 + 2.0 * c2 * tau + w * (b * cp - a * sp)
    fpp = 2.0 * c2 - w * w * (a * cp + b * sp)
    return f, fp, fpp


@njit(cache=True)
def bracket_root(f0, c1, c2, a, b, th0, s0, k0, w, lo, hi, xtol):
    """Root of ``f`` in ``[lo, hi]`` with ``f(lo) > 0 >= f(hi)`` (safeguarded Newton).

    The root is unique in the bracket by construction of the callers (``f`` convex or concave
    there). Converges quadratically; falls back to bisection whenever Newton would leave the
    bracket.
    """
    x = 0.5 * (lo + hi)
    for _ in range(300):
        f, fp, _fpp = hev(f0, c1, c2, a, b, th0, s0, k0, w, x)
        if f > 0.0:
            lo = x
        elif f < 0.0:
            hi = x
        else:
            return x
        if fp < 0.0:
            dx = f / fp
            xn = x - dx
            if lo < xn < hi:
                if abs(dx) <= xtol:
                    return xn
                x = xn
                continue
        if hi - lo <= xtol:
            return hi
        x = 0.5 * (lo + hi)
    return hi


@njit(cache=True)
def _deriv_root(f0, c1, c2, a, b, th0, s0, k0, w, lo, hi, xtol, sign):
    """Root of ``sign·f'`` in ``[lo, hi]`` where ``sign·f'`` goes from positive to non-positive."""
    # f'(τ) = f'(0) + 2c2 τ + wB(cos φ − cos θ0) − wA(sin φ − sin θ0)
    d0 = c1 + w * (b * k0 - a * s0)
    return bracket_root(
        sign * d0, sign * 2.0 * c2, 0.0, sign * w * b, -sign * w * a, th0, s0, k0, w, lo, hi, xtol
    )


@njit(cache=True)
def _interval_root(f0, c1, c2, a, b, th0, s0, k0, w, lo, flo, fplo, hi, fhi, fphi, convex, xtol):
    """First root in ``(lo, hi]`` of ``f`` on an interval where it is convex or concave.

    ``flo >= 0`` is assumed. Returns -1.0 when there is none.
    """
    if convex:
        if fplo >= 0.0:
            return -1.0  # convex and not decreasing: f >= f(lo) >= 0
        if fhi <= 0.0:
            if flo <= 0.0:
                return lo
            return bracket_root(f0, c1, c2, a, b, th0, s0, k0, w, lo, hi, xtol)
        if fphi <= 0.0:
            return -1.0  # decreasing throughout, ends positive
        # the minimum is interior: f' increases from negative to positive
        m = _deriv_root(f0, c1, c2, a, b, th0, s0, k0, w, lo, hi, xtol, -1.0)
        fm, _fp, _fpp = hev(f0, c1, c2, a, b, th0, s0, k0, w, m)
        if fm > 0.0:
            return -1.0
        if flo <= 0.0:
            return lo
        if fm == 0.0:
            return m
        return bracket_root(f0, c1, c2, a, b, th0, s0, k0, w, lo, m, xtol)
    # concave: f >= min(f(lo), f(hi)) on the interval
    if fhi > 0.0:
        return -1.0
    if fhi == 0.0 and flo > 0.0:
        return hi
    if flo > 0.0:
        return bracket_root(f0, c1, c2, a, b, th0, s0, k0, w, lo, hi, xtol)
    # f(lo) == 0: a root at lo unless f is departing upwards
    if fplo <= 0.0:
        return lo
    m = _deriv_root(f0, c1, c2, a, b, th0, s0, k0, w, lo, hi, xtol, 1.0)
    fm, _fp, _fpp = hev(f0, c1, c2, a, b, th0, s0, k0, w, m)
    if fm <= 0.0:
        return m
    return bracket_root(f0, c1, c2, a, b, th0, s0, k0, w, m, hi, xtol)


@njit(cache=True)
def first_root(f0, c1, c2, a, b, th0, w, t_max, xtol):
    """First ``τ`` in ``(0, t_max]`` where ``f`` reaches zero from above.

    Parameters
    ----------
    f0, c1, c2, a, b : float
        Coefficients of the difference form (module docstring); ``f0 >= 0``.
    th0 : float
        Stator phase at ``τ = 0``.
    w : float
        Stator angular frequency (nondimensional ``omega_s``).
    t_max : float
        End of the search window.
    xtol : float
        Absolute tolerance on the root.

    Returns
    -------
    float
        The root, or -1.0 if ``f > 0`` on ``(0, t_max]``. A tangential (grazing) root counts.
        ``f0 < 0`` returns 0.0.
    """
    if f0 < 0.0:
        return 0.0
    s0 = sin(th0)
    k0 = cos(th0)
    amp = hypot(a, b)
    kk = 2.0 * c2 / (w * w)
    per = TWO_PI / w
    p1 = inf
    p2 = inf
    if amp > 0.0 and abs(kk) < amp:
        delta = atan2(a, b)
        beta = asin(kk / amp)
        p1 = mod_two_pi(beta - delta - th0) / w
        p2 = mod_two_pi(pi - beta - delta - th0) / w
    lo = 0.0
    flo, fplo, _fpp = hev(f0, c1, c2, a, b, th0, s0, k0, w, 0.0)
    flo = f0
    while True:
        hi = t_max
        if p1 < hi:
            hi = p1
        if p2 < hi:
            hi = p2
        if hi == p1:
            p1 += per
        if hi == p2:
            p2 += per
        if hi <= lo:
            if lo >= t_max:
                return -1.0
            continue
        fhi, fphi, _fpp = hev(f0, c1, c2, a, b, th0, s0, k0, w, hi)
        _fm, _fpm, fppm = hev(f0, c1, c2, a, b, th0, s0, k0, w, 0.5 * (lo + hi))
        r = _interval_root(
            f0, c1, c2, a, b, th0, s0, k0, w, lo, flo, fplo, hi, fhi, fphi, fppm > 0.0, xtol
        )
        if r >= 0.0:
            return r
        if hi >= t_max:
            return -1.0
        lo = hi
        flo = fhi
        fplo = fphi
