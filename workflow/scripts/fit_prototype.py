"""Adapter: fit the model to the prototype's velocity-time curve and load curve jointly."""

from bouncedisk.fitting import FitSettings, fit_curve, fit_dataset, summary_text
from bouncedisk.io.job_log import log_to
from bouncedisk.io.load_curves import read_load_curve
from bouncedisk.io.netcdf import write_dataset
from bouncedisk.io.runup_curves import read_curve

with log_to(snakemake.log[0]) as log:
    curve = read_curve(snakemake.input.curve)
    settings = FitSettings(
        seed=snakemake.params.seed,
        bootstrap=snakemake.params.bootstrap,
        **({} if snakemake.params.e_sigma is None else {"e_sigma": snakemake.params.e_sigma}),
        **snakemake.params.search,  # scan, zoom: the fit's defaults unless the config sets them
        cores=max(snakemake.threads, snakemake.params.threads),
    )
    # the load curve and its sidecar when the config names one (a joint fit), else none
    loads = [read_load_curve(p) for p in snakemake.input.load if p.endswith(".csv")]
    fit = fit_curve(curve, settings, progress=log.info, load=loads)
    ds = fit_dataset(fit)
    write_dataset(ds, snakemake.output[0])
    log.info("\n%s", summary_text(ds))
