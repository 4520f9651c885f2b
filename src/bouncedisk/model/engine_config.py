"""A scene translated into the engine's configuration (one place)."""

from __future__ import annotations

import math

from ..engine import EngineConfig
from .scene import Scene


def engine_config(scene: Scene) -> EngineConfig:
    """Translate a scene into the engine's configuration."""
    p = scene.params
    eff = scene.effects
    traj = scene.outputs.trajectory
    t_end = scene.stop.time if scene.stop.time is not None else math.inf
    return EngineConfig(
        e=p.e,
        omega_s=p.omega_s,
        r_phi=p.r_phi,
        psi=p.psi,
        contact="contact" in eff,
        torsion="torsion" in eff,
        impulse_cap="impulse_cap" in eff,
        inertia_ratio=p.inertia_ratio if "stator_inertia" in eff else math.inf,
        mu_ratio=p.mu_ratio if "kinetic_static" in eff else 1.0,
        tol=scene.solver.tol,
        t_end=t_end,
        max_events=scene.stop.impacts if scene.stop.impacts is not None else scene.stop.max_events,
        traj_dt=traj.dt if traj else 0.0,
        traj_t0=traj.t_start if traj and traj.t_start is not None else scene.initial.t,
        traj_t1=traj.t_stop if traj and traj.t_stop is not None else math.inf,
        stroboscopic=scene.outputs.stroboscopic,
        clipped=scene.model == "clipped",
        e_sigma=p.e_sigma if "restitution_noise" in eff else 0.0,
        seed=scene.ensemble.seed,
        load_torque=p.load_torque if "load" in eff else 0.0,
    )


def motor_config(e: float, omega_s: float, r_phi: float, psi: float, **run) -> EngineConfig:
    """The engine's configuration of the motor the fit models: impacts, sticking contact and
    torsion (docs/model.md "Phases of motion", "Events") at ``(e, omega_s, r_phi, psi)``, with
    the run's own settings ``run`` (stop, samples, restitution noise, seed, member)."""
    return EngineConfig(
        e=e, omega_s=omega_s, r_phi=r_phi, psi=psi, contact=True, torsion=True, **run
    )
