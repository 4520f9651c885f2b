# The figure table workflow/config/figures.yaml (what each figure is drawn from, how, and where the
# report shows it), checked against the figure registry before any job runs, and the functions
# rule `figure` (figures.smk) reads it with. The registry is bouncedisk.figures.registry, the light
# declaration bouncedisk.figures.drawing.FIGURES is built from: every Snakemake invocation and every
# job parses this file, and importing it loads no matplotlib, xarray or pandas.
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
        raise ValueError(f"{FIGURE_TABLE_FILE}: must be a mapping, figure name -> entry")
    try:
        validate(table, "../schemas/figures.schema.yaml")
    except WorkflowError as ex:
        cause = ex.__cause__ or ex.__context__  # the jsonschema ValidationError
        if not hasattr(cause, "absolute_path"):
            raise
        where = ".".join(str(p) for p in cause.absolute_path) or "(top level)"
        raise ValueError(f"{FIGURE_TABLE_FILE}: {where}: {cause.message}") from None
    return table


def _config_has(dotted):
    """Whether the pipeline config sets the dotted key (a figure's ``needs``)."""
    node = config
    for key in dotted.split("."):
        if not isinstance(node, dict) or node.get(key) in (None, ""):
            return False
        node = node[key]
    return True


FIGURE_TABLE = _read_figure_table()
# what rule `all` draws (results/figures/<name>.pdf and .png), in the table's order; a figure
# that needs a config key (e.g. the joint fit's, prototype.load_curve) only when it is set
FIGURES = [n for n, e in FIGURE_TABLE.items() if "needs" not in e or _config_has(e["needs"])]
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
            raise ValueError(
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
            raise ValueError(f"{where}.plot: unknown figure {row['plot']!r} "
                             f"(bouncedisk.figures.drawing.FIGURES: {', '.join(sorted(PLOTS))})")
        for part, given, wanted in (("inputs", row.get("inputs", {}), spec.inputs),
                                    ("params", row.get("params", {}), spec.params)):
            if set(given) != set(wanted):
                raise ValueError(f"{where}.{part}: {row['plot']!r} takes {sorted(wanted)}, "
                                 f"the table gives {sorted(given)}")
        for key, mapping in row.get("params", {}).items():
            if not isinstance(config.get(mapping), dict):
                raise ValueError(f"{where}.params.{key}: no mapping {mapping!r} in the config")
        caption = Path(workflow.basedir, "workflow", "report", f"{row['caption']}.rst")
        if not caption.is_file():
            raise ValueError(f"{where}.caption: no file {caption}")
        _figure_paths(name)


_check_figures()


def figure_inputs(wildcards):
    return {"code": rules.compile_engine.output[0], **_figure_paths(wildcards.fig)}


def figure_params(wildcards):
    """The figure's parameters: each a config mapping's values, in the order of its keys."""
    params = FIGURE_TABLE[wildcards.fig].get("params", {})
    return {key: list(config[mapping].values()) for key, mapping in params.items()}


def figure_caption(wildcards):
    """The text of the figure's caption (workflow/report/figure.rst shows it in the report)."""
    caption = FIGURE_TABLE[wildcards.fig]["caption"]
    return Path(workflow.basedir, "workflow", "report", f"{caption}.rst").read_text()
