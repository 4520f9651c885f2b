"""The nonsmooth laws of the bouncing disk, as small compiled functions (docs/model.md "Events").

Nondimensional throughout (docs/model.md "Variables and scales"): stator ``u_s = sin φ``,
``v_s = w cos φ``, ``a_s = −w² sin φ``, twist rate ``Ω_s = w cos(φ + ψ)``, twist acceleration
``α_s = −w² sin(φ + ψ)``; normal load in contact ``N = 1 + a_s``; slip ``s = RΩ − Ω_s``.
"""

from math import asin, cos, pi, sin, sqrt

from numba import njit

from . import _cache  # noqa: F401  (the cache locators, before anything here is decorated)


@njit(cache=True, inline="always")
def normal_load(w, phase):
    """Normal load in contact ``N = 1 − w² sin φ`` (docs/model.md; paper eq. 17 corrected)."""
    return 1.0 - w * w * sin(phase)


@njit(cache=True, inline="always")
def slip(r, w, psi, omega, phase):
    """Slip ``s = RΩ − Ω_s`` with ``Ω_s = w cos(φ + ψ)`` (docs/model.md; paper eq. 19)."""
    return r * omega - w * cos(phase + psi)


@njit(cache=True)
def impact_law(e, w, r, psi, phase, v_minus, omega, torsion, cap, inertia_factor):
    """Apply restitution and impulsive friction at an impact (paper eqs. 4, 8, 18, 19).

    Parameters
    ----------
    e, w, r, psi : float
        Restitution, stator frequency, angular amplitude ratio ``R``, torsional phase.
    phase : float
        Stator phase at impact.
    v_minus, omega : float
        Rotor axial velocity and angular velocity just before impact.
    torsion, cap : bool
        Whether angular impulses are applied, and whether ``H = min(H_a, H_p)`` (else ``H_a``).
    inertia_factor : float
        ``J_s/(J_s + J_r)`` for the finite-stator-inertia effect (eq. 11), 1 for eq. 19.

    Returns
    -------
    v_rel, v_plus, omega_plus : float
        Relative impact velocity ``v_s − v⁻ >= 0``, ``v⁺ = v_s + e(v_s − v⁻)`` and
        ``Ω⁺ = Ω⁻ − H sgn(s⁻)`` with ``H_a = (1 + e) v_rel`` and ``H_p = |s⁻|/R``.
    """
    return impact_law_sc(
        e, w, r, psi, phase, cos(phase), v_minus, omega, torsion, cap, inertia_factor
    )


@njit(cache=True)
def impact_law_sc(e, w, r, psi, phase, cos_phase, v_minus, omega, torsion, cap, inertia_factor):
    """:func:`impact_law` with ``cos φ`` given (the caller has it already)."""
    vs = w * cos_phase
    v_rel = vs - v_minus
    if v_rel < 0.0:
        v_rel = 0.0
    v_plus = vs + e * v_rel
    omega_plus = omega
    if torsion:
        s = slip(r, w, psi, omega, phase)
        if s != 0.0:
            h_a = (1.0 + e) * v_rel
            h_p = inertia_factor * abs(s) / r
            if cap and h_p <= h_a:
                if inertia_factor == 1.0:
                    # the slip is brought exactly to zero
                    omega_plus = w * cos(phase + psi) / r
                else:
                    omega_plus = omega - h_p * (1.0 if s > 0.0 else -1.0)
            else:
                omega_plus = omega - h_a * (1.0 if s > 0.0 else -1.0)
    return v_rel, v_plus, omega_plus


#: Gap below which a separation is grazing: a flight that stays below it is not taken, the rotor
#: stays in contact (docs/model.md "w ≤ 1"; the limit w → 1⁺).
GRAZE_GAP = 64.0 * 2.220446049250313e-16
#: The rounding of a position near the top of the stator's stroke (one ulp of 1.0): a chattering
#: sequence whose bounces all stay below it cannot be resolved bounce by bounce.
ROUND_GAP = 2.220446049250313e-16
#: Stators with ``1 < w < 1 + NEAR_ONE`` barely lift the rotor off (its flight after a separation
#: rises less than about 1e-8): there a landing comes at nearly zero load and its chattering
#: sequence is accumulated once its bounces fall below ``ROUND_GAP`` (:func:`chatter_time`).
NEAR_ONE = 1e-3


@njit(cache=True)
def chatter_time(e, w, phase, w_rel, tol):
    """Time to the accumulation point of a complete chattering sequence, or -1.

    After an impact leaving relative velocity ``W = e v_rel``, bounces on a locally constant
    effective gravity ``N0`` take ``2 e^k W / N0`` and accumulate after
    ``T = 2 W / (N0 (1 − e))`` (docs/model.md "Chattering"; Nordmark & Piiroinen 2009). The jump is
    taken when ``N`` stays positive over ``T`` and the neglected variation of ``N`` changes the
    accumulation time by less than ``tol``: ``(|N'| + w⁴T) T² / (N0 (1 − e²)) <= tol``.

    Near ``w = 1⁺`` (``w < 1 + NEAR_ONE``) the rotor lands just after the short separation
    window, at a load ``N0 ~ 1e-6``, and that test fails until the bounces are far below the
    rounding of a position (``v_rel ~ 1e-14``, 4e-8 apart): the sequence then ended in contact
    with no chatter event, while at ``w = 1 + 1e-5`` it was accumulated. There
    the jump is also taken once every bounce stays below the rounding of a position: the first
    (highest) one rises ``W² / (2 N_min) <= ROUND_GAP``, ``N_min`` the least load over ``T``.
    So as ``w → 1⁺`` every cycle is separate, land, accumulate, ride; and below the grazing
    limit (:data:`GRAZE_GAP`) the rotor rests.
    """
    return chatter_time_sc(e, w, sin(phase), cos(phase), w_rel, tol)


@njit(cache=True)
def chatter_time_sc(e, w, sin_phase, cos_phase, w_rel, tol):
    """:func:`chatter_time` with ``sin φ, cos φ`` given (the caller has them already)."""
    if e >= 1.0 or w_rel <= 0.0:
        return -1.0
    n0 = 1.0 - w * w * sin_phase  # normal_load(w, phase)
    if n0 <= 0.0:
        return -1.0
    t = 2.0 * w_rel / (n0 * (1.0 - e))
    n1 = abs(w * w * w * cos_phase)
    w4 = w * w * w * w
    n_min = n0 - n1 * t - 0.5 * w4 * t * t
    if n_min <= 0.0:
        return -1.0
    if (n1 + w4 * t) * t * t > tol * n0 * (1.0 - e * e):
        if w - 1.0 >= NEAR_ONE or w_rel * w_rel > 2.0 * ROUND_GAP * n_min:
            return -1.0
    return t


@njit(cache=True)
def separation_phase(w):
    """Phase ``θ_sep = arcsin(1/w²)`` at which contact ends (``N = 0``, decreasing); -1 if ``w <= 1``."""
    if w <= 1.0:
        return -1.0
    return asin(1.0 / (w * w))


@njit(cache=True)
def separation_window(w):
    """Flight through the window where ``N < 0`` right after a separation.

    From the separation point (``u = 1/w²``, ``v = w cos θ_sep``) the gap is convex while
    ``N < 0``, i.e. for phases in ``(θ_sep, π − θ_sep)``; so it stays positive there and the first
    impact search can start at the window's end. Returns the window's duration ``T``, the gap
    ``g = T (v_sep − T/2)`` and the rotor velocity ``v_sep − T`` at its end.
    """
    ts = asin(1.0 / (w * w))
    # cos θ_sep computed without cancellation from (w² − 1)(w² + 1)/w⁴
    wm1 = w - 1.0
    c = sqrt(wm1 * (w + 1.0) * (w * w + 1.0)) / (w * w)
    t = (pi - 2.0 * ts) / w
    v_sep = w * c
    g = t * (v_sep - 0.5 * t)
    return t, g, v_sep - t


@njit(cache=True, inline="always")
def slip_omega(omega0, sigma, w, th0, tau, load):
    """Rotor angular velocity while slipping, eq. (23) corrected, with a load torque.

    ``Ω(τ) = Ω0 − σ [τ + (v_s(τ) − v_s(0))] − τ_L τ`` with ``v_s = w cos φ``, written in difference
    form (docs/model.md "Stick–slip transitions"; "The motor under load": eq. 23 gains ``− τ_L τ``).
    """
    half = 0.5 * w * tau
    dv = -2.0 * w * sin(th0 + half) * sin(half)
    if load == 0.0:
        return omega0 - sigma * (tau + dv)
    return omega0 - sigma * (tau + dv) - load * tau


@njit(cache=True, inline="always")
def slip_omega_integral(omega0, sigma, w, th0, tau, load):
    """``∫_0^τ Ω dτ'`` while slipping: the integral of :func:`slip_omega` (eq. 23 corrected).

    ``Ω0 τ − σ [τ²/2 + (u_s(τ) − u_s(0)) − v_s(0) τ] − τ_L τ²/2`` with ``u_s = sin φ``,
    ``v_s = w cos φ``.
    """
    half = 0.5 * w * tau
    du = 2.0 * cos(th0 + half) * sin(half)
    total = omega0 * tau - sigma * (0.5 * tau * tau + du - w * cos(th0) * tau)
    if load == 0.0:
        return total
    return total - 0.5 * load * tau * tau


@njit(cache=True, inline="always")
def loaded_omega(omega0, load, tau):
    """``Ω(τ) = Ω0 − τ_L τ`` with no friction: flight, or the clipped model's unloaded ride
    (docs/model.md "The motor under load": ``Ω' = −τ_L``)."""
    if load == 0.0:
        return omega0
    return omega0 - load * tau


@njit(cache=True, inline="always")
def loaded_omega_integral(omega0, load, tau):
    """``∫_0^τ Ω dτ' = Ω0 τ − τ_L τ²/2`` of :func:`loaded_omega`."""
    if load == 0.0:
        return omega0 * tau
    return omega0 * tau - 0.5 * load * tau * tau


@njit(cache=True, inline="always")
def stick_omega_integral(w, r, psi, th0, tau):
    """``∫_0^τ Ω dτ'`` while sticking, ``RΩ = Ω_s = w cos(φ + ψ)``: ``(φ_s(τ) − φ_s(0))/R``."""
    half = 0.5 * w * tau
    return 2.0 * cos(th0 + psi + half) * sin(half) / r


@njit(cache=True, inline="always")
def stick_margin_shift(r, load):
    """``R τ_L``: the load's share of the stick condition ``|α_s + R τ_L| <= ρ R N``
    (docs/model.md "The motor under load": the friction must supply ``α_s/R + τ_L``)."""
    return r * load


# --- the energy audit (docs/model.md "The motor under load", "Power and energy audit") ------------
# Closed forms of the audit's integrals over one segment of length L that starts at phase th0
# (φ = th0 + w τ), each in difference form: dsin(x, h) = sin(x + h) − sin(x) etc.


@njit(cache=True, inline="always")
def dsin(x, h):
    """``sin(x + h) − sin(x)`` without cancellation."""
    return 2.0 * cos(x + 0.5 * h) * sin(0.5 * h)


@njit(cache=True, inline="always")
def dcos(x, h):
    """``cos(x + h) − cos(x)`` without cancellation."""
    return -2.0 * sin(x + 0.5 * h) * sin(0.5 * h)


@njit(cache=True, inline="always")
def contact_axial_work(w, th0, length):
    """Stator's work on a rotor riding it, ``∫ N v_s dt = Δu_s + Δ(v_s²/2)`` (units ``m_r g U0``).

    ``N v_s = (1 + a_s) v_s`` and ``a_s v_s = d(v_s²/2)/dt``: the work is the change of the
    riding rotor's energy ``E_ax = v²/2 + u`` (docs/model.md "Power and energy audit").
    """
    h = w * length
    du = dsin(th0, h)
    dc = dcos(th0, h)
    c0 = cos(th0)
    # Δ(w² cos²φ / 2) = w² (cos φ1 − cos φ0)(cos φ1 + cos φ0) / 2
    return du + 0.5 * w * w * dc * (dc + 2.0 * c0)


@njit(cache=True, inline="always")
def slip_twist_work(sigma, w, r, psi, th0, length):
    """Stator's torsional input while slipping, ``W_t = ∫ f Ω_s/R dt`` with ``f = −σN``.

    ``∫ N Ω_s dt = Δ sin(φ + ψ) + (w²/4) Δ cos(2φ + ψ) + (w³ L / 2) sin ψ`` (``N = 1 − w² sin φ``,
    ``Ω_s = w cos(φ + ψ)``); units of ``Ω²/2`` (docs/model.md "Power and energy audit").
    """
    h = w * length
    n_os = dsin(th0 + psi, h) + 0.25 * w * w * dcos(2.0 * th0 + psi, 2.0 * h)
    n_os += 0.5 * w * w * h * sin(psi)
    return -sigma * n_os / r


@njit(cache=True, inline="always")
def slip_load_omega_integral(omega0, sigma, w, th0, length, load):
    """``∫ N Ω dt`` over a slip segment (``N = 1 − w² sin φ``, Ω from :func:`slip_omega`).

    With ``Ω = A + Bτ − σ w cos φ``, ``A = Ω0 + σ w cos θ0``, ``B = −(σ + τ_L)``:
    ``A L + B L²/2 − σ Δsin φ + A w Δcos φ + B w L cos φ1 − B Δsin φ + σ (w²/2) Δ sin²φ``.
    """
    h = w * length
    s0 = sin(th0)
    c0 = cos(th0)
    ds = dsin(th0, h)
    dc = dcos(th0, h)
    a = omega0 + sigma * w * c0
    b = -(sigma + load)
    total = a * length + 0.5 * b * length * length - sigma * ds + a * w * dc
    total += b * w * length * (c0 + dc) - b * ds + 0.5 * sigma * w * w * ds * (ds + 2.0 * s0)
    return total


@njit(cache=True, inline="always")
def stick_twist_work(w, r, psi, load, th0, length):
    """Stator's torsional input while sticking, ``f = α_s/R + τ_L``:
    ``W_t = Δ(Ω_s²/2)/R² + τ_L Δφ_s / R`` (docs/model.md "The motor under load")."""
    h = w * length
    x = th0 + psi
    dc = dcos(x, h)
    work = 0.5 * w * w * dc * (dc + 2.0 * cos(x)) / (r * r)
    if load != 0.0:
        work += load * dsin(x, h) / r
    return work
