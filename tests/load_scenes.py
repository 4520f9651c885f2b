"""A small scene with the load effect, shared by the load-curve, figure and check tests."""

from __future__ import annotations

from bouncedisk.model.scene import Scene, scene_from_mapping


def small_load_scene(
    e: float = 0.6, members: int = 2, time: float = 300.0, discard: float = 50.0
) -> Scene:
    """The paper's motor (``omega_s = 1.5, R_phi = 0.01, psi = 0``) at ``e`` with the ``load``
    effect (``load_torque`` set per load), ``members`` members, ``time`` and ``discard``."""
    params = {"e": e, "omega_s": 1.5, "r_phi": 0.01, "psi": 0.0, "e_sigma": 1e-9}
    return scene_from_mapping(
        {
            "name": "small_load",
            "parameters": {**params, "load_torque": 0.0},
            "effects": ["impacts", "contact", "torsion", "restitution_noise", "load"],
            "stop": {"time": time},
            "ensemble": {"members": members, "seed": 1},
            "stats": {"discard": discard},
        },
        "<small load scene>",
    )
