"""Parameter sweeps: regime maps, motor curves and bifurcation diagrams, from ensembles.

A sweep takes a base scene and a grid of parameter values. Every grid point is the scene's
ensemble (:mod:`bouncedisk.analysis.ensembles`), reduced to ensemble statistics with 95 % intervals
(:mod:`bouncedisk.analysis.statistics`): a long-run number from one run of a chaotic scene is not a result
(docs/model.md "Long-run statistics of chaotic motion"). The first swept parameter is split into
contiguous shards, so every shard is a hypercube block and shards join with
``xarray.combine_by_coords`` (``open_mfdataset`` too, where dask is installed).

:func:`run_continuation` follows attractors instead: each point of a 1-D sweep starts from the
previous point's final state, up or down, so coexisting attractors both appear.
"""

from __future__ import annotations

import contextlib
import dataclasses
import time
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
import xarray as xr

from ..engine import EngineConfig, InitialState
from ..io.provenance import base_attrs, new_run_id
from ..model import stator
from ..model.engine_config import engine_config
from ..model.errors import InputError, plain
from ..model.scene import Scene
from ..run.runner import scene_attrs
from . import observables as ob
from .ensembles import CappedRun, run_member
from .statistics import (
    QUANTITIES,
    EnsembleStats,
    capped_error,
    confidence_interval,
    ensemble_window,
)

SWEEPABLE = ("e", "omega_s", "r_phi", "psi")
#: Quantities a sweep records per point, each with ``<name>_ci_low`` and ``<name>_ci_high``.
SWEPT = ("mean_omega", "mean_slip", "impact_rate", "chatter_rate", "lyapunov")


def grid_values(spec: dict) -> np.ndarray:
    """Values of one swept parameter from ``{min, max, n}`` or ``{values: [...]}``."""
    if "values" in spec:
        return np.asarray(spec["values"], dtype=float)
    return np.linspace(float(spec["min"]), float(spec["max"]), int(spec["n"]))


def shard_slice(n: int, shard: int, n_shards: int) -> slice:
    """Contiguous block ``shard`` of ``n`` items split into ``n_shards`` nearly equal blocks."""
    if not 0 <= shard < n_shards:
        raise InputError("sweep", "shard", f"must be in [0, {n_shards}), got {shard}")
    edges = np.linspace(0, n, n_shards + 1).round().astype(int)
    return slice(int(edges[shard]), int(edges[shard + 1]))


def with_params(scene: Scene, **values: float) -> Scene:
    """A copy of ``scene`` with some nondimensional parameters replaced (validated)."""
    params = scene.params.replaced(scene.source, **values)
    raw = dict(scene.raw)
    raw["parameters"] = {**(raw.get("parameters") or {}), **values}
    return dataclasses.replace(scene, params=params, raw=raw)


@dataclasses.dataclass
class PointResult:
    """One grid point: ensemble statistics, member 0's event tail and final state."""

    stats: EnsembleStats
    tail: dict[str, np.ndarray]
    final: dict[str, float]


MemberTask = tuple[EngineConfig, InitialState, int, float]


def _member_tasks(scene: Scene, init: InitialState | None = None) -> list[MemberTask]:
    """The runs of a point's ensemble: :func:`run_member`'s arguments, member by member."""
    t_from, _ = ensemble_window(scene)
    cfg = engine_config(scene)
    return [(cfg, init or scene.initial, m, t_from) for m in range(scene.ensemble.members)]


def _point_result(scene: Scene, runs: Sequence[tuple]) -> PointResult:
    """A point's statistics from its members' runs (:func:`run_member`'s results, in order)."""
    t_from, t_end = ensemble_window(scene)
    stats = EnsembleStats([st for st, _, _ in runs], scene.stats.discard, t_end - t_from)
    _, final, tail = runs[0]
    return PointResult(stats, tail, final)


@contextlib.contextmanager
def _point_named(scene: Scene, names: Sequence[str]) -> Iterator[None]:
    """A member of the point ``scene`` that stops at ``stop.max_events`` before its window ends:
    an input error naming the scene, the field and the point's swept values
    (:func:`~bouncedisk.analysis.statistics.capped_error`)."""
    try:
        yield
    except CappedRun as ex:
        point = ", ".join(f"{n} = {plain(getattr(scene.params, n))}" for n in names)
        raise capped_error(scene, ex, f" at the sweep point {point}") from None


def _ordered_runs(
    pool: ThreadPoolExecutor, tasks: Iterator[MemberTask], ahead: int
) -> Iterator[tuple]:
    """:func:`run_member` of every task on ``pool``, the results in the tasks' order, whatever
    order the threads finish in; at most ``ahead`` tasks are submitted and not yet taken, so the
    memory is bounded whatever the sweep's size."""
    pending: deque[Future] = deque()
    for task in tasks:
        pending.append(pool.submit(run_member, *task))
        if len(pending) >= ahead:
            yield pending.popleft().result()
    while pending:
        yield pending.popleft().result()


def run_point(scene: Scene, init: InitialState | None = None) -> PointResult:
    """Run a scene's ensemble at one grid point, members in turn (:func:`run_sweep` runs the
    members of its points side by side, and shards split a sweep over jobs)."""
    return _point_result(scene, [run_member(*task) for task in _member_tasks(scene, init)])


class _Grid:
    """Per-point arrays of a sweep: statistics with intervals, regime, and an event tail."""

    def __init__(self, shape: tuple[int, ...], tail: int):
        self.tail = tail
        self.values = {k: np.full(shape, np.nan) for k in self.names()}
        self.ints = {k: np.zeros(shape, np.int16) for k in ("regime", "period_p", "period_q")}
        self.phase = np.full(shape + (tail,), np.nan)
        self.v_rel = np.full(shape + (tail,), np.nan)
        self.chatter = np.zeros(shape + (tail,), np.int8)
        self.n_events = np.zeros(shape, np.int64)

    @staticmethod
    def names() -> list[str]:
        out = [f"{q}{s}" for q in SWEPT for s in ("", "_ci_low", "_ci_high")]
        return out + ["regime_fraction", "lyapunov_reset_fraction"]

    def put(self, idx: tuple[int, ...], point: PointResult) -> None:
        st = point.stats
        for q in SWEPT:
            col = st.column(q)
            mean, low, high = confidence_interval(col)
            self.values[q][idx], self.values[f"{q}_ci_low"][idx] = mean, low
            self.values[f"{q}_ci_high"][idx] = high
        name, frac, period = st.regime
        self.ints["regime"][idx] = ob.REGIME_CODES[name]
        self.ints["period_p"][idx], self.ints["period_q"][idx] = period or (0, 0)
        self.values["regime_fraction"][idx] = frac
        self.values["lyapunov_reset_fraction"][idx] = float(
            np.mean(np.isneginf(st.column("lyapunov")))
        )
        k = min(self.tail, len(point.tail["t"]))
        if k:
            self.phase[idx][:k] = point.tail["phase"][-k:]
            self.v_rel[idx][:k] = point.tail["v_rel"][-k:]
            self.chatter[idx][:k] = point.tail["kind"][-k:] == ob.KIND_CHATTER
        self.n_events[idx] = int(sum(m.n_impacts + m.n_chatter for m in st.members))

    def dataset(self, dims: tuple[str, ...], coords: dict) -> xr.Dataset:
        data = {}
        for q in SWEPT:
            long_name, units = QUANTITIES[q]
            data[q] = (dims, self.values[q], {"long_name": f"ensemble mean of the {long_name}"})
            for s, what in (("_ci_low", "lower"), ("_ci_high", "upper")):
                data[f"{q}{s}"] = (
                    dims,
                    self.values[f"{q}{s}"],
                    {"long_name": f"{what} end of the 95% interval of {q}", "units": units},
                )
        data["regime"] = (dims, self.ints["regime"], regime_attrs())
        data["regime_fraction"] = (
            dims,
            self.values["regime_fraction"],
            {"long_name": "fraction of members in the reported regime", "units": "1"},
        )
        data["lyapunov_reset_fraction"] = (
            dims,
            self.values["lyapunov_reset_fraction"],
            {"long_name": "fraction of members reset every cycle (exponent -inf)", "units": "1"},
        )
        for k, what in (("period_p", "impacts"), ("period_q", "stator periods")):
            data[k] = (dims, self.ints[k], {"long_name": f"{what} per cycle (0: not periodic)"})
        ev_dims = dims + ("impact",)
        for name, values, long_name, units in (
            ("phase", self.phase, "stator phase at the event, member 0 tail", "rad"),
            ("v_rel", self.v_rel, "relative impact velocity, member 0 tail", "1"),
            ("is_chatter", self.chatter, "the event is a complete chatter (a reset)", "1"),
        ):
            data[name] = (ev_dims, values, {"long_name": long_name, "units": units})
        # per point, so that any join of shards (open_mfdataset too) sums to the sweep's total
        data["n_events"] = (
            dims,
            self.n_events,
            {"long_name": "events after the transient, all members", "units": "1"},
        )
        return xr.Dataset(data, coords=coords)


def regime_attrs() -> dict:
    """CF flag attributes of a ``regime`` variable (:data:`bouncedisk.analysis.observables.REGIMES`)."""
    return {
        "long_name": "dynamical regime (most common among members)",
        "units": "1",
        **ob.regime_flags(np.int16),
        "comment": "periodic regimes: period_p impacts every period_q stator periods",
    }


def _sweep_attrs(
    scene: Scene, names: Sequence[str], title: str, grid: _Grid, start: float, run: str
) -> dict:
    """Global attributes of a sweep or continuation: provenance, ensemble, counts, timing."""
    attrs = base_attrs(title)
    sa = scene_attrs(scene)
    for n in list(names) + ["gamma"]:
        sa.pop(n, None)
    attrs.update(sa)
    attrs.update(
        {
            "ensemble_members": scene.ensemble.members,
            "ensemble_seed": scene.ensemble.seed,
            "stats_discard": scene.stats.discard,
            "confidence_level": 0.95,
            "n_impacts": int(grid.n_events.sum()),
            "status": "completed",
            "run_id": new_run_id(f"{scene.name}-{run}", scene.sha256),
            "wall_time_s": round(time.perf_counter() - start, 6),
        }
    )
    return attrs


def run_sweep(
    scene: Scene,
    axes: Sequence[tuple[str, np.ndarray]],
    shard: int = 0,
    n_shards: int = 1,
    tail: int = 200,
    progress: Callable[[int, int], None] | None = None,
    cores: int = 1,
) -> xr.Dataset:
    """Run one shard of a sweep over the grid ``axes`` (name, values) pairs.

    Returns a Dataset with the swept parameters as dimensions (the first one restricted to this
    shard's block) and per point the ensemble means of :data:`SWEPT` with their 95 % intervals
    (``<name>_ci_low``, ``<name>_ci_high``), the regime, and member 0's last ``tail`` events.
    The members of every point run on ``cores`` threads (the kernel releases the GIL), each
    thread taking the next member as it finishes one, so members and points of unequal cost
    balance themselves; a point's numbers do not depend on ``cores``. ``progress(done, total)``
    is called in grid order.
    """
    names = [a for a, _ in axes]
    for name in names:
        if name not in SWEEPABLE:
            raise InputError(scene.source, f"sweep.{name}", f"cannot sweep (known: {SWEEPABLE})")
    ensemble_window(scene)
    values = [np.asarray(v, float) for _, v in axes]
    values[0] = values[0][shard_slice(len(values[0]), shard, n_shards)]
    shape = tuple(len(v) for v in values)
    grid = _Grid(shape, tail)
    total = int(np.prod(shape))
    start = time.perf_counter()
    made: deque[tuple[tuple[int, ...], Scene]] = deque()  # points whose members are submitted

    def tasks() -> Iterator[MemberTask]:
        for idx in np.ndindex(*shape):
            sc = with_params(scene, **{names[d]: float(values[d][i]) for d, i in enumerate(idx)})
            made.append((idx, sc))
            yield from _member_tasks(sc)

    members = scene.ensemble.members  # every point's (a sweep changes parameters only)
    pool = ThreadPoolExecutor(max_workers=max(1, cores))
    try:
        runs = _ordered_runs(pool, tasks(), ahead=2 * max(1, cores) * members)
        for count in range(total):
            with _point_named(made[0][1] if made else scene, names):
                point_runs = [next(runs) for _ in range(members)]
            idx, sc = made.popleft()
            grid.put(idx, _point_result(sc, point_runs))
            if progress:
                progress(count + 1, total)
    finally:  # an error or Ctrl-C: the members not started are dropped, not run
        pool.shutdown(wait=True, cancel_futures=True)
    coords = {
        n: (n, v, {"units": "rad" if n == "psi" else "1", "long_name": n})
        for n, v in zip(names, values, strict=True)
    }
    ds = grid.dataset(tuple(names), coords)
    title = f"bouncedisk sweep of scene '{scene.name}' over {', '.join(names)}"
    ds.attrs.update(_sweep_attrs(scene, names, title, grid, start, f"sweep{shard}"))
    # a shard's count is named as such: open_mfdataset keeps the first file's attributes, and
    # a joined sweep's total is n_events.sum() (or n_impacts of combine_shards)
    ds.attrs["shard_n_impacts"] = ds.attrs.pop("n_impacts")
    ds.attrs.update({"swept": ",".join(names), "shard": shard, "n_shards": n_shards, "tail": tail})
    return ds


def _continued(final: dict[str, float], scene: Scene) -> InitialState:
    """The state that continues a run from its final state, at the scene's clock origin.

    The clock restarts at the same stator phase within the first period after
    ``scene.initial.t``; a rotor riding the stator (position and velocity the stator's, to
    rounding) restarts in contact.
    """
    w = scene.params.omega_s
    period = 2.0 * np.pi / w
    t = scene.initial.t + float(np.mod(final["t"] - scene.initial.t, period))
    us, vs = stator.position(w * final["t"]), stator.velocity(w * final["t"], w)
    riding = abs(final["u"] - us) <= 1e-9 and abs(final["v"] - vs) <= 1e-9 * (1.0 + w)
    if final["in_contact"] or riding:
        return InitialState(t=t, omega=final["omega"])
    return InitialState(t=t, omega=final["omega"], u=final["u"], v=final["v"])


def run_continuation(
    scene: Scene,
    name: str,
    values: np.ndarray,
    direction: str = "up",
    tail: int = 150,
    progress: Callable[[int, int], None] | None = None,
) -> xr.Dataset:
    """Numerical continuation along one parameter (docs/model.md "Regimes": coexisting attractors).

    The points are visited in increasing (``up``) or decreasing (``down``) order; every point
    starts from member 0's final state at the previous point, with the clock reset to the
    scene's initial time, so an attractor is followed until it disappears. Returns the same
    variables as :func:`run_sweep`, with ``direction`` as a global attribute.
    """
    if direction not in ("up", "down"):
        raise InputError(scene.source, "direction", f"must be 'up' or 'down', got {direction!r}")
    if name not in SWEEPABLE:
        raise InputError(scene.source, f"sweep.{name}", f"cannot sweep (known: {SWEEPABLE})")
    ensemble_window(scene)
    order = np.sort(np.asarray(values, float))
    if direction == "down":
        order = order[::-1]
    grid = _Grid((len(order),), tail)
    init = None
    start = time.perf_counter()
    for i, x in enumerate(order):
        sc = with_params(scene, **{name: float(x)})
        with _point_named(sc, [name]):
            pt = run_point(sc, init)
        grid.put((i,), pt)
        init = _continued(pt.final, scene)
        if progress:
            progress(i + 1, len(order))
    ds = grid.dataset((name,), {name: (name, order, {"units": "1", "long_name": name})})
    ds = ds.sortby(name)
    title = f"bouncedisk continuation of '{scene.name}' in {name}"
    ds.attrs.update(_sweep_attrs(scene, [name], title, grid, start, direction))
    ds.attrs.update({"swept": name, "direction": direction, "tail": tail})
    return ds


def combine_shards(shards: Sequence[xr.Dataset]) -> xr.Dataset:
    """Join sweep shards along their swept dimensions; ``n_impacts`` sums the shards'."""
    ds = xr.combine_by_coords(list(shards), combine_attrs="drop_conflicts")
    ds.attrs.pop("shard", None)
    ds.attrs.pop("shard_n_impacts", None)
    first = shards[0].attrs
    ds.attrs["run_id"] = new_run_id(
        f"{first.get('scene_name', 'sweep')}-sweep", str(first.get("scene_sha256", "0" * 8))
    )
    ds.attrs["shard_run_ids"] = ",".join(str(s.attrs.get("run_id")) for s in shards)
    ds.attrs["wall_time_s"] = float(sum(float(s.attrs.get("wall_time_s", 0.0)) for s in shards))
    ds.attrs["n_impacts"] = int(
        sum(int(s.attrs.get("shard_n_impacts", s.attrs.get("n_impacts", 0))) for s in shards)
    )
    return ds
