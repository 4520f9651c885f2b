"""Coexisting motions and their basins (``bouncedisk basins``; docs/formats.md "Basins file").

Which motion a start reaches: starts over the stator's phase at switch-on, the rotor's initial
speed and its initial height above the stator (height 0: resting on it, in contact and moving
with it; above 0: released at absolute rest, docs/model.md "Things that are easy to get wrong",
initial condition), each run over the scene's statistics window ``[discard, stop]`` with the
scene's effects (load, noise). Every start is one run of the engine reduced by
:func:`~bouncedisk.analysis.ensembles.run_member` (regime, period, mean speed, as ``stats``
measures them), the starts run side by side on threads (:mod:`bouncedisk.analysis.sweeps`'s
ordered runs), and start ``i`` uses the noise stream ``(seed, i)``: its numbers do not depend
on the shard it is in or on the number of cores.

**The rule** (:data:`RULE`). A start's window is measured in two halves, each a run from the
start (the first to the window's middle, the second to its end), so the start's mean speed is
the mean of its two halves' means and its regime that of the window's end:

1. its class is its regime with its period: ``periodic`` and ``chattering-periodic`` with
   ``(p, q)`` (and, for these, the impact phases of one cycle), ``chaotic`` (chaotic or with
   chatter reinjection: one class, the tail's naming may flip between them), ``rest``;
   ``unresolved`` is not a class: the start has **not settled**;
2. a start has **settled** when its two halves' mean speeds differ by at most the class's
   tolerance: ``settle x scale x min(1, 10 T_s / h)`` (``scale``: the largest absolute mean
   speed of all starts, at least 1; ``h`` the start's half-window, ``T_s`` the stator period: a
   periodic orbit's halves differ by its ripple over part of a cycle, which falls as ``1/h``, a
   drifting start's by its drift rate times ``h``), ``10 x settle x scale`` for the chaotic
   class, whose finite-time means fluctuate. A start not settled by this rule with its own
   speed as the scale (``max(1, |mean speed|)``: as strict as the grouping's or stricter) is
   measured again over the scene's window doubled (``[2 discard, 2 stop]`` after its
   switch-on), then four times, ..., up to ``extend`` doublings (:data:`EXTEND`), and keeps
   the first window it settles in (``window_factor``), else the longest it ran to its end; a
   start that has not settled even then is labelled ``-1`` (a drifting speed: run longer).
   A longer window continues the start's run from where its last window ended (when that is
   not past the new window's start; else from the start), in segments each continued from
   the last state at the same stator phase: the same orbit to rounding, at the cost of the
   added time only; each segment draws start ``i``'s noise stream afresh;
3. settled starts of one class (and, for periodic classes, one cycle of impact phases within
   :data:`PHASE_TOL`) belong to one attractor when a chain of them joins their mean speeds with
   steps of at most the larger of the two starts' tolerances. A chaotic attractor is not split
   by its finite-time means: each start's halves differ by less than the tolerance, and the
   means of its starts spread less than that, so consecutive means are closer still;
4. attractors are numbered by decreasing mean speed (label 0: the fastest).

The basin fraction of an attractor is its starts over all starts, with the Wilson score interval
(95 %), and the same for the starts that have not settled.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..analysis import observables as ob
from ..analysis.ensembles import CappedRun, run_member
from ..analysis.statistics import capped_error, confidence_interval, ensemble_window, wilson
from ..analysis.sweeps import _ordered_runs, shard_slice, with_params
from ..engine import InitialState
from ..engine.bounds import MAX_SPEED
from ..io.provenance import base_attrs, new_run_id
from ..io.records import json_number as _num
from ..model import limits
from ..model.engine_config import engine_config
from ..model.errors import InputError
from ..model.scene import Scene, require_scene
from ..run.cores import checked_cores
from ..run.runner import scene_attrs
from .shards import join_indexed

#: The settle tolerance's default, relative to the largest mean speed (rule 2).
DEFAULT_SETTLE = 1e-2
#: The chaotic class's tolerance, in units of the others' (rule 2).
CHAOTIC_FACTOR = 10.0
#: Half-window, in stator periods, below which a periodic class's tolerance stops shrinking: the
#: tolerance is ``settle x scale x min(1, HALF_PERIODS T_s / h)`` for halves of length ``h``
#: (rule 2). A periodic orbit's half-window means differ by its ripple over a part of a cycle,
#: which falls as ``1/h``; a start still drifting towards its attractor differs by its drift
#: rate times ``h``: the shrinking tolerance keeps a short window from calling a drift settled.
HALF_PERIODS = 10.0
#: Default number of doublings of the window for the starts that have not settled (rule 2):
#: up to 8 times the scene's window.
EXTEND = 3
#: Most doublings one computation may ask for.
MAX_EXTEND = 8
#: Regime codes of the chaotic class (rule 1).
CHAOTIC_CODES = (ob.REGIME_CODES["chaotic"], ob.REGIME_CODES["chaotic-reinjection"])
#: Fewest stator periods in each half-window (:func:`check_scene`).
MIN_HALF_PERIODS = 10.0
#: Largest difference of two cycles' impact phases (rad) of one periodic attractor (rule 3).
PHASE_TOL = 1e-4
#: Impact phases of one cycle kept per start (a cycle of up to 32 events, the regime search's).
ORBIT_SLOTS = 33
#: Largest number of starts one computation may ask for.
MAX_STARTS = 100_000
#: Largest number of initial speeds or heights one list may give (:func:`parse_values`).
MAX_VALUES = 10_000
#: Largest initial height above the stator: a fall of about 1400 time units, longer than any
#: window a basin computation can tell settling in.
MAX_HEIGHT = 1e6
#: The grouping rule, as the files and ``--json`` state it.
RULE = (
    "start settled when its two half-window mean speeds differ by <= settle * scale * "
    "min(1, 10 T_s / h) (h: the start's half-window, T_s: the stator period; chaotic class: "
    "10 settle * scale; scale = max |mean speed|, >= 1); a start not settled with its own "
    "|mean speed| as the scale is measured again over the window doubled (its run "
    "continued), up to `extend` times; settled starts of one class (regime + period + cycle "
    "phases; chaotic and chaotic-reinjection one class) form one attractor when chained by "
    "mean-speed steps <= the larger of the two starts' tolerances; unresolved or unsettled: -1"
)
#: Per-start variables of a shard: name -> (long name, units) (docs/formats.md "Basins file").
START_VARS = {
    "phase": ("stator phase at switch-on", "rad"),
    "speed": ("initial rotor angular velocity", "1"),
    "height": ("initial height above the stator (0: in contact)", "1"),
    "mean_omega": ("time-averaged rotor angular velocity over the window", "1"),
    "mean_omega_first_half": ("mean rotor angular velocity over the window's first half", "1"),
    "mean_omega_second_half": ("mean rotor angular velocity over the window's second half", "1"),
    "regime": ("dynamical regime at the window's end", "1"),
    "period_p": ("impacts per cycle (periodic regimes; 0 otherwise)", "1"),
    "period_q": ("stator periods per cycle (periodic regimes; 0 otherwise)", "1"),
    "lyapunov": ("largest Lyapunov exponent per impact, between resets (second half)", "1"),
    "n_impacts": ("impacts over the window", "1"),
    "window_factor": ("the start's window over the scene's (2^k: doubled k times, rule 2)", "1"),
    "orbit_phases": ("sorted impact phases of one cycle (periodic regimes; NaN otherwise)", "rad"),
}


@dataclass(frozen=True)
class StartGrid:
    """The starts: ``phases`` (rad, stator phase at switch-on), ``speeds`` (initial ``Ω``),
    ``heights`` (above the stator; 0: in contact), flattened with the phase varying fastest,
    then the speed, then the height."""

    phases: np.ndarray
    speeds: np.ndarray
    heights: np.ndarray

    @property
    def size(self) -> int:
        """Number of starts."""
        return len(self.phases) * len(self.speeds) * len(self.heights)

    def flat(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(phase, speed, height)`` of every start, in start order."""
        h, s, p = np.meshgrid(self.heights, self.speeds, self.phases, indexing="ij")
        return p.ravel(), s.ravel(), h.ravel()


def parse_values(text: str, field: str, what: str, source: str = "<arguments>") -> list[float]:
    """Initial speeds or heights from ``START:STOP:N`` (``N`` evenly spaced, ends included) or
    ``a,b,c`` (any sign: :func:`start_grid` checks the range); ``what`` (``speed``,
    ``height``) names one value in the messages.

    Raises
    ------
    InputError
        Naming ``source`` and ``field``: empty, an empty item (``1,,2``), not numbers, ``N < 2``
        or above :data:`MAX_VALUES`, ``STOP <= START``, or a value repeated.
    """
    from ..model.params import number, whole_number

    text = str(text).strip()
    form = f"give START:STOP:N or a,b,c {what}s"
    if not text:
        raise InputError(source, field, f"is empty; {form}")
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise InputError(source, field, f"{form}, got {text!r}")
        start, stop = (number(source, field, x) for x in parts[:2])
        n = whole_number(source, field, parts[2], minimum=2)
        if n > MAX_VALUES:
            raise InputError(source, field, f"asks for {n} {what}s, more than {MAX_VALUES}")
        if not stop > start:
            raise InputError(source, field, f"STOP must be > START, got {text!r}")
        return np.linspace(start, stop, n).tolist()
    items = text.split(",")
    if any(not x.strip() for x in items):
        raise InputError(source, field, f"has an empty {what} in {text!r}; {form}")
    if len(items) > MAX_VALUES:
        raise InputError(source, field, f"gives {len(items)} {what}s, more than {MAX_VALUES}")
    values = [number(source, field, x) for x in items]
    if len(set(values)) != len(values):
        raise InputError(source, field, f"repeats a {what}: {text!r}")
    return sorted(values)


def _check_values(
    source: str, field: str, values: Sequence[float], low: float, high: float, why: str
):
    """Finite values within ``[low, high]`` (one of them at least), else an input error."""
    arr = np.asarray(values, float)
    shown = "[" + ", ".join(f"{float(x):g}" for x in arr.ravel()) + "]"
    if arr.size == 0 or not np.all(np.isfinite(arr)):
        raise InputError(source, field, f"must be finite values, got {shown}")
    bad = arr[(arr < low) | (arr > high)]
    if bad.size:
        within = f"within ±{high:g}" if low == -high else f"in [{low:g}, {high:g}]"
        raise InputError(source, field, f"must be {within} ({why}), got {float(bad[0]):g}")


def start_grid(
    n_phases: int,
    speeds: Sequence[float],
    heights: Sequence[float] = (0.0,),
    source: str = "<arguments>",
) -> StartGrid:
    """``n_phases`` phases ``2 pi k / n_phases`` over one stator period, with the speeds and
    heights given.

    Raises
    ------
    InputError
        No phase, a speed beyond the scene's bound on ``initial.omega`` (:data:`bouncedisk.engine.bounds.MAX_SPEED`),
        a negative height or one above :data:`MAX_HEIGHT`, a non-finite value, or more than
        :data:`MAX_STARTS` starts.
    """
    if isinstance(n_phases, bool) or not isinstance(n_phases, int | np.integer) or n_phases < 1:
        raise InputError(source, "--phases", f"must be a whole number >= 1, got {n_phases!r}")
    bound = MAX_SPEED
    _check_values(source, "--speeds", speeds, -bound, bound, "a scene's bound on initial.omega")
    _check_values(source, "--heights", heights, 0.0, MAX_HEIGHT, "above the stator, 0: on it")
    grid = StartGrid(
        2.0 * math.pi * np.arange(n_phases) / n_phases,
        np.asarray(speeds, float),
        np.asarray(heights, float),
    )
    if grid.size > MAX_STARTS:
        raise InputError(source, "--phases", f"asks for {grid.size} starts, more than {MAX_STARTS}")
    return grid


def start_state(scene: Scene, phase: float, speed: float, height: float) -> InitialState:
    """The initial state of one start: at time ``phase / omega_s`` (the stator's phase at
    switch-on), rotor speed ``speed``; in contact for ``height == 0``, else released at rest
    (``v = 0``) at ``u = u_s + height`` (eq. 1)."""
    t = phase / scene.params.omega_s
    if height == 0.0:
        return InitialState(t=t, omega=speed)
    return InitialState(t=t, omega=speed, u=math.sin(phase) + height, v=0.0)


def check_scene(scene: Scene) -> tuple[float, float]:
    """The scene's window ``(discard, duration)``; a basin computation needs a time stop with a
    window of a stator period or more (:func:`ensemble_window`), torsion and the exact solver.

    Raises
    ------
    InputError
        Naming the scene's field at fault.
    """
    t_from, t_end = ensemble_window(scene)
    if "torsion" not in scene.effects:
        raise InputError(scene.source, "effects", "basins compare rotor speeds: add 'torsion'")
    if scene.model != "bouncing":
        raise InputError(scene.source, "model", "basins run the bouncing model only")
    if scene.solver.method != "exact":
        raise InputError(scene.source, "solver.method", "basins run the exact solver only")
    half = 0.5 * (t_end - t_from)
    periods = half * scene.params.omega_s / (2.0 * math.pi)
    if periods < MIN_HALF_PERIODS:
        raise InputError(
            scene.source,
            "stop.time",
            f"each half of the window [stats.discard, stop.time] must span at least "
            f"{MIN_HALF_PERIODS:g} stator periods to tell a settled start from a drifting one; "
            f"it spans {periods:.3g}",
        )
    return t_from - scene.initial.t, t_end - scene.initial.t


def _tasks(
    scene: Scene, grid: StartGrid, index: np.ndarray, factor: float = 1.0
) -> Iterator[tuple]:
    """:func:`run_member`'s arguments: two per start (the window's halves), in start order, over
    the scene's window stretched ``factor`` times (``[factor discard, factor stop]`` after the
    start's switch-on)."""
    discard, duration = (factor * x for x in check_scene(scene))
    cfg = engine_config(scene)
    mid = discard + 0.5 * (duration - discard)
    phase, speed, height = grid.flat()
    for i in index:
        init = start_state(scene, float(phase[i]), float(speed[i]), float(height[i]))
        t0 = init.t
        yield dataclasses.replace(cfg, t_end=t0 + mid), init, int(i), t0 + discard
        yield dataclasses.replace(cfg, t_end=t0 + duration), init, int(i), t0 + mid


def _orbit(stats, tail: dict) -> np.ndarray:
    """The sorted impact phases of one cycle of a (chattering-)periodic start, NaN-padded."""
    out = np.full(ORBIT_SLOTS, np.nan)
    if stats.regime == ob.REGIME_CODES["periodic"]:
        n = stats.period_p
    elif stats.regime == ob.REGIME_CODES["chattering-periodic"]:
        n = stats.period_p + 1
    else:
        return out
    n = min(n, ORBIT_SLOTS, len(tail["phase"]))
    if n:
        out[:n] = np.sort(np.mod(tail["phase"][-n:], 2.0 * math.pi))
    return out


def _capped_named(scene: Scene, grid: StartGrid, runs: Iterator) -> Iterator:
    """``runs``, a start that stops at ``stop.max_events`` before its window ends an input error
    naming the field and the start: its index, phase, speed and height
    (:func:`~bouncedisk.analysis.statistics.capped_error`)."""
    try:
        yield from runs
    except CappedRun as ex:
        phase, speed, height = (float(a[ex.member]) for a in grid.flat())
        who = (
            f"start {ex.member} of the basins (phase {phase:.4g} rad, speed {speed:.4g}, "
            f"height {height:.4g})"
        )
        raise capped_error(scene, ex, who=who) from None


class _StartValues:
    """The per-start values of one shard (:data:`START_VARS`), filled pass by pass."""

    def __init__(self, n: int):
        names = ("mean_omega", "mean_omega_first_half", "mean_omega_second_half", "lyapunov")
        self.vals = {k: np.full(n, np.nan) for k in names}
        self.vals["window_factor"] = np.ones(n)
        names = ("regime", "period_p", "period_q", "n_impacts")
        self.ints = {k: np.zeros(n, np.int64) for k in names}
        self.orbit = np.full((n, ORBIT_SLOTS), np.nan)
        #: per start: (time after its switch-on its run has reached, the state there)
        self.reached: list[tuple[float, dict] | None] = [None] * n

    def put(self, j: int, first, second, tail: dict, factor: float) -> None:
        """Start ``j``'s two halves over a window stretched ``factor`` times."""
        self.vals["mean_omega_first_half"][j] = first.mean_omega
        self.vals["mean_omega_second_half"][j] = second.mean_omega
        self.vals["mean_omega"][j] = 0.5 * (first.mean_omega + second.mean_omega)
        self.vals["lyapunov"][j] = second.lyapunov
        self.vals["window_factor"][j] = factor
        self.ints["regime"][j] = second.regime
        self.ints["period_p"][j], self.ints["period_q"][j] = second.period_p, second.period_q
        self.ints["n_impacts"][j] = first.n_impacts + second.n_impacts
        self.orbit[j] = _orbit(second, tail)

    def settled_alone(self, half_window: float, period: float, settle: float) -> np.ndarray:
        """Which starts have settled by rule 2 with their own speed as the scale
        (``max(1, |mean speed|)``, never above the grouping's: as strict or stricter)."""
        mean = self.vals["mean_omega"]
        scale = np.maximum(1.0, np.abs(mean))
        shrink = np.minimum(1.0, HALF_PERIODS * period / (half_window * self.vals["window_factor"]))
        chaotic = np.isin(self.ints["regime"], CHAOTIC_CODES)
        tol = settle * scale * np.where(chaotic, CHAOTIC_FACTOR, shrink)
        d_half = np.abs(self.vals["mean_omega_second_half"] - self.vals["mean_omega_first_half"])
        resolved = self.ints["regime"] != ob.REGIME_CODES["unresolved"]
        return resolved & np.isfinite(mean) & (d_half <= tol)


def _segment(cfg, init: InitialState, member: int, length: float, stats_from: float = 0.0):
    """:func:`run_member` from ``init`` for ``length`` time units, averaged after
    ``stats_from`` of them."""
    run = dataclasses.replace(cfg, t_end=init.t + length)
    return run_member(run, init, member, init.t + stats_from)


def _longer_window(scene: Scene, cfg, init: InitialState, member: int, window, resume):
    """Start ``member`` over ``window`` ``(a, b)`` (time after its switch-on, ``init``'s time),
    continuing its run from ``resume`` ``(reached, state)`` when that is not past ``a``, else
    from its start: a run to ``a``, then the halves ``[a, m]`` and ``[m, b]``, each continued
    from the last state (:func:`~bouncedisk.studies.torque_speed.continued_state`). Returns
    the halves' statistics, the second's tail and ``(b, state at b)``."""
    from .torque_speed import continued_state

    a, b = window
    m = 0.5 * (a + b)
    w = scene.params.omega_s
    reached, state = resume if resume is not None and resume[0] <= a else (0.0, None)
    here = init if state is None else continued_state(state, w)
    if a > reached:
        _, state, _ = _segment(cfg, here, member, a - reached)
        here = continued_state(state, w)
    first, state, _ = _segment(cfg, here, member, m - a)
    second, state, tail = _segment(cfg, continued_state(state, w), member, b - m)
    return first, second, tail, (b, state)


def _extend(
    scene, grid, index, out: _StartValues, pool, ahead: int, extend: int, settle: float, progress
):
    """Rule 2's longer windows: the starts not settled by their own speed run on over the
    window doubled, up to ``extend`` times (:func:`_longer_window`); a start whose longer run
    stops at ``stop.max_events`` keeps its last window (and stays unsettled)."""
    discard, duration = check_scene(scene)
    half = 0.5 * (duration - discard)
    period = 2.0 * math.pi / scene.params.omega_s
    cfg = engine_config(scene)
    phase, speed, height = grid.flat()
    for k in range(1, extend + 1):
        todo = np.nonzero(~out.settled_alone(half, period, settle))[0]
        if not todo.size:
            return
        factor = 2.0**k
        window = (factor * discard, factor * duration)
        for block in np.array_split(todo, -(-len(todo) // ahead)):  # bounded memory
            futures = []
            for j in block:
                i = int(index[j])
                init = start_state(scene, float(phase[i]), float(speed[i]), float(height[i]))
                args = (scene, cfg, init, i, window, out.reached[j])
                futures.append(pool.submit(_longer_window, *args))
            for j, future in zip(block, futures, strict=True):
                try:
                    first, second, tail, reached = future.result()
                except CappedRun:
                    continue
                out.put(int(j), first, second, tail, factor)
                out.reached[j] = reached
            if progress:
                progress(int(np.searchsorted(todo, block[-1])) + 1, len(todo))


def run_starts(
    scene: Scene,
    grid: StartGrid,
    shard: int = 0,
    n_shards: int = 1,
    cores: int = 1,
    progress: Callable[[int, int], None] | None = None,
    extend: int = EXTEND,
    settle: float = DEFAULT_SETTLE,
) -> xr.Dataset:
    """Run one shard of the starts (a contiguous block of start indices) and return their
    per-start values (:data:`START_VARS`) with the scene's provenance; join shards with
    :func:`join_shards`, or group one complete set with :func:`group`. A start not settled over
    the scene's window is measured again over windows twice, four times, ... as long, its run
    continued, up to ``extend`` doublings (rule 2, ``settle`` its tolerance), each start on its
    own: its numbers do not depend on the shard."""
    start = time.perf_counter()
    limits.SETTLE_RANGE.check("<arguments>", "settle", settle)  # before any run
    check_scene(scene)
    if (
        isinstance(extend, bool)
        or not isinstance(extend, int | np.integer)
        or not 0 <= extend <= MAX_EXTEND
    ):
        raise InputError(
            "<arguments>",
            "--extend",
            f"must be a whole number in [0, {MAX_EXTEND}], got {extend!r}",
        )
    index = np.arange(grid.size)[shard_slice(grid.size, shard, n_shards)]
    n = len(index)
    out = _StartValues(n)
    pool = ThreadPoolExecutor(max_workers=max(1, cores))
    try:
        runs = _capped_named(
            scene, grid, _ordered_runs(pool, _tasks(scene, grid, index), 4 * max(1, cores))
        )
        _, duration = check_scene(scene)
        for j in range(n):
            first, _, _ = next(runs)
            second, state, tail = next(runs)
            out.put(j, first, second, tail, 1.0)
            out.reached[j] = (duration, state)
            if progress:
                progress(j + 1, n)
        _extend(scene, grid, index, out, pool, 16 * max(1, cores), extend, settle, progress)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    phase, speed, height = (a[index] for a in grid.flat())
    ds = _start_dataset(index, phase, speed, height, out.vals, out.ints, out.orbit)
    ds.attrs.update(_attrs(scene, grid, start, f"basins{shard}"))
    ds.attrs.update({"shard": shard, "n_shards": n_shards, "n_impacts": int(ds["n_impacts"].sum())})
    ds.attrs.update({"extend": int(extend), "extend_settle": float(settle)})
    return ds


def _start_dataset(index, phase, speed, height, vals, ints, orbit) -> xr.Dataset:
    """The per-start variables of :data:`START_VARS` (docs/formats.md "Basins file")."""
    arrays = {"phase": phase, "speed": speed, "height": height, **vals, **ints}
    data = {}
    for name, (long_name, units) in START_VARS.items():
        attrs = {"long_name": long_name, "units": units}
        if name == "regime":
            attrs.update(ob.regime_flags(np.int64))
        if name == "orbit_phases":
            data[name] = (("start", "orbit_slot"), orbit, attrs)
        else:
            data[name] = (("start",), arrays[name], attrs)
    coords = {"start": ("start", np.asarray(index, np.int64), {"long_name": "start index"})}
    return xr.Dataset(data, coords=coords)


def _attrs(scene: Scene, grid: StartGrid, start: float, run: str) -> dict:
    """Global attributes: provenance, the scene, the starts' grid and window."""
    discard, duration = check_scene(scene)
    attrs = base_attrs(f"bouncedisk basins of scene '{scene.name}'")
    attrs.update(scene_attrs(scene))
    attrs.update(
        {
            "n_starts": grid.size,
            "phases": grid.phases,
            "speeds": grid.speeds,
            "heights": grid.heights,
            "start_order": "phase fastest, then speed, then height",
            "window": [discard, duration],
            "window_comment": "each start averages over [t0 + window[0], t0 + window[1]], "
            "t0 = phase / omega_s its switch-on",
            "noise_streams": "start i uses the stream (ensemble_seed, i)",
            "run_id": new_run_id(f"{scene.name}-{run}", scene.sha256),
            "wall_time_s": round(time.perf_counter() - start, 6),
            "status": "completed",
        }
    )
    return attrs


def join_shards(shards: Sequence[xr.Dataset]) -> xr.Dataset:
    """The shards' starts in start order, checked: every start of the grid appears once.

    Raises
    ------
    ValueError
        A start missing or repeated, or shards of different computations.
    """
    if not shards:
        raise ValueError("no shards to join")
    n = int(shards[0].attrs["n_starts"])
    if any(int(s.attrs["n_starts"]) != n for s in shards) or any(
        s.attrs.get("scene_sha256") != shards[0].attrs.get("scene_sha256") for s in shards
    ):
        raise ValueError("the shards are of different basin computations")
    ds = join_indexed(shards, "start", n, "start")
    ds.attrs["n_impacts"] = int(ds["n_impacts"].sum())
    ds.attrs["shard_run_ids"] = ",".join(str(s.attrs.get("run_id")) for s in shards)
    first = shards[0].attrs
    ds.attrs["run_id"] = new_run_id(
        f"{first.get('scene_name', 'scene')}-basins", str(first.get("scene_sha256", "0" * 8))
    )
    return ds


def _class_of(regime: int, p: int, q: int) -> tuple | None:
    """A start's class (rule 1), ``None`` for ``unresolved``."""
    name = ob.REGIMES[int(regime)]
    if name == "unresolved":
        return None
    if name in ("chaotic", "chaotic-reinjection"):
        return ("chaotic", 0, 0)
    if name == "rest":
        return ("rest", 0, 0)
    return (name, int(p), int(q))


def _same_cycle(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two cycles' impact phases agree within :data:`PHASE_TOL` (rule 3): as many, and
    each of either within the tolerance of one of the other's (on the circle, so a phase near 0
    matches one near 2 pi)."""
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    if len(a) != len(b):
        return False
    if len(a) == 0:  # neither periodic: the class alone decides
        return True
    d = ob.circular_distance(a[:, None], b[None, :])
    return bool(np.all(d.min(axis=1) <= PHASE_TOL) and np.all(d.min(axis=0) <= PHASE_TOL))


def _tolerances(ds: xr.Dataset, settle: float, scale: float) -> Callable[[tuple, int], float]:
    """The settle tolerance of a class at start ``i`` (rule 2), from the file's window, the
    start's window factor (1 when the file has none) and the stator period."""
    discard, duration = (float(x) for x in np.ravel(ds.attrs["window"]))
    half = 0.5 * (duration - discard)
    period = 2.0 * math.pi / float(ds.attrs["omega_s"])
    shrink = np.minimum(1.0, HALF_PERIODS * period / (half * _window_factors(ds)))

    def tolerance(cls: tuple, i: int) -> float:
        return settle * scale * (CHAOTIC_FACTOR if cls[0] == "chaotic" else float(shrink[i]))

    return tolerance


def labels(ds: xr.Dataset, settle: float = DEFAULT_SETTLE) -> tuple[np.ndarray, float]:
    """Every start's attractor label by the module's rule (:data:`RULE`), ``-1`` when it has not
    settled, and the speed scale; attractors numbered by decreasing mean speed."""
    mean = ds["mean_omega"].values
    d_half = np.abs(ds["mean_omega_second_half"].values - ds["mean_omega_first_half"].values)
    finite = mean[np.isfinite(mean)]
    scale = max(1.0, float(np.max(np.abs(finite)))) if finite.size else 1.0
    tolerance = _tolerances(ds, settle, scale)
    groups: dict[tuple, list[list[int]]] = {}  # class -> cycles -> starts
    for i in range(len(mean)):
        cls = _class_of(ds["regime"].values[i], ds["period_p"].values[i], ds["period_q"].values[i])
        if cls is None or not math.isfinite(mean[i]):
            continue
        if not d_half[i] <= tolerance(cls, i):
            continue
        cycles = groups.setdefault(cls, [])
        orbit = ds["orbit_phases"].values[i]
        home = next(
            (c for c in cycles if _same_cycle(ds["orbit_phases"].values[c[0]], orbit)), None
        )
        if home is None:
            cycles.append([i])
        else:
            home.append(i)
    found: list[list[int]] = []
    for cls, cycles in groups.items():
        for members in cycles:
            order = sorted(members, key=lambda i: (mean[i], i))
            chain = [order[0]]
            for a, b in zip(order, order[1:], strict=False):
                if mean[b] - mean[a] > max(tolerance(cls, a), tolerance(cls, b)):
                    found.append(chain)
                    chain = []
                chain.append(b)
            found.append(chain)
    found.sort(key=lambda c: (-float(np.mean(mean[c])), min(c)))
    out = np.full(len(mean), -1, np.int64)
    for k, chain in enumerate(found):
        out[chain] = k
    return out, scale


#: Per-attractor variables: name -> (long name, whole number), in the order :func:`group` fills.
ATTRACTOR_VARS = {
    "attractor_mean_speed": ("mean rotor angular velocity of the attractor's starts", False),
    "attractor_mean_speed_ci95_low": ("lower end of the 95% Student interval of it", False),
    "attractor_mean_speed_ci95_high": ("upper end of the 95% Student interval of it", False),
    "attractor_regime": ("dynamical regime (most common among the attractor's starts)", True),
    "attractor_period_p": ("impacts per cycle (periodic regimes; 0 otherwise)", True),
    "attractor_period_q": ("stator periods per cycle (periodic regimes; 0 otherwise)", True),
    "attractor_starts": ("starts reaching the attractor", True),
    "attractor_fraction": ("basin fraction: starts reaching the attractor over all starts", False),
    "attractor_fraction_ci95_low": ("lower end of the 95% Wilson interval of it", False),
    "attractor_fraction_ci95_high": ("upper end of the 95% Wilson interval of it", False),
}
LABEL_LONG_NAME = "attractor reached (-1: not settled within the window; 0: the fastest)"


def group(ds: xr.Dataset, settle: float = DEFAULT_SETTLE) -> xr.Dataset:
    """The starts of a complete computation with their labels and the attractors: per attractor
    its mean speed (mean over its starts, Student interval across them), regime and period,
    basin fraction with its Wilson interval (docs/formats.md "Basins file")."""
    limits.SETTLE_RANGE.check("", "settle", settle)
    lab, scale = labels(ds, settle)
    n = len(lab)
    mean = ds["mean_omega"].values
    rows = []
    for k in range(int(lab.max(initial=-1)) + 1):
        idx = np.nonzero(lab == k)[0]
        m, lo, hi = confidence_interval(mean[idx])
        regimes = Counter(int(r) for r in ds["regime"].values[idx])
        code = max(regimes, key=lambda c: (regimes[c], -c))
        first = idx[0]
        periodic = ob.REGIMES[code] in ("periodic", "chattering-periodic")
        p = int(ds["period_p"].values[first]) if periodic else 0
        q = int(ds["period_q"].values[first]) if periodic else 0
        rows.append((m, lo, hi, code, p, q, len(idx), *_fraction(len(idx), n)))
    arr = np.array(rows, float).reshape(-1, len(ATTRACTOR_VARS))
    out = ds.copy()
    out["label"] = ("start", lab, {"long_name": LABEL_LONG_NAME, "units": "1"})
    out = out.assign_coords(
        attractor=(
            "attractor",
            np.arange(len(rows), dtype=np.int64),
            {"long_name": "attractor label (0: the fastest)"},
        )
    )
    for j, (name, (long_name, whole)) in enumerate(ATTRACTOR_VARS.items()):
        values = arr[:, j].astype(np.int64) if whole else arr[:, j]
        out[name] = (("attractor",), values, {"long_name": long_name, "units": "1"})
    out["attractor_regime"].attrs.update(ob.regime_flags(np.int64))
    unsettled = int(np.sum(lab < 0))
    frac, low, high = _fraction(unsettled, n)
    out.attrs.update(
        {
            "rule": RULE,
            "settle": settle,
            "speed_scale": scale,
            "n_attractors": len(rows),
            "unsettled_starts": unsettled,
            "unsettled_fraction": frac,
            "unsettled_fraction_ci95": [low, high],
            "confidence_level": 0.95,
            "fraction_interval": "Wilson score",
        }
    )
    out.attrs.pop("n_shards", None)
    return out


def _fraction(k: int, n: int) -> tuple[float, float, float]:
    """``k / n`` and its Wilson interval."""
    return (k / n if n else math.nan, *wilson(k, n))


def basins(
    scene: Scene,
    grid: StartGrid,
    cores: int = 1,
    settle: float = DEFAULT_SETTLE,
    progress: Callable[[int, int], None] | None = None,
    extend: int = EXTEND,
) -> xr.Dataset:
    """Every start of ``grid`` run (its window doubled up to ``extend`` times while it has not
    settled) and grouped (:func:`run_starts`, :func:`group`)."""
    scene = require_scene(scene)
    if not isinstance(grid, StartGrid):
        raise InputError(
            "<arguments>",
            "grid",
            f"must be a StartGrid (start_grid(...)), got {type(grid).__name__}",
        )
    cores = checked_cores(cores)
    ds = run_starts(scene, grid, cores=cores, progress=progress, extend=extend, settle=settle)
    return group(ds, settle)


def _window_factors(ds: xr.Dataset) -> np.ndarray:
    """Each start's window over the scene's (1 in a file without ``window_factor``)."""
    if "window_factor" in ds:
        return ds["window_factor"].values
    return np.ones(ds.sizes["start"])


def summary(ds: xr.Dataset) -> dict:
    """The JSON object of ``bouncedisk basins --json`` (docs/formats.md "Basins file")."""
    attractors = []
    for k in ds["attractor"].values:
        a = ds.sel(attractor=k)
        p, q = int(a["attractor_period_p"]), int(a["attractor_period_q"])
        attractors.append(
            {
                "label": int(k),
                "mean_speed": _num(float(a["attractor_mean_speed"])),
                "mean_speed_ci95": [
                    _num(float(a["attractor_mean_speed_ci95_low"])),
                    _num(float(a["attractor_mean_speed_ci95_high"])),
                ],
                "regime": ob.REGIMES[int(a["attractor_regime"])],
                "period": [p, q] if p > 0 else None,
                "starts": int(a["attractor_starts"]),
                "fraction": float(a["attractor_fraction"]),
                "fraction_ci95": [
                    float(a["attractor_fraction_ci95_low"]),
                    float(a["attractor_fraction_ci95_high"]),
                ],
            }
        )
    at = ds.attrs
    return {
        "starts": int(ds.sizes["start"]),
        "window": [float(x) for x in np.ravel(at["window"])],
        "rule": at["rule"],
        "settle": float(at["settle"]),
        "extend": int(at.get("extend", 0)),
        "speed_scale": float(at["speed_scale"]),
        "attractors": attractors,
        "unsettled": {
            "starts": int(at["unsettled_starts"]),
            "fraction": float(at["unsettled_fraction"]),
            "fraction_ci95": [float(x) for x in np.ravel(at["unsettled_fraction_ci95"])],
        },
        "per_start": {
            "phase": ds["phase"].values.tolist(),
            "speed": ds["speed"].values.tolist(),
            "height": ds["height"].values.tolist(),
            "label": ds["label"].values.tolist(),
            "mean_speed": [_num(x) for x in ds["mean_omega"].values.tolist()],
            "window_factor": _window_factors(ds).tolist(),
            "regime": [ob.REGIMES[int(r)] for r in ds["regime"].values],
        },
    }


#: Per-load fractions of the start-up file: name -> long name, in the order :func:`startup` fills.
STARTUP_FRACTIONS = {
    "fast_fraction": "fraction of starts settled on the fast branch",
    "fast_fraction_ci95_low": "lower end of the 95% Wilson interval of fast_fraction",
    "fast_fraction_ci95_high": "upper end of the 95% Wilson interval of fast_fraction",
    "slow_fraction": "fraction of starts settled on an attractor slower than fast_above",
    "slow_fraction_ci95_low": "lower end of the 95% Wilson interval of slow_fraction",
    "slow_fraction_ci95_high": "upper end of the 95% Wilson interval of slow_fraction",
    "unsettled_fraction": "fraction of starts not settled within the window",
    "unsettled_fraction_ci95_low": "lower end of the 95% Wilson interval of unsettled_fraction",
    "unsettled_fraction_ci95_high": "upper end of the 95% Wilson interval of unsettled_fraction",
}
#: Per-load, per-start variables of the start-up file (those of :func:`group`'s file).
STARTUP_PER_START = ("label", "mean_omega", "regime", "period_p", "period_q", "window_factor")


def startup(
    scene: Scene,
    loads: Sequence[float],
    grid: StartGrid,
    fast_above: float,
    cores: int = 1,
    settle: float = DEFAULT_SETTLE,
    extend: int = EXTEND,
) -> xr.Dataset:
    """Start-up under load: at each load torque, the starts of ``grid`` (from rest: speed 0)
    grouped (:func:`basins`), and the fraction that settles on the fast branch, an attractor
    whose mean speed is ``fast_above`` or more, and on a slower one (the slow branch), each
    with its Wilson interval; starts that have not
    settled within the window count as not reaching it (docs/formats.md "Basins file")."""
    if "load" not in scene.effects:
        raise InputError(scene.source, "effects", "start-up under load needs the 'load' effect")
    start = time.perf_counter()
    rows, impacts = [], 0
    per_start: dict[str, list] = {k: [] for k in STARTUP_PER_START}
    for load in loads:
        ds = basins(with_params(scene, load_torque=float(load)), grid, cores, settle, extend=extend)
        fast_labels = ds["attractor"].values[ds["attractor_mean_speed"].values >= fast_above]
        k = int(np.isin(ds["label"].values, fast_labels).sum())
        n, unsettled = int(ds.sizes["start"]), int(ds.attrs["unsettled_starts"])
        rows.append((*_fraction(k, n), *_fraction(n - k - unsettled, n), *_fraction(unsettled, n)))
        impacts += int(ds.attrs["n_impacts"])
        for name, values in per_start.items():
            values.append(ds[name])
    arr = np.array(rows, float)
    d = ("load_torque",)
    data = {
        name: (d, arr[:, j], {"long_name": long_name, "units": "1"})
        for j, (name, long_name) in enumerate(STARTUP_FRACTIONS.items())
    }
    n_att = [int(np.max(v.values, initial=-1)) + 1 for v in per_start["label"]]
    data["n_attractors"] = (d, np.array(n_att, np.int64), {"long_name": "attractors found"})
    for name, values in per_start.items():
        data[name] = (d + ("start",), np.stack([v.values for v in values]), dict(values[0].attrs))
    phase, speed, height = grid.flat()
    coords = {
        "start": ("start", np.arange(grid.size, dtype=np.int64), {"long_name": "start index"})
    }
    for name, values in (("phase", phase), ("speed", speed), ("height", height)):
        long_name, units = START_VARS[name]
        coords[name] = ("start", values, {"long_name": long_name, "units": units})
    coords["load_torque"] = (
        "load_torque",
        np.asarray(loads, float),
        {"long_name": "load torque tau_L (units of mu m_r g_eff r_eff)", "units": "1"},
    )
    out = xr.Dataset(data, coords=coords)
    out.attrs.update(_attrs(scene, grid, start, "startup"))
    out.attrs.pop("load_torque", None)
    out.attrs.update(
        {
            "title": f"bouncedisk start-up under load of scene '{scene.name}'",
            "fast_above": float(fast_above),
            "n_impacts": impacts,
            "extend": int(extend),
            "rule": RULE,
            "settle": settle,
            "confidence_level": 0.95,
            "fraction_interval": "Wilson score",
        }
    )
    return out


#: The pipeline's start-up file (in the results folder) the reproduction check reads.
STARTUP_FILE = "basins/startup.nc"


def closed_case(results, scene: Callable[[], Scene]) -> tuple[str, str, str, bool, str]:
    """The reproduction check of the closed case: at e = 0.3 without load every start from rest
    reaches the one period-2 orbit (docs/model.md "Classic results"). Reads the pipeline's
    start-up file at load 0 (``results/basins/startup.nc``), else runs 16 starts of ``scene()``
    at load 0. Returns ``(claim, measured, expected, passed, source)``."""
    from ..io.netcdf import open_checked

    path = None if results is None else results / STARTUP_FILE
    ds = None
    if path is not None and path.is_file():
        ds = open_checked(path, required=("label", "regime"), what="start-up under load")
        source = str(path)
        if 0.0 not in ds["load_torque"].values:  # the pipeline's loads do not start at 0
            ds = None
    if ds is None:
        grid = start_grid(8, [0.0], [0.0, 0.5])
        ds = startup(scene(), [0.0], grid, math.inf, cores=2)
        source = f"simulated ({ds.attrs['scene_name']}.yaml, load 0, {grid.size} starts)"
    at = ds.sel(load_torque=0.0)
    n = int(at.sizes["start"])
    periodic = at["regime"].values == ob.REGIME_CODES["periodic"]
    p2 = periodic & (at["period_p"].values == 2) & (at["period_q"].values == 2)
    one = bool(np.all(at["label"].values == 0)) and int(at["n_attractors"]) == 1
    low, _ = wilson(int(p2.sum()), n)
    return (
        "e = 0.3 without load: every start from rest reaches the one period-2 orbit (basins)",
        f"{int(at['n_attractors'])} attractor(s); {int(p2.sum())} of {n} starts on period-2 "
        f"(95% Wilson lower bound {low:.3f}), {int(np.sum(at['label'].values < 0))} not settled",
        "one attractor, periodic 2/2, every start",
        one and bool(np.all(p2)),
        source,
    )
