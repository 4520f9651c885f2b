"""Adapter: draw one figure from built netCDF files (PDF and PNG, written atomically)."""

from bouncedisk import plotting
from bouncedisk.datasets import open_checked, open_simulation
from bouncedisk.logutil import log_to

with log_to(snakemake.log[0]) as log:
    kind = snakemake.params.figure
    inp = snakemake.input
    if kind == "fig2":
        fig = plotting.fig2_schematic()
    elif kind == "trajectory":
        band = open_checked(inp.band, required=("omega_mean", "omega_ci_low"), what="band")
        fig = plotting.fig_trajectory(open_simulation(inp.sim), band=band)
    elif kind == "poincare":
        maps = [open_checked(p, required=("phase", "v_rel")) for p in inp.maps]
        fig = plotting.fig_poincare(dict(zip(snakemake.params.labels, maps, strict=True)))
    elif kind == "bifurcation":
        up, down = (
            open_checked(p, required=("phase", "is_chatter", "lyapunov"))
            for p in (inp.up, inp.down)
        )
        fig = plotting.fig_bifurcation(up, down)
    elif kind == "regime_map":
        fig = plotting.fig_regime_map(open_checked(inp.sweep, required=("regime", "lyapunov")))
    elif kind == "speed_vs_psi":
        fig = plotting.fig_speed_vs_psi(
            open_checked(inp.sweep, required=("mean_omega", "mean_omega_ci_low"))
        )
    elif kind == "fig5":
        from bouncedisk.curves import read_curve

        curve = read_curve(inp.curve)
        df = {"time_s": curve.time, "omega_rad_s": curve.omega}
        fit = open_checked(inp.fit, required=("omega_measured", "omega_fitted"), what="fit")
        fig = plotting.fig5_motor(df, fitted=fit)
    elif kind == "fit_profiles":
        fit = open_checked(inp.fit, required=("omega_measured", "omega_fitted"), what="fit")
        fig = plotting.fig_fit_profiles(fit)
    elif kind in ("work_precision", "scaling"):
        import pandas as pd

        table = pd.read_csv(inp.table)
        fig = (plotting.fig_work_precision if kind == "work_precision" else plotting.fig_scaling)(
            table
        )
    elif kind == "stats_cost":
        import pandas as pd

        fig = plotting.fig_stats_cost(pd.read_csv(inp.table), pd.read_csv(inp.singles))
    elif kind == "clipped":
        fig = plotting.fig_clipped_vs_bouncing(open_checked(inp.study, required=("omega_rotor",)))
    else:
        raise ValueError(f"unknown figure {kind!r}")
    plotting.save_figure(fig, snakemake.output.pdf, snakemake.output.png)
    log.info("wrote %s and %s", snakemake.output.pdf, snakemake.output.png)
