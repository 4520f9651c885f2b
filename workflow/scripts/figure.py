"""Adapter: draw every figure of one batch of the figure table (workflow/config/figures.yaml),
PDF and PNG, in one process.

The rule's inputs and outputs are named ``<figure>__<name>`` (a figure's name holds no ``__``);
its params hold, per figure, the plot and its options. Each figure is saved
atomically and closed before the next is drawn (the package's figures are pyplot-free
``Figure`` objects: no figure manager holds them, clearing one and dropping it frees it). The
first figure that fails (or Ctrl-C) stops the job with an error naming it, and the figures the
batch had saved are removed again; a job killed by a signal leaves its outputs to Snakemake,
which removes the outputs of a job that did not finish.
"""

from bouncedisk.figures import common, drawing
from bouncedisk.io.atomic import recording_outputs, remove_outputs
from bouncedisk.io.job_log import log_to


class FigureError(RuntimeError):
    """A figure of the batch could not be drawn or saved."""


def by_figure(named):
    """``<figure>__<name>`` -> {figure: {name: value}} (a list-valued input stays a list)."""
    out = {}
    for key, value in named.items():
        figure, _, name = key.partition("__")
        out.setdefault(figure, {})[name] = value
    return out


def draw_batch(batch, figures, inputs, outputs, log):
    """Draw and save each figure of ``figures`` (name -> plot, options) in turn."""
    for name, spec in figures.items():
        fig = None
        try:
            fig = drawing.draw_figure(spec["plot"], inputs.get(name, {}), spec["options"])
            common.save_figure(fig, outputs[name]["pdf"], outputs[name]["png"])
        except Exception as ex:
            raise FigureError(
                f"figure batch {batch!r}: figure {name!r} (plot {spec['plot']!r}) failed: "
                f"{type(ex).__name__}: {ex}"
            ) from ex
        finally:
            if fig is not None:
                fig.clear()
            del fig
        log.info("wrote %s and %s", outputs[name]["pdf"], outputs[name]["png"])


with log_to(snakemake.log[0]) as log, recording_outputs():
    try:
        draw_batch(
            snakemake.params.batch,
            snakemake.params.figures,
            by_figure({k: v for k, v in snakemake.input.items() if k != "code"}),
            by_figure(dict(snakemake.output.items())),
            log,
        )
    except BaseException:  # a figure failed, or the job was interrupted (Ctrl-C)
        log.exception("figure batch %r failed", snakemake.params.batch)
        for path in remove_outputs():
            log.error("removed %s (the batch failed)", path)
        raise
