"""The certified first-root search (engine/roots.py) against closed forms and brute force."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from bouncedisk.engine.roots import (
    TWO_PI,
    first_root,
    floor_turns,
    inflections,
)


def f_eval(f0, c1, c2, a, b, th0, w, tau):
    ph = th0 + w * tau
    return (
        f0
        + c1 * tau
        + c2 * tau**2
        + a * (np.cos(ph) - math.cos(th0))
        + b * (np.sin(ph) - math.sin(th0))
    )


def test_linear_root():
    assert first_root(1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 10.0, 1e-14) == pytest.approx(
        1.0, abs=1e-14
    )


def test_parabola_on_resting_stator_lands_at_2v():
    # gap of a rotor launched at v = 0.7 from a stator at rest (A = B = 0): root 2v
    r = first_root(0.0, 0.7, -0.5, 0.0, 0.0, 0.0, 1.0, 10.0, 1e-14)
    assert r == pytest.approx(1.4, abs=1e-13)


def test_tangential_root_is_found():
    # f = 1 - sin(τ) touches zero at π/2 without crossing (grazing)
    r = first_root(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 10.0, 1e-14)
    assert r == pytest.approx(math.pi / 2, abs=1e-7)


def test_near_miss_is_not_a_root_but_near_hit_is():
    assert first_root(1.0 + 1e-10, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 3.0, 1e-14) == -1.0
    r = first_root(1.0 - 1e-10, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 3.0, 1e-14)
    assert abs(r - math.pi / 2) < 2e-5 and r < math.pi / 2


def test_first_of_many_roots_at_high_frequency():
    # f = 0.999 - sin(100 τ) has roots every period; the first is at asin(0.999)/100
    r = first_root(0.999, 0.0, 0.0, 0.0, -1.0, 0.0, 100.0, 50.0, 1e-15)
    assert r == pytest.approx(math.asin(0.999) / 100.0, abs=1e-13)


def test_departing_start_is_not_a_root():
    # f(0) = 0 with f'(0) > 0: the root at 0 is ignored, the next one is returned
    r = first_root(0.0, 1.0, -0.5, 0.0, 0.0, 0.0, 1.0, 5.0, 1e-14)
    assert r == pytest.approx(2.0, abs=1e-13)


@given(
    f0=st.floats(0.0, 2.0),
    c1=st.floats(-5.0, 5.0),
    c2=st.floats(-2.0, 0.5),
    a=st.floats(-3.0, 3.0),
    b=st.floats(-3.0, 3.0),
    th0=st.floats(0.0, 2 * math.pi),
    w=st.floats(0.05, 30.0),
)
def test_no_root_is_skipped(f0, c1, c2, a, b, th0, w):
    """Against a dense scan: nothing below zero before the returned root, and f(root) ≈ 0."""
    t_max = 6.0
    r = first_root(f0, c1, c2, a, b, th0, w, t_max, 1e-13)
    tau = np.linspace(0.0, t_max, 200_001)[1:]
    f = f_eval(f0, c1, c2, a, b, th0, w, tau)
    scale = 1.0 + abs(f0) + abs(c1) * t_max + abs(c2) * t_max**2 + abs(a) + abs(b)
    if r < 0:
        assert f.min() > -1e-9 * scale
    else:
        before = tau < r * (1 - 1e-9) - 1e-12
        if before.any():
            assert f[before].min() > -1e-9 * scale
        assert abs(f_eval(f0, c1, c2, a, b, th0, w, r)) < 1e-8 * scale


@given(
    c2=st.floats(-2.0, 0.5),
    a=st.floats(-3.0, 3.0),
    b=st.floats(-3.0, 3.0),
    w=st.floats(0.05, 30.0),
)
def test_curvature_is_positive_before_p1_and_negative_before_p2(c2, a, b, w):
    """The rule first_root_from uses in place of sampling f'': convex before an inflection
    ``φ + δ ≡ β`` (p1), concave before ``φ + δ ≡ π − β`` (p2), one sign when there is none."""
    found, delta, beta = inflections(a, b, c2, w)

    def fpp(phi):
        return 2.0 * c2 - w * w * (a * np.cos(phi) + b * np.sin(phi))

    phis = np.linspace(0.0, 2 * math.pi, 4001)
    if not found:
        vals = fpp(phis)
        scale = abs(2.0 * c2) + w * w * (abs(a) + abs(b)) + 1e-300
        assert vals.min() >= -1e-12 * scale or vals.max() <= 1e-12 * scale
        return
    p1, p2 = beta - delta, math.pi - beta - delta
    amp = math.hypot(a, b)
    assert abs(fpp(p1)) <= 1e-9 * w * w * (amp + abs(2 * c2 / (w * w)))
    assert abs(fpp(p2)) <= 1e-9 * w * w * (amp + abs(2 * c2 / (w * w)))
    gap = (p2 - p1) % (2 * math.pi)  # p1 -> p2 concave, p2 -> p1 convex
    if min(gap, 2 * math.pi - gap) < 1e-3:
        return  # inflections too close together to sample between them
    inside = p1 + gap * np.linspace(0.05, 0.95, 19)
    outside = p2 + (2 * math.pi - gap) * np.linspace(0.05, 0.95, 19)
    assert (fpp(inside) < 0.0).all() and (fpp(outside) > 0.0).all()


# --- the shortcuts of first_root_sc change no result ------------------------------------------
# The walk as it was before the shortcuts (evaluating f at every interval's end, hev with every
# term, the reduction of a phase by a division): the engine's first root must be this one's,
# bit for bit.


@njit(cache=False)
def _plain_mod(x):
    r = x - TWO_PI * math.floor(x / TWO_PI)
    if r >= TWO_PI:
        r -= TWO_PI
    if r < 0.0:
        r = 0.0
    return r


@njit(cache=False)
def _plain_hev(f0, c1, c2, a, b, th0, s0, k0, w, tau):
    """``roots.hev`` as it was (no shortcut for a flight's gap)."""
    half = 0.5 * w * tau
    sh = math.sin(half)
    mid = th0 + half
    sm = math.sin(mid)
    cm = math.cos(mid)
    ds = 2.0 * cm * sh
    dc = -2.0 * sm * sh
    sp = s0 + ds
    cp = k0 + dc
    f = f0 + tau * (c1 + c2 * tau) + a * dc + b * ds
    fp = c1 + 2.0 * c2 * tau + w * (b * cp - a * sp)
    fpp = 2.0 * c2 - w * w * (a * cp + b * sp)
    return f, fp, fpp


@njit(cache=False)
def _plain_bracket(f0, c1, c2, a, b, th0, s0, k0, w, lo, hi, xtol):
    x = 0.5 * (lo + hi)
    for _ in range(300):
        f, fp, _fpp = _plain_hev(f0, c1, c2, a, b, th0, s0, k0, w, x)
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


@njit(cache=False)
def _plain_interval(f0, c1, c2, a, b, th0, s0, k0, w, lo, flo, fplo, hi, fhi, fphi, convex, xtol):
    if convex:
        if fplo >= 0.0:
            return -1.0
        if fhi <= 0.0:
            if flo <= 0.0:
                return lo
            return _plain_bracket(f0, c1, c2, a, b, th0, s0, k0, w, lo, hi, xtol)
        if fphi <= 0.0:
            return -1.0
        d0 = c1 + w * (b * k0 - a * s0)
        m = _plain_bracket(-d0, -2.0 * c2, 0.0, -w * b, w * a, th0, s0, k0, w, lo, hi, xtol)
        fm, _fp, _fpp = _plain_hev(f0, c1, c2, a, b, th0, s0, k0, w, m)
        if fm > 0.0:
            return -1.0
        if flo <= 0.0:
            return lo
        if fm == 0.0:
            return m
        return _plain_bracket(f0, c1, c2, a, b, th0, s0, k0, w, lo, m, xtol)
    if fhi > 0.0:
        return -1.0
    if fhi == 0.0 and flo > 0.0:
        return hi
    if flo > 0.0:
        return _plain_bracket(f0, c1, c2, a, b, th0, s0, k0, w, lo, hi, xtol)
    if fplo <= 0.0:
        return lo
    d0 = c1 + w * (b * k0 - a * s0)
    m = _plain_bracket(d0, 2.0 * c2, 0.0, w * b, -w * a, th0, s0, k0, w, lo, hi, xtol)
    fm, _fp, _fpp = _plain_hev(f0, c1, c2, a, b, th0, s0, k0, w, m)
    if fm <= 0.0:
        return m
    return _plain_bracket(f0, c1, c2, a, b, th0, s0, k0, w, m, hi, xtol)


@njit(cache=False)
def _plain_first_root(f0, c1, c2, a, b, th0, w, t_max, xtol):
    if f0 < 0.0:
        return 0.0
    found, delta, beta = inflections(a, b, c2, w)
    s0 = math.sin(th0)
    k0 = math.cos(th0)
    per = TWO_PI / w
    p1 = math.inf
    p2 = math.inf
    if found:
        p1 = _plain_mod(beta - delta - th0) / w
        p2 = _plain_mod(math.pi - beta - delta - th0) / w
    lo = 0.0
    flo = f0
    fplo = c1 + w * (b * k0 - a * s0)
    while True:
        hi = t_max
        if p1 < hi:
            hi = p1
        if p2 < hi:
            hi = p2
        convex = p1 < p2
        tie = p1 == p2
        if hi == p1:
            p1 += per
        if hi == p2:
            p2 += per
        if hi <= lo:
            if lo >= t_max:
                return -1.0
            continue
        fhi, fphi, _fpp = _plain_hev(f0, c1, c2, a, b, th0, s0, k0, w, hi)
        if not found or tie:
            _fm, _fpm, fppm = _plain_hev(f0, c1, c2, a, b, th0, s0, k0, w, 0.5 * (lo + hi))
            convex = fppm > 0.0
        r = _plain_interval(
            f0, c1, c2, a, b, th0, s0, k0, w, lo, flo, fplo, hi, fhi, fphi, convex, xtol
        )
        if r >= 0.0:
            return r
        if hi >= t_max:
            return -1.0
        lo = hi
        flo = fhi
        fplo = fphi


def _same_bits(x: float, y: float) -> bool:
    return np.float64(x).tobytes() == np.float64(y).tobytes()


@given(
    d0=st.floats(1e-12, 20.0),
    th0=st.floats(0.0, 2 * math.pi, exclude_max=True),
    w=st.floats(0.5, 200.0),
    frac=st.floats(0.0, 3.0),
    tol=st.sampled_from([1e-12, 1e-9, 1e-14]),
)
@settings(max_examples=600, deadline=None)
def test_a_flights_ascent_is_skipped_only_when_the_walk_finds_nothing(d0, th0, w, frac, tol):
    """A gap that starts at zero and opens at ``d0`` (after an impact), searched up to around
    where the whole-window shortcut stops holding (``d0/(1 + w²)``)."""
    v = w * math.cos(th0) + d0
    t_max = frac * d0 / (1.0 + w * w) + 1e-15
    args = (0.0, v, -0.5, 0.0, -1.0, th0, w, t_max, tol)
    assert _same_bits(first_root(*args), _plain_first_root(*args))


@given(
    g0=st.floats(0.0, 2.0),
    v=st.floats(-20.0, 0.0),
    th0=st.floats(0.0, 2 * math.pi, exclude_max=True),
    w=st.floats(0.5, 20.0),
    t_max=st.floats(1e-6, 20.0),
    tol=st.sampled_from([1e-12, 1e-9]),
)
@settings(max_examples=600, deadline=None)
def test_a_flights_descent_finds_the_walks_root(g0, v, th0, w, t_max, tol):
    """A falling rotor: the shortcut that takes ``f(hi) < 0`` from a bound."""
    args = (g0, v, -0.5, 0.0, -1.0, th0, w, t_max, tol)
    assert _same_bits(first_root(*args), _plain_first_root(*args))


@given(
    f0=st.floats(0.0, 3.0),
    c1=st.floats(-5.0, 5.0),
    c2=st.floats(-2.0, 0.5),
    a=st.floats(-3.0, 3.0),
    b=st.floats(-3.0, 3.0),
    th0=st.floats(0.0, 2 * math.pi, exclude_max=True),
    w=st.floats(0.05, 100.0),
    t_max=st.floats(1e-9, 30.0),
)
@settings(max_examples=600, deadline=None)
def test_every_family_finds_the_walks_root(f0, c1, c2, a, b, th0, w, t_max):
    """Any quadratic-plus-harmonic function (slip, stick margins): the same root, bit for bit."""
    args = (f0, c1, c2, a, b, th0, w, t_max, 1e-12)
    assert _same_bits(first_root(*args), _plain_first_root(*args))


@njit(cache=False)
def _floor_mismatches(x):
    bad = 0
    for v in x:
        if floor_turns(v) != math.floor(v / TWO_PI):
            bad += 1
    return bad


def test_floor_turns_is_the_floor_of_the_division():
    rng = np.random.default_rng(3)
    k = rng.integers(-(10**7), 10**7, 200_000).astype(float)
    near = k * TWO_PI
    for x in (
        rng.uniform(-1e3, 1e3, 200_000),
        rng.uniform(-1e15, 1e15, 200_000),
        near,
        np.nextafter(near, np.inf),
        np.nextafter(near, -np.inf),
        near * (1 + rng.normal(0, 1e-15, len(near))),
        np.array([0.0, -0.0, 1e300, -1e300, 5e-324]),
    ):
        assert _floor_mismatches(x) == 0
