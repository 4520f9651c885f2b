"""Scenes whose complete engine output is stored in ``tests/data/reference/`` (one ``.npz`` each).

The stored arrays are the engine's output at the time the references were made; the test
``tests/test_reference_outputs.py`` holds every later version of the engine to them, bit for bit.
Regenerate only on purpose, for a change that is meant to alter outputs:
``python tests/reference/make_references.py``.
"""

from __future__ import annotations

#: The scene files as they were when the references were made (the workflow's own copies may
#: change; these may not).
BASES: dict[str, str] = {
    "fig3": """\
name: fig3
description: "Paper Fig. 3: regular (period-2) bouncing, e = 0.3"
parameters: {e: 0.3, omega_s: 1.5, r_phi: 0.01, psi: 0.0}
initial: {t: 0.0, omega: 0.0}
effects: [impacts, contact, torsion]
stop: {impacts: 300}
outputs:
  events: true
  trajectory: {dt: 0.01}
solver: {method: exact, tol: 1.0e-12}
""",
    "fig4": """\
name: fig4
description: "Paper Fig. 4: irregular (chaotic) bouncing, e = 0.6"
parameters: {e: 0.6, omega_s: 1.5, r_phi: 0.01, psi: 0.0}
initial: {t: 0.0, omega: 0.0}
effects: [impacts, contact, torsion]
stop: {impacts: 300}
outputs:
  events: true
  trajectory: {dt: 0.01}
solver: {method: exact, tol: 1.0e-12}
""",
    "poincare_e06": """\
name: poincare_e06
description: "Impact and stroboscopic maps of the chaotic attractor, e = 0.6"
parameters: {e: 0.6, omega_s: 1.5, r_phi: 0.01, psi: 0.0}
effects: [impacts, contact]
stop: {impacts: 20000}
outputs: {events: true, stroboscopic: true}
solver: {method: exact, tol: 1.0e-12}
""",
    "poincare_e03": """\
name: poincare_e03
description: "Impact and stroboscopic maps of the period-2 attractor, e = 0.3"
parameters: {e: 0.3, omega_s: 1.5, r_phi: 0.01, psi: 0.0}
effects: [impacts, contact]
stop: {impacts: 20000}
outputs: {events: true, stroboscopic: true}
solver: {method: exact, tol: 1.0e-12}
""",
    "clipped_comparison": """\
name: clipped_comparison
description: "Bouncing model against the clipped-sinusoid spring contact of refs. [2, 3]"
parameters: {e: 0.6, omega_s: 1.5, r_phi: 0.01, psi: 0.0}
effects: [impacts, contact, torsion]
stop: {time: 1500.0}
outputs: {events: true, trajectory: {dt: 0.5}}
solver: {method: exact, tol: 1.0e-12}
""",
    "regime_map": """\
name: regime_map
description: "Base scene of the regime map over (e, omega_s)"
parameters: {e: 0.3, omega_s: 1.5, r_phi: 0.01, psi: 0.0}
effects: [impacts, contact]
stop: {impacts: 3000}
outputs: {events: true}
solver: {method: exact, tol: 1.0e-12}
""",
}

#: name -> (base scene in BASES, --set overrides)
CASES: dict[str, tuple[str, list[str]]] = {
    "fig3_trajectory": ("fig3", ["outputs.trajectory.dt=0.05"]),
    "fig4_long": ("fig4", ["stop={impacts: 20000}", "outputs={events: true}"]),
    "axial_e06_chatter": ("poincare_e06", ["stop={impacts: 30000}"]),
    "axial_e05_locked": (
        "regime_map",
        ["parameters.e=0.5", "parameters.omega_s=1.126", "stop={impacts: 3000}"],
    ),
    "clipped_model": ("clipped_comparison", ["model=clipped"]),
    "bouncing_vs_clipped": ("clipped_comparison", ["parameters.psi=1.5707963"]),
    "strobe_e03": (
        "poincare_e03",
        ["stop={impacts: 2000}", "outputs={events: true, stroboscopic: true}"],
    ),
    "kinetic_static": (
        "fig4",
        [
            "effects=[impacts, contact, torsion, kinetic_static]",
            "parameters.mu_ratio=1.5",
            "parameters.r_phi=0.1",
            "stop={impacts: 3000}",
            "outputs={events: true}",
        ],
    ),
    "stator_inertia": (
        "fig4",
        [
            "effects=[impacts, contact, torsion, stator_inertia]",
            "parameters.inertia_ratio=2.0",
            "stop={impacts: 3000}",
            "outputs={events: true}",
        ],
    ),
    "plastic_e0": (
        "fig3",
        [
            "parameters.e=0.0",
            "parameters.psi=1.0",
            "stop={time: 200.0}",
            "outputs={trajectory: {dt: 0.1}}",
        ],
    ),
}
