"""Warnings about a statistic's averaging window, printed on stderr by ``bouncedisk stats`` and
``bouncedisk torque-speed`` (docs/model.md "Long-run statistics of chaotic motion").

A long-run average that starts at the start of the run carries the start-up transient; one member
of a run that is not periodic gives one round-off-chosen sample with no interval. Both still give
a number, so they warn (one line each, ``bouncedisk: warning: SCENE: FIELD: ...``) instead of
failing.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterable

from ..model.scene import Scene

#: Regimes whose one-member average is the attractor's own (no interval needed).
SETTLED = frozenset({"periodic", "chattering-periodic", "rest"})


def window_warnings(scene: Scene, regimes: Iterable[str | None]) -> list[str]:
    """The warning lines of a statistic of ``scene`` whose members ended in ``regimes``.

    Parameters
    ----------
    scene : Scene
        The scene as run (after ``--set`` overrides).
    regimes : iterable of str or None
        The majority regime of each point (one for ``stats``, one per load for ``torque-speed``).

    Returns
    -------
    list of str
        At most three lines: no ``stats.discard`` (the average includes the transient); an
        unresolved regime at some point (a transient or a cycle longer than the window,
        whatever the ensemble); one member of an irregular run (no interval, a round-off-chosen
        sample).
    """
    out = []
    if scene.stats.discard <= 0.0:
        out.append(
            f"bouncedisk: warning: {scene.source}: stats.discard: 0 (or not given), so the "
            "averages include the start-up transient; discard it, e.g. --set "
            f"stats.discard={_example_discard(scene):g}"
        )
    seen = {r for r in regimes if r is not None}
    if "unresolved" in seen:
        out.append(
            f"bouncedisk: warning: {scene.source}: stats.discard: the window shows no period and "
            "no chaos (unresolved): the run may still be in its transient, or its cycle longer "
            "than the window; discard more or run longer (stats.discard, stop.time)"
            + _long_flight(scene)
        )
    if "rest" in seen and scene.physical is not None and scene.params.omega_s < 1.0:
        p = scene.physical
        out.append(
            f"bouncedisk: warning: {scene.source}: physical: the stator's peak acceleration "
            f"U0 (2 pi f)^2 = {p.U0 * (2.0 * math.pi * p.f) ** 2:.3g} m/s^2 is below g_eff = "
            f"{p.scales().g_eff:.3g} m/s^2, so the rotor never leaves it (omega_s = "
            f"{scene.params.omega_s:.3g} < 1); check the units: f in Hz, U0 in m"
        )
    irregular = sorted(seen - SETTLED - {"unresolved"})
    if scene.ensemble.members == 1 and irregular:
        out.append(
            f"bouncedisk: warning: {scene.source}: ensemble.members: one member of an "
            f"irregular run ({'/'.join(irregular)}) is one round-off-chosen sample with no "
            "interval; use an ensemble, e.g. --set 'ensemble={members: 32, seed: 1}' with "
            "restitution_noise"
        )
    return out


def _long_flight(scene: Scene) -> str:
    """A physical scene's hint when one flight outlasts the window: a rotor launched at the
    stator's peak speed ``omega_s`` flies about ``2 omega_s`` (docs/model.md, units of t_c)."""
    window = (scene.stop.time or math.inf) - scene.initial.t - scene.stats.discard
    flight = 2.0 * scene.params.omega_s
    if scene.physical is None or not flight > window:
        return ""
    return (
        f"; a flight lasts about 2 omega_s = {flight:.3g} time units, longer than the window "
        f"({window:.3g}): check the units of physical.f (Hz) and physical.U0 (m)"
    )


def _example_discard(scene: Scene) -> float:
    """A discard to suggest: 2000 time units (a run-up at ``R_φ = 0.01``), or two fifths of a
    shorter run, one significant figure, leaving at least two stator periods to average over
    (0 where the run is shorter than that)."""
    run = (scene.stop.time or math.inf) - scene.initial.t
    if run > 5000.0:
        return 2000.0
    room = run - 2.0 * (2.0 * math.pi / scene.params.omega_s)
    return max(0.0, float(f"{min(0.4 * run, room):.1g}"))


def print_window_warnings(scene: Scene, regimes: Iterable[str | None]) -> None:
    """Print :func:`window_warnings` on stderr."""
    for line in window_warnings(scene, regimes):
        print(line, file=sys.stderr)
