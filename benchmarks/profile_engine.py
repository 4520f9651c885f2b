"""Where the engine's time goes per impact (axial, omega_s = 1.5, e = 0.3), by timing its parts.

Run:  python benchmarks/profile_engine.py [--events N] [--repeat R] [--record]

numba's machine code has no per-line profile, so each part of an impact is timed alone over the
states of a recorded run, in a compiled loop where every call's input depends on the previous
call's result (the event loop is one dependency chain: an impact's phase starts the next
flight's search, so what counts is latency, not throughput):

- the flight's search (:func:`~bouncedisk.engine.kernel._flight_root`), and within it the
  certified root's safeguarded Newton (:func:`~bouncedisk.engine.roots.bracket_root`) on the
  same brackets; root bracketing is the difference (ascent test, the descent's start and its
  sine and cosine, inflection phases, shortcuts, the impact phase's reduction);
- the impact law with the sine and cosine of the impact phase and the chattering test;
- the event row (:func:`~bouncedisk.engine.kernel._record_event`, off the chain);
- bookkeeping is what the kernel (:func:`~bouncedisk.engine.kernel.run_chunk` writing into
  reused buffers) takes beyond these; output the run's fresh arrays and the driver
  (:func:`~bouncedisk.engine.simulate_arrays` beyond the kernel).

The floor is the latency of the chain's libm calls, square root and divisions alone: per impact
the sine and cosine of the impact phase and of the descent's start, a square root, and per
Newton step a sine, a sine-and-cosine and a division (the measured mean number of steps). Times
are CPU times, the median of interleaved repetitions; on a loaded machine read the shares.
"""

from __future__ import annotations

import argparse
import statistics
import time
from math import cos, pi, sin, sqrt

import numpy as np
from numba import njit

from bouncedisk.engine import EngineConfig, simulate_arrays
from bouncedisk.engine import kernel as K
from bouncedisk.engine import roots as R
from bouncedisk.engine.driver import InitialState, _pack, initial_state

W, E, TOL = 1.5, 0.3, 1e-12


@njit
def _descents(u0, v0, th0, w, infl):
    """The descent of each flight (all rise above u = 1 here): ``(g, v, θ, sin θ, cos θ, t_max,
    bracket end)`` as :func:`~bouncedisk.engine.kernel._flight_root` computes them."""
    _found, dl, bt = infl
    out = np.empty((u0.shape[0], 7))
    for i in range(u0.shape[0]):
        disc = sqrt(v0[i] * v0[i] - 2.0 * (1.0 - u0[i]))
        _k, ph2 = K._advance(0, th0[i], w * (v0[i] + disc))
        t_max = 4.0 / (sqrt(disc * disc + 4.0) + disc) * (1.0 + 1e-12) + 1e-12
        p1 = R.mod_two_pi(bt - dl - ph2) / w
        p2 = R.mod_two_pi(pi - bt - dl - ph2) / w
        out[i] = (1.0 - sin(ph2), -disc, ph2, sin(ph2), cos(ph2), t_max, min(t_max, p1, p2))
    return out


@njit
def _search_chain(u0, v0, th0, s0, c0, w, infl):
    z = 0.0
    for i in range(u0.shape[0]):
        tau = K._flight_root(u0[i], v0[i] + z, th0[i], s0[i], c0[i], 0.0, 0.0, w, TOL, infl)[0]
        z = 0.0 * tau
    return z


@njit
def _newton_chain(d, w):
    z = 0.0
    for i in range(d.shape[0]):
        g, v, th, s, c, _t, hi = d[i]
        r = R.bracket_root(g, v + z, -0.5, 0.0, -1.0, th, s, c, w, 0.0, hi, TOL)
        z = 0.0 * r
    return z


@njit
def _law_chain(ph, v_minus, w, e):
    z = 0.0
    for i in range(ph.shape[0]):
        p = ph[i] + z
        out = K._impact_sc(
            e, e, w, 0.01, 0.0, p, sin(p), cos(p), v_minus[i], 0.0, False, True, 1.0, TOL
        )
        z = 0.0 * (out[1] + out[4])
    return z


@njit
def _rows(ev, evk, ist, info, t, ph, v_rel):
    for i in range(t.shape[0]):
        if info[K.O_EVENTS] >= evk.shape[0]:
            info[K.O_EVENTS] = 0
        K._record_event(ev, evk, ist, info, t[i], ph[i], v_rel[i], 0.0, 0.0, K.KIND_IMPACT)


@njit
def _floor_chain(th0, d, w, steps):
    """The chain's libm calls and divisions alone, ``steps`` Newton steps per impact (mean)."""
    z = 0.0
    owed = 0.0
    for i in range(th0.shape[0]):
        p = th0[i] + z
        s, c = sin(p), cos(p)
        q = d[i, 2] + 1e-300 * sqrt(2.0 + s * c)
        s2, c2 = sin(q), cos(q)
        x = 0.5 * d[i, 6] + 0.0 * (s2 + c2)
        owed += steps
        while owed >= 1.0:
            owed -= 1.0
            h = 0.5 * w * x
            sh, sm, cm = sin(h), sin(q + h), cos(q + h)
            x = x - 1e-30 * ((1e-3 - 2.0 * cm * sh) / (1.0 + w * (c2 - 2.0 * sm * sh)))
        z = 0.0 * x
    return z


def newton_steps(d: np.ndarray, m: int = 2000) -> float:
    """Mean evaluations per Newton solve over the first ``m`` brackets (Python, counted)."""
    calls = [0]
    hev = R.hev

    def counted(*a):
        calls[0] += 1
        return hev(*a)

    R.hev = counted
    try:
        for g, v, th, s, c, _t, hi in d[:m]:
            R.bracket_root.py_func(g, v, -0.5, 0.0, -1.0, th, s, c, W, 0.0, hi, TOL)
    finally:
        R.hev = hev
    return calls[0] / min(m, len(d))


def kernel_run(cfg: EngineConfig, cap: int = 1 << 14) -> None:
    """The kernel alone, writing every chunk's events into the same buffers."""
    prm, flg = _pack(cfg)
    st, ist = initial_state(cfg, InitialState())
    ev = tuple(np.empty(cap) for _ in range(K.EV_COLS))
    evk = np.empty(cap, np.int8)
    traj, strobe = np.empty((0, K.TRAJ_COLS)), np.empty((0, K.STROBE_COLS))
    info = np.zeros(K.N_OUT, np.int64)
    while True:
        K.run_chunk(prm, flg, st, ist, ev, evk, traj, strobe, info)
        if info[K.O_STATUS] != K.ST_CHUNK:
            return


def parts(events: int) -> dict[str, tuple]:
    """Every timed part: ``name -> (function, arguments)``, from one recorded run."""
    cfg = EngineConfig(e=E, omega_s=W, max_events=events)
    ev = simulate_arrays(cfg).events
    ph, v_rel = ev["phase"], ev["v_rel"]
    vs = W * np.cos(ph)
    u0, v0, v_minus = np.sin(ph), vs + E * v_rel, vs - v_rel
    infl = R.inflections(0.0, -1.0, -0.5, W)
    d = _descents(u0, v0, ph, W, infl)
    cap = 1 << 14
    buf = (tuple(np.empty(cap) for _ in range(K.EV_COLS)), np.empty(cap, np.int8))
    counters = (np.zeros(K.N_IST, np.int64), np.zeros(K.N_OUT, np.int64))
    return {
        "run (simulate_arrays)": (simulate_arrays, (cfg,)),
        "kernel, reused buffers": (kernel_run, (cfg,)),
        "flight search": (_search_chain, (u0, v0, ph, u0, np.cos(ph), W, infl)),
        "certified root (Newton)": (_newton_chain, (d, W)),
        "impact law": (_law_chain, (ph, v_minus, W, E)),
        "event row": (_rows, (*buf, *counters, ev["t"], ph, v_rel)),
        "floor": (_floor_chain, (ph, d, W, newton_steps(d))),
    }


def measure(events: int, repeat: int) -> dict[str, float]:
    """Median CPU nanoseconds per impact of every part, repetitions interleaved."""
    todo = parts(events)
    small = parts(100)
    for f, a in small.values():  # compile
        f(*a)
    times: dict[str, list[float]] = {k: [] for k in todo}
    for _ in range(repeat):
        for k, (f, a) in todo.items():
            t0 = time.process_time()
            f(*a)
            times[k].append(1e9 * (time.process_time() - t0) / events)
    return {k: statistics.median(v) for k, v in times.items()}


def rows(t: dict[str, float]) -> list[tuple[str, str]]:
    """The breakdown as ``(part, ns per impact and share of the run)`` rows."""
    run = t["run (simulate_arrays)"]
    part = {
        "root bracketing (ascent test, descent start with its sin and cos, inflection phases, "
        "shortcuts, phase reduction)": t["flight search"] - t["certified root (Newton)"],
        "certified root: safeguarded Newton, sin + sincos + division per step": t[
            "certified root (Newton)"
        ],
        "impact law with sin and cos of the impact phase, chattering test": t["impact law"],
        "event row (6 columns and kind; off the dependency chain)": t["event row"],
        "bookkeeping (loop, state arrays, calls, branches)": t["kernel, reused buffers"]
        - t["flight search"]
        - t["impact law"]
        - t["event row"],
        "output: the run's fresh arrays and the driver": run - t["kernel, reused buffers"],
    }
    out = [(k, f"{v:.0f} ns ({100 * v / run:.0f} %)") for k, v in part.items()]
    out.append(("whole impact (simulate_arrays)", f"{run:.0f} ns = {1e3 / run:.2f} million/s"))
    out.append(
        (
            "floor: the chain's libm calls, square root and divisions alone",
            f"{t['floor']:.0f} ns ({100 * t['floor'] / run:.0f} % of the impact)",
        )
    )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--events", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument(
        "--record", action="store_true", help="write benchmarks/out/engine_profile.json"
    )
    args = ap.parse_args()
    table = rows(measure(args.events, args.repeat))
    print(f"{args.events:,} impacts, median of {args.repeat} interleaved repetitions (CPU time)")
    for k, v in table:
        print(f"  {k:<100} {v}")
    if args.record:
        from record import write_record

        write_record("engine_profile", "Where the time of an impact goes in the engine", table)


if __name__ == "__main__":
    main()
