"""Independent checks of a run's invariants (docs/model.md), shared by the hard-case and property tests.

They recompute everything from the event table with numpy, without the engine: each free flight
is re-sampled densely to prove that no earlier root of the gap was skipped.
"""

from __future__ import annotations

import numpy as np

from bouncedisk.engine import KIND_IMPACT, RunResult
from bouncedisk.model import stator


def check_events_sane(res: RunResult) -> None:
    """No NaN, times non-decreasing, relative impact velocities non-negative, phases in range."""
    ev = res.events
    for name in ("t", "phase", "v_rel", "omega_after", "omega_before", "u"):
        assert np.all(np.isfinite(ev[name])), f"non-finite {name}"
    assert np.all(np.diff(ev["t"]) >= 0.0), "event times go backwards"
    assert np.all(ev["v_rel"] >= 0.0)
    assert np.all((ev["phase"] >= 0.0) & (ev["phase"] < 2 * np.pi))
    assert np.all(np.abs(ev["u"]) <= 1.0 + 1e-12)


def check_no_skipped_root(
    res: RunResult, e: float, w: float, n_check: int = 2000, samples: int = 400, tol: float = 1e-9
) -> int:
    """Re-sample free flights between consecutive impacts: the rotor must never be below the
    stator by more than ``tol`` before the recorded impact. Returns the number of flights checked.
    """
    ev = res.events
    t, ph, vr, kd = ev["t"], ev["phase"], ev["v_rel"], ev["kind"]
    if len(t) < 2:
        return 0
    v_post = stator.velocity(ph, w) + e * vr
    dt = np.diff(t)
    landing = stator.position(ph[:-1]) + v_post[:-1] * dt - 0.5 * dt**2
    free = (
        (kd[:-1] == KIND_IMPACT)
        & (kd[1:] == KIND_IMPACT)
        & (np.abs(landing - stator.position(ph[1:])) < 1e-6 * (1 + dt**2))
    )
    idx = np.nonzero(free)[0]
    if len(idx) > n_check:
        idx = np.random.default_rng(0).choice(idx, n_check, replace=False)
    frac = np.linspace(0.0, 1.0, samples)[1:-1]
    for k in idx:
        tau = frac * dt[k]
        # stator phase carried from the impact phase, as the engine does
        gap = (
            stator.position(ph[k])
            + v_post[k] * tau
            - 0.5 * tau**2
            - stator.position(ph[k] + w * tau)
        )
        assert gap.min() >= -tol * (1.0 + w * dt[k]), (
            f"flight {k} dips {gap.min():.3e} below the stator before its recorded impact"
        )
    return len(idx)


def check_slip_never_reverses(res: RunResult, r_phi: float, w: float, psi: float) -> None:
    """At every impact ``s⁺`` has the sign of ``s⁻`` (or is zero) and ``|s⁺| <= |s⁻|``."""
    ev = res.events
    sel = ev["kind"] == KIND_IMPACT
    twist = stator.twist_rate(ev["phase"][sel], w, psi)
    s_minus = r_phi * ev["omega_before"][sel] - twist
    s_plus = r_phi * ev["omega_after"][sel] - twist
    scale = 1e-12 * (1.0 + np.abs(r_phi * ev["omega_before"][sel]) + w)
    assert np.all(s_minus * s_plus >= -scale * np.abs(s_minus)), "slip reversed at an impact"
    assert np.all(np.abs(s_plus) <= np.abs(s_minus) + scale), "impact increased the slip"
