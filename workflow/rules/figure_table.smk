# The figure table workflow/config/figures.yaml (what each figure is drawn from, how, in which
# batch, and where the report shows it), checked against the figure registry before any job runs,
# and the functions the rules figure_<batch> (figures.smk) are built with: one rule per batch,
# whose job draws every figure of the batch in one process. The registry is
# bouncedisk.figures.registry, the light declaration bouncedisk.figures.drawing.FIGURES is built
# from: every Snakemake invocation and every job parses this file, and importing it loads no
# matplotlib, xarray or pandas.
import re

import yaml
from snakemake.exceptions import WorkflowError

from bouncedisk.figures.registry import FIGURES as PLOTS

FIGURE_TABLE_FILE = "workflow/config/figures.yaml"


def _read_figure_table():
    """The table, schema-checked; a malformed file or entry is named (not "config file")."""
    with open(Path(workflow.basedir, FIGURE_TABLE_FILE)) as stream:
        table = yaml.safe_load(stream)  # a YAML error's position names the file
    if not isinstance(table, dict):  # validate() checks mappings only
        raise ConfigError(f"{FIGURE_TABLE_FILE}: must be a mapping, figure name -> entry")
    try:
        validate(table, "../schemas/figures.schema.yaml")
    except WorkflowError as ex:
        cause = ex.__cause__ or ex.__context__  # the jsonschema ValidationError
        if not hasattr(cause, "absolute_path"):
            raise
        where = ".".join(str(p) for p in cause.absolute_path) or "(top level)"
        raise ConfigError(f"{FIGURE_TABLE_FILE}: {where}: {cause.message}") from None
    return table


def _config_has(dotted):
    """Whether the pipeline config sets the dotted key (a figure's ``needs``)."""
    node = config
    for key in dotted.split("."):
        if not isinstance(node, dict) or node.get(key) in (None, ""):
            return False
        node = node[key]
    return True


# the fields of the table's path templates; those in _LIST_FIELDS give one file per value
_FIELDS = {"results": RES, "curve": config["prototype"]["curve"]}
_LIST_FIELDS = {"poincare": list(config["poincare"])}


def _figure_paths(name):
    """Input name -> path (or list of paths) of figure ``name``, its templates filled in."""
    paths = {}
    for key, template in FIGURE_TABLE[name].get("inputs", {}).items():
        used = set(re.findall(r"\{(\w+)\}", template))
        unknown = used - set(_FIELDS) - set(_LIST_FIELDS)
        if unknown:
            raise ConfigError(
                f"{FIGURE_TABLE_FILE}: {name}.inputs.{key}: unknown field(s) {sorted(unknown)} "
                f"(known: {sorted(_FIELDS) + sorted(_LIST_FIELDS)})"
            )
        filled = template.format(**{k: v for k, v in _FIELDS.items() if k in used},
                                 **{k: f"{{{k}}}" for k in _LIST_FIELDS if k in used})
        listed = {k: v for k, v in _LIST_FIELDS.items() if k in used}
        paths[key] = expand(filled, **listed) if listed else filled
    return paths


def _check_figures():
    """Fail before any job, naming the entry, when the table and the figure registry disagree."""
    for name, row in FIGURE_TABLE.items():
        where = f"{FIGURE_TABLE_FILE}: {name}"
        spec = PLOTS.get(row["plot"])
        if spec is None:
            raise ConfigError(f"{where}.plot: unknown figure {row['plot']!r} "
                             f"(bouncedisk.figures.drawing.FIGURES: {', '.join(sorted(PLOTS))})")
        for part, given, wanted in (("inputs", row.get("inputs", {}), spec.inputs),
                                    ("params", row.get("params", {}), spec.params)):
            if set(given) != set(wanted):
                raise ConfigError(f"{where}.{part}: {row['plot']!r} takes {sorted(wanted)}, "
                                 f"the table gives {sorted(given)}")
        for key, mapping in row.get("params", {}).items():
            if not isinstance(config.get(mapping), dict):
                raise ConfigError(f"{where}.params.{key}: no mapping {mapping!r} in the config")
        caption = Path(workflow.basedir, "workflow", "report", f"{row['caption']}.rst")
        if not caption.is_file():
            raise ConfigError(f"{where}.caption: no file {caption}")
        _figure_paths(name)


try:  # one line naming the file and the entry, exit 2, as the config's own checks
    FIGURE_TABLE = _read_figure_table()
    # what rule `all` draws (results/figures/<name>.pdf and .png), in the table's order; a
    # figure that needs a config key (e.g. the joint fit's, prototype.load_curve) only when set
    FIGURES = [n for n, e in FIGURE_TABLE.items() if "needs" not in e or _config_has(e["needs"])]
    _check_figures()
except ConfigError as _ex:
    exit_with_error(str(_ex))


# the batches (figures.yaml `batch`), in the table's order: batch -> its figures of FIGURES (a
# figure left out for an unset `needs` is left out of its batch; a batch left empty has no rule)
FIGURE_BATCHES = {}
for _name in FIGURES:
    FIGURE_BATCHES.setdefault(FIGURE_TABLE[_name]["batch"], []).append(_name)
# rule name -> the batch job's name in the tracking store (tracking.smk), figures/<batch>
FIGURE_JOB_NAMES = {f"figure_{batch}": f"figures/{batch}" for batch in FIGURE_BATCHES}


def figure_batch_inputs(batch):
    """The batch's inputs: the engine's flag, then each figure's inputs as <figure>__<input> (a
    list-valued input, e.g. the Poincaré maps, stays one list)."""
    paths = {"code": rules.compile_engine.output[0]}
    for name in FIGURE_BATCHES[batch]:
        paths.update({f"{name}__{key}": p for key, p in _figure_paths(name).items()})
    return paths


def figure_batch_outputs(batch):
    """Each figure's PDF and PNG as <figure>__pdf and <figure>__png, the PNG in the report with
    the figure's own caption (workflow/report/<caption>.rst) and category."""
    outputs = {}
    for name in FIGURE_BATCHES[batch]:
        row = FIGURE_TABLE[name]
        outputs.update({f"{name}__{ext}": path
                        for ext, path in fig_out(name, row["caption"], row["category"]).items()})
    return outputs


def figure_batch_params(batch):
    """Per figure of the batch: its plot (a key of bouncedisk.figures.drawing.FIGURES) and its
    options (each a config mapping's values, in the order of its keys); its caption goes with its
    PNG in the report (figure_batch_outputs)."""
    return {
        name: {
            "plot": FIGURE_TABLE[name]["plot"],
            "options": {key: list(config[mapping].values())
                        for key, mapping in FIGURE_TABLE[name].get("params", {}).items()},
        }
        for name in FIGURE_BATCHES[batch]
    }
