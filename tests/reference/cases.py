"""Scenes whose complete engine output is stored in ``tests/data/reference/`` (one ``.npz`` each).

The stored arrays are the engine's output at the time the references were made; the test
``tests/test_reference_outputs.py`` holds every later version of the engine to them, bit for bit.
Regenerate only on purpose, for a change that is meant to alter outputs:
``python tests/reference/make_references.py``.
"""

from __future__ import annotations

SCENES = "workflow/config/scenes"

#: name -> (scene file, --set overrides)
CASES: dict[str, tuple[str, list[str]]] = {
    "fig3_trajectory": (f"{SCENES}/fig3.yaml", ["outputs.trajectory.dt=0.05"]),
    "fig4_long": (f"{SCENES}/fig4.yaml", ["stop={impacts: 20000}", "outputs={events: true}"]),
    "axial_e06_chatter": (f"{SCENES}/poincare_e06.yaml", ["stop={impacts: 30000}"]),
    "axial_e05_locked": (
        f"{SCENES}/regime_map.yaml",
        ["parameters.e=0.5", "parameters.omega_s=1.126", "stop={impacts: 3000}"],
    ),
    "clipped_model": (f"{SCENES}/clipped_comparison.yaml", ["model=clipped"]),
    "bouncing_vs_clipped": (f"{SCENES}/clipped_comparison.yaml", ["parameters.psi=1.5707963"]),
    "strobe_e03": (
        f"{SCENES}/poincare_e03.yaml",
        ["stop={impacts: 2000}", "outputs={events: true, stroboscopic: true}"],
    ),
    "kinetic_static": (
        f"{SCENES}/fig4.yaml",
        [
            "effects=[impacts, contact, torsion, kinetic_static]",
            "parameters.mu_ratio=1.5",
            "parameters.r_phi=0.1",
            "stop={impacts: 3000}",
            "outputs={events: true}",
        ],
    ),
    "stator_inertia": (
        f"{SCENES}/fig4.yaml",
        [
            "effects=[impacts, contact, torsion, stator_inertia]",
            "parameters.inertia_ratio=2.0",
            "stop={impacts: 3000}",
            "outputs={events: true}",
        ],
    ),
    "plastic_e0": (
        f"{SCENES}/fig3.yaml",
        [
            "parameters.e=0.0",
            "parameters.psi=1.0",
            "stop={time: 200.0}",
            "outputs={trajectory: {dt: 0.1}}",
        ],
    ),
}
