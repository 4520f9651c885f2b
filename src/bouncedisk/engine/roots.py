"""Certified first roots of quadratic-plus-harmonic event functions.

Every event function of the bouncing-disk model has the form

.. math::

    f(\\tau) = f_0 + c_1\\tau + c_2\\tau^2 + A(\\cos\\varphi - \\cos\\theta_0)
               + B(\\sin\\varphi - \\sin\\theta_0), \\qquad \\varphi = \\theta_0 + w\\tau,

written in difference form so that :math:`f(0) = f_0` exactly and small departures are free of
cancellation. Examples: the flight gap (docs/model.md "Events", paper eq. 20), the contact slip
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

from . import _cache  # noqa: F401  (the cache locators, before anything here is decorated)

TWO_PI = 2.0 * pi


INV_TWO_PI = 1.0 / TWO_PI


@njit(cache=True, inline="always")
def floor_turns(x: float) -> float:
    """``floor(x / 2π)``, the same as with the division, mostly from a multiplication.

    ``q = x · fl(1/2π)`` and the rounded quotient ``x / 2π`` are both within ``2.1 u |q|`` of the
    exact one (``u = 2⁻⁵³``), so they have the same floor unless ``q`` is within that of an
    integer: only then (``q``'s fraction within ``1e-14 (1 + |q|)`` of 0 or 1, or ``q`` not
    finite) the division is made.
    """
    q = x * INV_TWO_PI
    k = floor(q)
    f = q - k
    tol = 1e-14 * (1.0 + abs(q))
    if tol < f < 1.0 - tol:
        return k
    return floor(x / TWO_PI)


@njit(cache=True, inline="always")
def mod_two_pi(x: float) -> float:
    """Reduce ``x`` to ``[0, 2π)``."""
    r = x - TWO_PI * floor_turns(x)
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
    if a == 0.0 and b == -1.0:
        # a flight's gap: the terms with a = 0 dropped (at most the sign of a zero differs,
        # which no caller reads: f and f' are only compared with 0 when they are 0)
        f = f0 + tau * (c1 + c2 * tau) - ds
        fp = c1 + 2.0 * c2 * tau - w * cp
        fpp = 2.0 * c2 + w * w * sp
        return f, fp, fpp
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
def inflections(a, b, c2, w):
    """Where ``f''`` changes sign: ``(found, δ, β)`` (module docstring).

    ``f'' = 2 c2 − w² amp sin(φ + δ)`` with ``amp = hypot(a, b)`` and ``δ = atan2(a, b)``: it
    vanishes where ``sin(φ + δ) = sin β``, ``β = asin(2 c2 / (w² amp))``. ``found`` is False when
    ``f''`` keeps its sign (``amp = 0`` or ``|2 c2 / w²| >= amp``). The values depend on
    ``a, b, c2, w`` only, so a caller searching several roots of one family (a flight's ascent
    and descent) computes them once.
    """
    amp = hypot(a, b)
    kk = 2.0 * c2 / (w * w)
    if amp > 0.0 and abs(kk) < amp:
        return True, atan2(a, b), asin(kk / amp)
    return False, 0.0, 0.0


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
    found, delta, beta = inflections(a, b, c2, w)
    return first_root_from(f0, c1, c2, a, b, th0, w, t_max, xtol, found, delta, beta)


@njit(cache=True)
def first_root_from(f0, c1, c2, a, b, th0, w, t_max, xtol, found, delta, beta):
    """:func:`first_root` with the inflection data ``(found, δ, β)`` of :func:`inflections`.

    See :func:`first_root_sc`, which this calls with ``sin θ0, cos θ0``.
    """
    if f0 < 0.0:
        return 0.0
    return first_root_sc(
        f0, c1, c2, a, b, th0, sin(th0), cos(th0), w, t_max, xtol, found, delta, beta
    )


#: Relative margin of the shortcuts of :func:`first_root_sc`: a shortcut is taken only when its
#: bound holds by this fraction of the size of the terms (:func:`_sizes`), some 1e5 times the
#: rounding of one evaluation of ``f``. A shortcut changes no result, only skips evaluations.
SHORTCUT_MARGIN = 1e-9


@njit(cache=True, inline="always")
def _sizes(f0, c1, c2, amp, th0, w, tau):
    """``(S_f, S_f')``: sizes of the terms of :func:`hev`'s ``f`` and ``f'`` at ``tau``.

    The rounding of each is at most 16 ``ε`` times its size (``amp = |A| + |B|``; the
    differences ``sin φ − sin θ0``, ``cos φ − cos θ0`` are bounded by ``min(1, h)(1 + h)``
    ``(|θ0| + 6 + 2h)`` ulps, ``h = wτ/2``, which covers the rounding of ``θ0 + h``). Both grow
    with ``tau``, so their values at an interval's end bound those at its start.
    """
    h = 0.5 * w * tau
    trig = (1.0 + h) * (abs(th0) + 6.0 + 2.0 * h)
    s_f = abs(f0) + tau * (abs(c1) + abs(c2) * tau) + amp * min(1.0, h) * trig
    s_p = abs(c1) + 2.0 * abs(c2) * tau + w * amp * (1.0 + trig)
    return s_f, s_p


@njit(cache=True, inline="always")
def no_root(f0, c1, c2, a, b, th0, s0, k0, w, t_max):
    """The first shortcut of :func:`first_root_sc`: ``f > 0`` on ``(0, t_max]`` for certain.

    ``f(τ) >= f0 + f'(0) τ − max(m, 0) t_max τ / 2`` with ``m = w²(|A| + |B|) − 2c2 >= −f''``,
    positive with a margin over the rounding of any evaluation in the window (``f0 >= 0``;
    NaN or an infinite window takes no shortcut). True means the walk would return -1.
    """
    amp = abs(a) + abs(b)
    fp0 = c1 + w * (b * k0 - a * s0)  # f'(0), as the walk computes it
    q = w * w * amp - 2.0 * c2
    if q < 0.0:
        q = 0.0
    hm = 0.5 * w * t_max
    k_size = abs(c1) + abs(c2) * t_max + 0.5 * w * amp * (1.0 + hm) * (abs(th0) + 6.0 + 2.0 * hm)
    s_p0 = abs(c1) + w * amp * (1.0 + (abs(th0) + 6.0))
    slack = fp0 - 0.5 * q * t_max
    return f0 >= 0.0 and slack > SHORTCUT_MARGIN * (s_p0 + k_size + q * t_max + abs(fp0))


@njit(cache=True)
def first_root_sc(f0, c1, c2, a, b, th0, s0, k0, w, t_max, xtol, found, delta, beta):
    """:func:`first_root_from` with ``s0, k0 = sin θ0, cos θ0`` given (``f0 >= 0``).

    The search walks the intervals between consecutive inflection points. ``f''`` is positive
    before an inflection at phase ``φ + δ ≡ β`` (``p1``: ``sin(φ + δ)`` rises through
    ``sin β``) and negative before one at ``φ + δ ≡ π − β`` (``p2``), so each interval is convex
    when the next inflection is a ``p1`` and concave when it is a ``p2``, with no evaluation of
    ``f''``. Without inflections (``found`` False) ``f''`` has one sign, taken at the window's
    middle.

    Two shortcuts skip evaluations whose outcome is certain, so the result is bit for bit the
    one of the plain walk (``tests/test_roots.py``). With ``m >= −f''`` and ``M >= f''``
    everywhere (``m, M = ∓2c2 + w²(|A| + |B|)``):

    - no root in the whole window: ``f(τ) >= f0 + f'(0) τ − max(m, 0) t_max τ / 2 > 0`` with a
      margin over the rounding of every evaluation the walk would make, so each of them would
      be positive and the walk would return -1 (a flight's ascent after an impact);
    - ``f < 0`` at an interval's end: ``f(hi) <= f(lo) + f'(lo) d + M d²/2 < 0`` (``d = hi −
      lo``) with the same margin; the interval's root then depends on the sign of ``f(hi)``
      only, so it is found without evaluating ``f(hi)`` (a flight's descent).
    """
    if no_root(f0, c1, c2, a, b, th0, s0, k0, w, t_max):
        return -1.0
    return first_root_walk(f0, c1, c2, a, b, th0, s0, k0, w, t_max, xtol, found, delta, beta)


@njit(cache=True)
def first_root_walk(f0, c1, c2, a, b, th0, s0, k0, w, t_max, xtol, found, delta, beta):
    """:func:`first_root_sc` after its first shortcut, for a caller that has found
    :func:`no_root` false with these arguments (the same result; the test is not repeated)."""
    per = TWO_PI / w
    amp = abs(a) + abs(b)
    ww = w * w
    lo = 0.0
    flo = f0
    fplo = c1 + w * (b * k0 - a * s0)  # f'(0) (hev at τ = 0 has no trigonometry left)
    m_up = 2.0 * c2 + ww * amp
    p1 = inf
    p2 = inf
    if found:
        p1 = mod_two_pi(beta - delta - th0) / w
        p2 = mod_two_pi(pi - beta - delta - th0) / w
    while True:
        hi = t_max
        if p1 < hi:
            hi = p1
        if p2 < hi:
            hi = p2
        convex = p1 < p2  # the next inflection is a p1 (only read when found and p1 != p2)
        tie = p1 == p2
        if hi == p1:
            p1 += per
        if hi == p2:
            p2 += per
        if hi <= lo:
            if lo >= t_max:
                return -1.0
            continue
        if found and not tie:
            # f(hi) < 0 for certain: the interval's root needs only that sign
            d = hi - lo
            upper = flo + fplo * d + 0.5 * m_up * d * d
            s_f, s_p = _sizes(f0, c1, c2, amp, th0, w, hi)
            size = 2.0 * s_f + s_p * d + abs(flo) + abs(fplo) * d + abs(m_up) * d * d
            if upper < -SHORTCUT_MARGIN * size:
                r = _interval_root(
                    f0, c1, c2, a, b, th0, s0, k0, w, lo, flo, fplo, hi, -1.0, -1.0, convex, xtol
                )
                if r >= 0.0:
                    return r
        fhi, fphi, _fpp = hev(f0, c1, c2, a, b, th0, s0, k0, w, hi)
        if not found or tie:
            _fm, _fpm, fppm = hev(f0, c1, c2, a, b, th0, s0, k0, w, 0.5 * (lo + hi))
            convex = fppm > 0.0
        r = _interval_root(
            f0, c1, c2, a, b, th0, s0, k0, w, lo, flo, fplo, hi, fhi, fphi, convex, xtol
        )
        if r >= 0.0:
            return r
        if hi >= t_max:
            return -1.0
        lo = hi
        flo = fhi
        fplo = fphi
