"""Comparator solvers for the accuracy study: what users would otherwise write.

- ``rk45``, ``dop853``, ``lsoda``: :func:`scipy.integrate.solve_ivp` on the gap dynamics
  ``z'' = −1 + w² sin(wt)`` (``z = u − u_s``) with a terminal event at ``z = 0``, restarted after
  each impact with the restitution law (eq. 4). Tolerances ``rtol = tol``, ``atol = tol/10``.
- ``moreau``: Moreau–Jean time-stepping with fixed step ``h`` (θ = 1/2, Newton impact law at the
  velocity level), the standard nonsmooth scheme (as in Siconos).

Both resolve the axial motion (effects ``impacts`` and ``contact``) and stop bouncing when the
relative impact velocity falls below ``v_rest`` (a user's rest threshold): they have no chattering
accumulation. Torsion is not supported. Results come back in the engine's event format.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.integrate import solve_ivp

from ..engine import laws
from ..engine.driver import Chunk, EngineError, RunResult
from ..io.records import RunStatus, StrobeColumn, TrajColumn
from ..model import stator
from ..model.errors import InputError
from ..model.scene import Scene

IVP_METHODS = {"rk45": "RK45", "dop853": "DOP853", "lsoda": "LSODA"}
TWO_PI = 2.0 * math.pi


def _check(scene: Scene) -> None:
    if scene.has("torsion"):
        raise InputError(
            scene.source,
            "solver.method",
            f"{scene.solver.method!r} supports the axial motion only; remove "
            "'torsion' from effects or use solver.method: exact",
        )
    if scene.outputs.trajectory is not None or scene.outputs.stroboscopic:
        raise InputError(
            scene.source, "outputs", f"{scene.solver.method!r} writes events only (no trajectory)"
        )
    if scene.solver.method == "moreau" and scene.solver.step is None:
        raise InputError(scene.source, "solver.step", "is required by the Moreau–Jean scheme")


def _gap_state(w: float, t0: float, u0: float | None, v0: float | None) -> tuple[float, float]:
    """Gap ``z = u − u_s`` and its rate at ``t0`` (0, 0 for a rotor riding the stator)."""
    if u0 is None:
        return 0.0, 0.0
    return u0 - stator.position(w * t0), v0 - stator.velocity(w * t0, w)


def _separation_after(t: float, w: float) -> float:
    """First time >= t where the contact load 1 − w² sin(wt) turns negative (inf if never)."""
    if w <= 1.0:
        return math.inf
    ts = laws.separation_phase(w)
    ph = w * t
    k = math.floor((ph - ts) / TWO_PI) + 1
    return (ts + TWO_PI * k) / w


def ivp_events(
    e: float,
    w: float,
    method: str,
    tol: float,
    t0: float,
    u0: float | None,
    v0: float | None,
    max_events: int,
    t_end: float = math.inf,
    contact: bool = True,
    v_rest: float = 1e-9,
) -> tuple[dict, int]:
    """Impacts from restarted :func:`~scipy.integrate.solve_ivp` runs (module docstring)."""
    rtol, atol = tol, tol * 0.1

    def rhs(t, y):
        """Gap dynamics in flight: ``z'' = −1 − a_s = −1 + w² sin(wt)`` (docs/model.md "Flight")."""
        return [y[1], -1.0 - stator.acceleration(w * t, w)]

    def gap(t, y):
        """Impact event: the gap ``z = u − u_s`` reaches 0 from above (eq. 20)."""
        return y[0]

    gap.terminal = True
    gap.direction = -1.0
    t = t0
    in_contact = u0 is None
    z, zd = _gap_state(w, t0, u0, v0)
    ts, vrel = [], []
    status = RunStatus.EVENTS
    while len(ts) < max_events:
        if in_contact:
            if not contact:
                return _pack(ts, vrel, w), RunStatus.NEED_CONTACT
            t = _separation_after(t, w)
            if not math.isfinite(t) or t > t_end:
                status = RunStatus.REST if not math.isfinite(t) else RunStatus.TIME
                break
            z, zd = 0.0, 0.0
            in_contact = False
            # the gap is convex just after separation: step off the root before restarting
            t_start = t
        else:
            t_start = t
        span = min(t_end, t_start + 1e3)
        # leave the root at the start: the first step is tiny, the event direction excludes it
        try:
            sol = solve_ivp(
                rhs,
                (t_start, span),
                [z, zd],
                method=IVP_METHODS[method],
                rtol=rtol,
                atol=atol,
                events=gap,
                first_step=min(1e-6, 0.1 * tol**0.5) or None,
            )
        except ValueError:
            # solve_ivp's event search fails on bounces below its resolution: call it rest
            in_contact = True
            if w <= 1.0:
                status = RunStatus.REST
                break
            continue
        if sol.status == 1 and len(sol.t_events[0]):
            t = float(sol.t_events[0][0])
            zd_minus = float(sol.y_events[0][0][1])
            v = -zd_minus
            ts.append(t)
            vrel.append(max(v, 0.0))
            if e * v <= v_rest or v <= v_rest:
                in_contact = True
                continue
            z, zd = 0.0, e * v
        else:
            status = RunStatus.TIME
            break
    return _pack(ts, vrel, w), status


def _no_traj() -> np.ndarray:
    """Comparators sample no trajectory: zero rows of the engine's columns."""
    return np.empty((0, len(TrajColumn)))


def _no_strobe() -> np.ndarray:
    """Comparators sample no stroboscopic section: zero rows of the engine's columns."""
    return np.empty((0, len(StrobeColumn)))


def _pack(ts, vrel, w) -> dict:
    t = np.asarray(ts, float)
    n = len(t)
    return {
        "t": t,
        "phase": np.mod(w * t, TWO_PI),
        "v_rel": np.asarray(vrel, float),
        "omega_after": np.zeros(n),
        "omega_before": np.zeros(n),
        "u": stator.position(w * t),
        "kind": np.zeros(n, dtype=np.int8),
    }


@njit(cache=True)
def _moreau_kernel(e, w, h, t0, z0, zd0, max_events, t_end, v_rest, out_t, out_v):
    """Moreau–Jean (θ = 1/2) on the gap z, zd with the Newton law 0 <= zd⁺ + e zd⁻ ⊥ p >= 0."""
    t = t0
    z = z0
    zd = zd0
    n = 0
    was_active = False
    steps = 0
    max_steps = int((t_end - t0) / h) + 1 if t_end < 1e300 else 1 << 62
    while n < max_events and steps < max_steps:
        # free velocity: zd'' = −1 + w² sin(wt), midpoint force
        tm = t + 0.5 * h
        f = -laws.normal_load(w, w * tm)  # = −1 − a_s
        zd_free = zd + h * f
        z_pred = z + 0.5 * h * zd  # predicted gap at mid-step
        active = z_pred <= 0.0
        if active:
            target = -e * zd if zd < 0.0 else 0.0
            zd_new = zd_free if zd_free >= target else target
            if zd < -v_rest and not was_active:
                out_t[n] = t + h
                out_v[n] = -zd
                n += 1
        else:
            zd_new = zd_free
        z = z + 0.5 * h * (zd + zd_new)
        zd = zd_new
        was_active = active
        t += h
        steps += 1
    return n, t


def moreau_events(
    e: float,
    w: float,
    h: float,
    t0: float,
    u0: float | None,
    v0: float | None,
    max_events: int,
    t_end: float = math.inf,
    v_rest: float = 1e-9,
) -> tuple[dict, int]:
    """Impacts from Moreau–Jean time-stepping with step ``h`` (module docstring)."""
    z0, zd0 = _gap_state(w, t0, u0, v0)
    out_t = np.empty(max_events)
    out_v = np.empty(max_events)
    cap_t = t_end if math.isfinite(t_end) else t0 + 50.0 * max_events * (1.0 + 1.0 / w)
    n, _t = _moreau_kernel(e, w, h, t0, z0, zd0, max_events, cap_t, v_rest, out_t, out_v)
    status = RunStatus.EVENTS if n >= max_events else RunStatus.TIME
    return _pack(out_t[:n], out_v[:n], w), status


def simulate_comparator(scene: Scene) -> RunResult:
    """Run a scene with its comparator solver, in memory."""
    _check(scene)
    p = scene.params
    i = scene.initial
    max_ev = scene.stop.impacts if scene.stop.impacts is not None else scene.stop.max_events
    t_end = scene.stop.time if scene.stop.time is not None else math.inf
    if scene.solver.method == "moreau":
        ev, status = moreau_events(p.e, p.omega_s, scene.solver.step, i.t, i.u, i.v, max_ev, t_end)
    else:
        ev, status = ivp_events(
            p.e,
            p.omega_s,
            scene.solver.method,
            scene.solver.tol,
            i.t,
            i.u,
            i.v,
            max_ev,
            t_end,
            contact=scene.has("contact"),
        )
    return RunResult(ev, _no_traj(), _no_strobe(), status.text, int(status))


def iterate_comparator(scene: Scene):
    """The comparator's run as one engine-format chunk (generator, like the engine's)."""
    res = simulate_comparator(scene)
    ev = res.events
    if res.status_code == RunStatus.NEED_CONTACT:
        raise EngineError(RunStatus.NEED_CONTACT.text, RunStatus.NEED_CONTACT)
    if len(ev["t"]):
        yield Chunk(
            t=ev["t"],
            phase=ev["phase"],
            v_rel=ev["v_rel"],
            omega_after=ev["omega_after"],
            u=ev["u"],
            omega_before=ev["omega_before"],
            kind=ev["kind"],
            traj=_no_traj(),
            strobe=_no_strobe(),
            n_events_total=len(ev["t"]),
            t_now=float(ev["t"][-1]),
        )
    t_last = float(ev["t"][-1]) if len(ev["t"]) else scene.initial.t
    return res.status_code, {
        "t": t_last,
        "u": math.nan,
        "v": math.nan,
        "omega": 0.0,
        "in_contact": 0.0,
    }
