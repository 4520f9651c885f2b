"""Run a scene: engine (or comparator solver) → streamed netCDF with provenance.

This is the one place that joins a validated :class:`~bouncedisk.model.scene.Scene`, the engine and
the file writer; the CLI and the pipeline's scripts call :func:`run_scene`.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import signal
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import NoReturn

from ..engine import EngineError, RunResult, iterate, simulate_arrays
from ..engine.driver import Chunk, Returning, audit_balances
from ..io.atomic import stop_checks
from ..io.netcdf import SimulationWriter
from ..io.provenance import base_attrs, new_run_id
from ..io.records import RunStatus
from ..model.engine_config import engine_config
from ..model.errors import InputError
from ..model.scene import Scene, require_scene


def _chunks(scene: Scene) -> Iterator[Chunk]:
    """Chunks from the scene's solver (the exact engine or a comparator)."""
    if scene.solver.method == "exact":
        # the energy audit over the whole run (docs/model.md "Power and energy audit")
        cfg = dataclasses.replace(engine_config(scene), stats_from=scene.initial.t)
        return iterate(cfg, scene.initial)
    from .comparators import iterate_comparator

    return iterate_comparator(scene)


def _status_text(scene: Scene, code: int) -> str:
    if code == RunStatus.EVENTS and scene.stop.kind == "time":
        return f"cap: stopped at the safety cap stop.max_events = {scene.stop.max_events}"
    return RunStatus(code).text


class Progress:
    """Progress on stderr for runs longer than ``delay`` seconds (a bar on a terminal)."""

    def __init__(
        self,
        label: str,
        total_events: int | None,
        t_end: float | None,
        t_start: float,
        delay: float = 2.0,
        stream=None,
    ):
        self.label = label
        self.total_events = total_events
        self.t_end = t_end
        self.t_start = t_start
        self.delay = delay
        self.stream = stream or sys.stderr
        self.start = time.monotonic()
        self.last = 0.0
        self.shown = False
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()

    def fraction(self, events: int, t_now: float) -> float:
        """Fraction done, from events or time (nan when neither bounds the run)."""
        if self.total_events:
            return min(1.0, events / self.total_events)
        if self.t_end and math.isfinite(self.t_end) and self.t_end > self.t_start:
            return min(1.0, (t_now - self.t_start) / (self.t_end - self.t_start))
        return math.nan

    def update(self, events: int, t_now: float) -> None:
        """Show progress (after ``delay`` s; twice a second on a terminal, every 10 s otherwise)."""
        now = time.monotonic()
        elapsed = now - self.start
        if elapsed < self.delay or now - self.last < (0.5 if self.tty else 10.0):
            return
        self.last = now
        frac = self.fraction(events, t_now)
        eta = elapsed * (1 - frac) / frac if frac and frac > 0 and math.isfinite(frac) else math.nan
        bar = ""
        if math.isfinite(frac):
            filled = int(30 * frac)
            bar = f"[{'#' * filled}{'.' * (30 - filled)}] {100 * frac:5.1f}% "
        msg = f"{self.label}: {bar}{events:,} events, t = {t_now:.6g}, {elapsed:.0f} s" + (
            f", ~{eta:.0f} s left" if math.isfinite(eta) else ""
        )
        if self.tty:
            self.stream.write("\r" + msg)
        else:
            self.stream.write(msg + "\n")
        self.stream.flush()
        self.shown = True

    def close(self) -> None:
        """End the progress line."""
        if self.shown and self.tty:
            self.stream.write("\n")
            self.stream.flush()


class StopRequest:
    """Signal handler that only records the request; the run stops at a safe point."""

    def __init__(self) -> None:
        self.signum: int | None = None

    def __call__(self, signum, frame) -> None:
        self.signum = signum

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` (outside any file write) if a stop was requested."""
        if self.signum is not None:
            raise KeyboardInterrupt


@contextlib.contextmanager
def deferred_interrupts() -> Iterator[StopRequest]:
    """During the block, SIGINT and SIGTERM set a flag instead of interrupting the code.

    A signal landing inside a netCDF/HDF5 call could leave the library unable to close the file;
    the run loop calls :meth:`StopRequest.check` between chunks instead. A request pending when
    an output is about to be renamed into place vetoes the rename
    (:func:`bouncedisk.io.atomic.stop_checks`), and one that arrived during the block raises
    ``KeyboardInterrupt`` when it ends: an interrupt is never answered by a normal exit. The
    request is then handed to the handler the block replaced (the command's stops the command
    and ignores a second signal), unless the block failed otherwise.
    """
    req = StopRequest()
    old = {}
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            old[sig] = signal.signal(sig, req)
    except ValueError:  # not the main thread: the host keeps its handlers
        pass
    failed: BaseException | None = None
    try:
        with stop_checks(req.check):
            yield req
    except BaseException as ex:
        failed = ex
        raise
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)
        if old and req.signum is not None and isinstance(failed, KeyboardInterrupt | None):
            _deliver(old[req.signum], req.signum)


def _deliver(handler, signum: int) -> NoReturn:
    """Hand a deferred SIGINT or SIGTERM to ``handler``, the one the block replaced, and stop
    (``KeyboardInterrupt``) whatever it does."""
    if callable(handler):
        handler(signum, None)
    raise KeyboardInterrupt


@dataclass
class RunSummary:
    """What a run wrote: file, run id, status, event counts and wall time."""

    path: Path
    run_id: str
    status: str
    n_events: int
    n_impacts: int
    n_chatter: int
    wall_time_s: float


def scene_attrs(scene: Scene) -> dict:
    """Global attributes describing a scene (docs/formats.md)."""
    p = scene.params
    i = scene.initial
    attrs = {
        "e": p.e,
        "omega_s": p.omega_s,
        "r_phi": p.r_phi,
        "psi": p.psi,
        "gamma": p.gamma,
        "model": scene.model,
        "effects": ",".join(sorted(scene.effects)),
        "solver": scene.solver.method,
        "tol": scene.solver.tol,
        "scene_name": scene.name,
        "scene_sha256": scene.sha256,
        "scene_description": scene.description,
        "initial_t": i.t,
        "initial_omega": i.omega,
        "initial_condition": (
            "rotor in contact, moving with the stator"
            if i.u is None
            else f"rotor in flight at u = {i.u!r}, v = {i.v!r}"
        ),
        "stop": (
            f"impacts = {scene.stop.impacts}"
            if scene.stop.impacts is not None
            else f"time = {scene.stop.time!r}"
        ),
    }
    if "stator_inertia" in scene.effects:
        attrs["inertia_ratio"] = p.inertia_ratio
    if "kinetic_static" in scene.effects:
        attrs["mu_ratio"] = p.mu_ratio
    if "restitution_noise" in scene.effects:
        attrs.update({"e_sigma": p.e_sigma, "ensemble_seed": scene.ensemble.seed})
    if "load" in scene.effects:
        attrs["load_torque"] = p.load_torque
    if scene.ensemble.members > 1:
        attrs["ensemble_members"] = scene.ensemble.members
    if scene.solver.step is not None:
        attrs["step"] = scene.solver.step
    if scene.physical is not None:
        sc = scene.physical.scales()
        attrs.update({"t_c_s": sc.t_c, "omega_scale_rad_s": sc.omega_scale, "U0_m": sc.length})
        attrs.update({f"physical_{k}": v for k, v in scene.physical.as_dict().items()})
    return attrs


def run_scene(
    scene: Scene,
    out: str | Path,
    progress: bool = True,
    on_chunk: Callable[[Chunk], None] | None = None,
    command: str = "",
    max_output_bytes: float | None = None,
) -> RunSummary:
    """Run ``scene`` and write its netCDF file to ``out`` (atomically).

    ``max_output_bytes`` (default: :func:`bouncedisk.io.output_checks.default_max_output`) bounds the
    file: a scene whose output would exceed it is refused before it runs, and a run that
    crosses it anyway (a time stop with more impacts than expected) stops with no output.

    Raises
    ------
    InputError
        When ``out`` cannot be written (a folder, a read-only place), the scene leaves out an
        effect its dynamics need (names ``effects``), or its output would exceed
        ``max_output_bytes``.
    EngineError
        On a numerical failure of the engine.
    """
    from ..io.output_checks import check_output_path, check_output_size, default_max_output

    scene = require_scene(scene)
    out = check_output_path(out, "out")  # a folder or an unwritable place: before the run
    limit = default_max_output() if max_output_bytes is None else max_output_bytes
    check_output_size(scene, out, limit)
    run_id = new_run_id(scene.name, scene.sha256)
    prog = (
        Progress(scene.name, scene.stop.impacts, scene.stop.time, scene.initial.t)
        if progress
        else None
    )
    start = time.perf_counter()
    gen = _chunks(scene)
    try:
        with deferred_interrupts() as stop_request, _writer(scene, out, limit) as writer:
            code, final = _stream(gen, writer, stop_request, on_chunk, prog)
            wall = time.perf_counter() - start
            status = _status_text(scene, code)
            attrs = _run_attrs(scene, writer, run_id, wall, status, code, final, command)
            writer.set_attrs(attrs)
    except EngineError as ex:
        _raise_missing_effect(scene, ex)
        raise
    finally:
        if prog:
            prog.close()
    return RunSummary(
        out, run_id, status, writer.n_events, writer.n_impacts, writer.n_chatter, wall
    )


def _writer(scene: Scene, out: Path, limit: float) -> SimulationWriter:
    """The streaming netCDF writer for what ``scene`` asks to output."""
    return SimulationWriter(
        out,
        torsion=scene.has("torsion"),
        events=scene.outputs.events,
        trajectory=scene.outputs.trajectory is not None,
        strobe=scene.outputs.stroboscopic,
        omega_s=scene.params.omega_s,
        t_c=scene.scales.t_c if scene.scales else None,
        max_bytes=limit,
    )


def _stream(
    gen: Iterator[Chunk],
    writer: SimulationWriter,
    stop_request: StopRequest,
    on_chunk: Callable[[Chunk], None] | None,
    prog: Progress | None,
) -> tuple[int, dict[str, float]]:
    """Write every chunk of a run; return the engine's ``(status code, final state)``.

    A stop request (SIGINT, SIGTERM) is honoured between chunks, never inside a write.
    """
    chunks = Returning(gen)
    stop_request.check()
    for c in chunks:
        stop_request.check()
        writer.append(c)
        if on_chunk is not None:
            on_chunk(c)
        if prog:
            prog.update(c.n_events_total, c.t_now)
        stop_request.check()
    return chunks.value


def _run_attrs(
    scene: Scene,
    writer: SimulationWriter,
    run_id: str,
    wall: float,
    status: str,
    code: int,
    final: dict[str, float],
    command: str,
) -> dict:
    """Global attributes of a simulation file: CF/ACDD, the scene, the run and its final state."""
    attrs = base_attrs(
        f"bouncedisk simulation of scene '{scene.name}'",
        summary=(
            "Event-driven simulation of a rotor bouncing on a vibrating, twisting stator "
            f"(scene '{scene.name}': e = {scene.params.e:g}, omega_s = "
            f"{scene.params.omega_s:g}): one row per impact or chattering tail"
            + (", a dense trajectory" if scene.outputs.trajectory else "")
            + (", a stroboscopic section" if scene.outputs.stroboscopic else "")
            + ". Nondimensional units (lengths by U0, time by t_c) unless a variable "
            "says otherwise."
        ),
    )
    attrs.update(scene_attrs(scene))
    attrs.update(
        {
            "run_id": run_id,
            "wall_time_s": round(wall, 6),
            "n_impacts": writer.n_impacts,
            "n_chatter": writer.n_chatter,
            "n_events": writer.n_events,
            "status": status,
            "final_t": final["t"],
            "final_omega": final["omega"],
            "final_in_contact": int(bool(final["in_contact"]) or code == RunStatus.REST),
            "history": f"{attrs['created']}: {command or 'bouncedisk.run.runner.run_scene'}",
        }
    )
    if "audit" in final:
        terms = final["audit"]
        attrs["audit_residual_axial"], attrs["audit_residual_torsion"] = audit_balances(terms)
        attrs.update({f"audit_{k}": v for k, v in terms.items()})
    return attrs


def _raise_missing_effect(scene: Scene, ex: EngineError) -> None:
    """A run that needs the ``contact`` effect is the scene's fault: an :class:`InputError`."""
    if ex.code == RunStatus.NEED_CONTACT:
        raise InputError(scene.source, "effects", str(ex)) from None


def run_scene_arrays(scene: Scene) -> RunResult:
    """Run ``scene`` in memory (analysis, sweeps). Raises like :func:`run_scene`."""
    scene = require_scene(scene)
    try:
        if scene.solver.method == "exact":
            return simulate_arrays(engine_config(scene), scene.initial)
        from .comparators import simulate_comparator

        return simulate_comparator(scene)
    except EngineError as ex:
        _raise_missing_effect(scene, ex)
        raise
