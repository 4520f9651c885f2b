"""The paper's Fig. 2: the stator–rotor interface, drawn."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse, FancyArrowPatch, Rectangle

from .common import COLORS


def fig2_schematic() -> Figure:
    """Paper Fig. 2: the stator–rotor interface, the rotor simplified as a bouncing disk."""
    fig = Figure(figsize=(6.0, 4.2))
    ax = fig.add_subplot()
    ax.set_xlim(-3, 3)
    ax.set_ylim(-2.6, 2.4)
    ax.set_aspect("equal")
    ax.axis("off")
    # pretwisted beam (stator) and its tip
    ax.add_patch(Rectangle((-0.6, -2.5), 1.2, 2.0, fc="#d9d9d9", ec="k"))
    for y in np.linspace(-2.4, -0.6, 7):
        ax.plot([-0.6, 0.6], [y, y + 0.25], color="#9e9e9e", lw=0.8)
    ax.add_patch(Rectangle((-1.2, -0.5), 2.4, 0.35, fc="#bdbdbd", ec="k"))
    # rotor disk in flight above the stator
    ax.add_patch(Ellipse((0, 0.55), 3.4, 0.5, fc="#9ecae1", ec="k"))
    ax.add_patch(Rectangle((-1.7, 0.55), 3.4, 0.45, fc="#9ecae1", ec="none"))
    ax.add_patch(Ellipse((0, 1.0), 3.4, 0.5, fc="#c6dbef", ec="k"))
    ax.plot([-1.7, -1.7], [0.55, 1.0], "k", lw=1)
    ax.plot([1.7, 1.7], [0.55, 1.0], "k", lw=1)
    # contact radius on the stator face
    ax.annotate("", xy=(1.2, -0.32), xytext=(0, -0.32), arrowprops=dict(arrowstyle="<->", lw=1))
    ax.text(0.6, -0.28, "$r_c$", ha="center", va="bottom", fontsize=10)

    def arrow(x0, y0, x1, y1, **kw):
        ax.add_patch(FancyArrowPatch((x0, y0), (x1, y1), mutation_scale=12, lw=1.4, **kw))

    arrow(-2.3, -1.3, -2.3, -0.3, arrowstyle="<->", color="k")
    ax.text(-2.45, -0.8, r"$u_s = U_0\sin\omega t$", ha="right", va="center", fontsize=10)
    arrow(1.6, -1.45, 2.5, -1.15, arrowstyle="<->", color="k", connectionstyle="arc3,rad=0.4")
    ax.text(2.55, -1.55, r"$\phi_s = \Phi_0\sin(\omega t+\psi)$", ha="left", fontsize=10)
    arrow(0, 2.2, 0, 1.45, arrowstyle="->", color="k")
    ax.text(0.12, 1.85, r"$m_r g$ (+ preload)", fontsize=10)
    arrow(-2.2, 0.75, -2.2, 1.55, arrowstyle="->", color=COLORS["rotor"])
    ax.text(-2.3, 1.6, r"$u_r$", color=COLORS["rotor"], ha="right", fontsize=11)
    arrow(
        1.9, 1.2, 2.6, 0.7, arrowstyle="->", color=COLORS["rotor"], connectionstyle="arc3,rad=-0.5"
    )
    ax.text(2.65, 0.95, r"$\dot\phi_r$", color=COLORS["rotor"], fontsize=11)
    ax.text(0, 0.3, "rotor ($m_r$, $J_r = m_r r_g^2$)", ha="center", va="top", fontsize=9)
    ax.text(0, -1.5, "pretwisted beam\n(stator)", ha="center", fontsize=9)
    ax.text(-2.9, 2.2, "impact: $e$, friction: $\\mu$, $r_{eff} = 2r_c/3$", fontsize=9)
    return fig
