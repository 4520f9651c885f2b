# Shared helpers: paths, config checks that must fail before any job runs.
import math
import os

from bouncedisk.model.scene import check_swept, load_scene
from bouncedisk.studies import reproduction_files as _checked

RES = config["results"]
# How the bands are computed (members, seed, noise), apart from which scenes get one: adding a
# scene to bands.scenes builds its band and reruns no other.
BAND_SPEC = {k: v for k, v in config["bands"].items() if k != "scenes"}
# the prototype's load curve (optional): fitted jointly with the run-up when the config names it,
# and the rig (rotor, preload) of its fitted motor's load characteristic in SI units
LOAD_CURVE = config["prototype"].get("load_curve")
LOAD_INPUTS = [LOAD_CURVE, str(Path(LOAD_CURVE).with_suffix(".yaml"))] if LOAD_CURVE else []
# who made the files (ACDD creator/institution attributes of every netCDF file): the jobs read
# them from the environment (bouncedisk.io.provenance.METADATA_ENV); unset keys keep the defaults
for _key, _value in (config.get("metadata") or {}).items():
    if _value:
        os.environ[f"BOUNCEDISK_{_key.upper()}"] = str(_value)
# the scene files (config `scenes`, default workflow/config/scenes): one per study
SCENES = config.get("scenes", "workflow/config/scenes")
# every result depends on the code that made it: rule compile_engine takes every source file as
# input and every other job its flag (results/logs/engine_compiled.flag), so editing the package
# recompiles and reruns what it affects. One input a job instead of every source file: the DAG of
# a dry run is built in a third of the time (each input file is matched against every rule's
# outputs). The fit alone takes the files themselves (it starts beside compile_engine, fit.smk).
CODE = sorted(str(p) for p in Path("src/bouncedisk").rglob("*.py"))


wildcard_constraints:
    scene=r"[A-Za-z0-9][A-Za-z0-9_.-]*",
    sweep=r"[A-Za-z0-9][A-Za-z0-9_.-]*",


def scene_path(name):
    return f"{SCENES}/{name}.yaml"


class ConfigError(ValueError):
    """A mistake in the pipeline config or a scene it names: one line, exit 2 (below)."""


def _check_config():
    """Fail early, naming the key, when the config refers to something that does not exist."""
    wanted = {f"simulations[{i}]": s for i, s in enumerate(config["simulations"])}
    wanted.update({f"sweeps.{k}.scene": v["scene"] for k, v in config["sweeps"].items()})
    wanted["clipped_comparison.scene"] = config["clipped_comparison"]["scene"]
    wanted.update({f"statistics[{i}]": s for i, s in enumerate(config["statistics"])})
    wanted.update({f"bands.scenes[{i}]": s for i, s in enumerate(config["bands"]["scenes"])})
    wanted["continuation.scene"] = config["continuation"]["scene"]
    wanted["stats_cost.scene"] = config["stats_cost"]["scene"]
    if "basins" in config:
        wanted["basins.scene"] = config["basins"]["scene"]
    wanted.update({f"load_curves.{k}.scene": v["scene"] for k, v in config["load_curves"].items()})
    for key, name in wanted.items():
        if not Path(scene_path(name)).is_file():
            raise ConfigError(
                f"workflow/config/config.yaml: {key}: unknown scene {name!r} "
                f"(no file {scene_path(name)})"
            )
    for name in sorted(set(wanted.values())):  # each scene file valid before any job starts
        try:
            load_scene(scene_path(name))
        except InputError as ex:
            raise ConfigError(ex.line()) from None
    for key in config["poincare"]:
        if key not in config["simulations"]:
            raise ConfigError(
                f"workflow/config/config.yaml: poincare.{key}: not listed in 'simulations'"
            )
    for name, spec in config["sweeps"].items():
        base = load_scene(scene_path(spec["scene"]))
        if base.stop.time is None:  # a sweep's points are ensembles averaged over a window
            raise ConfigError(
                f"workflow/config/config.yaml: sweeps.{name}.scene: {spec['scene']} stops after "
                "impacts; a sweep averages over time: give it stop.time (or stop.periods)"
            )
        try:
            check_swept(base, spec["axes"], "workflow/config/config.yaml", f"sweeps.{name}.axes")
        except InputError as ex:
            raise ConfigError(ex.line()) from None
        first = next(iter(spec["axes"].values()))
        n = len(first["values"]) if "values" in first else first["n"]
        if spec["shards"] > n:
            raise ConfigError(
                f"workflow/config/config.yaml: sweeps.{name}.shards: {spec['shards']} shards "
                f"for only {n} values of the first axis"
            )
    for key in ("fig3", "fig4"):
        if key not in config["bands"]["scenes"]:
            raise ConfigError(
                f"workflow/config/config.yaml: bands.scenes: must include {key!r} (a paper figure)"
            )
    for key in CHECKED_STATS:
        if key not in config["statistics"]:
            raise ConfigError(
                f"workflow/config/config.yaml: statistics: must include {key!r} "
                "(a reproduction check reads it)"
            )
    for key in ("fig3", "fig4", "fig5"):
        if key not in config["simulations"]:
            raise ConfigError(
                f"workflow/config/config.yaml: simulations: must include {key!r} (a paper figure)"
            )
    for key in CHECKED_LOAD_CURVES:
        if key not in config["load_curves"]:
            raise ConfigError(
                f"workflow/config/config.yaml: load_curves: must include {key!r} "
                "(a reproduction check reads it)"
            )
    if not Path(config["prototype"]["curve"]).is_file():
        raise ConfigError(
            f"workflow/config/config.yaml: prototype.curve: no file {config['prototype']['curve']}"
        )


# ensemble statistics and load curves the reproduction checks read: their one list is
# bouncedisk.studies.reproduction_files (standard library only, cheap to import here)
CHECKED_STATS = list(_checked.STATS_SCENES)
CHECKED_LOAD_CURVES = list(_checked.LOAD_CURVES)
try:  # one line naming the file and the key, exit 2, as the package's commands
    _check_config()
except ConfigError as _ex:
    exit_with_error(str(_ex))


def sweep_shards(wildcards):
    n = config["sweeps"][wildcards.sweep]["shards"]
    return [f"{RES}/sweeps/{wildcards.sweep}/shard-{i}.nc" for i in range(n)]


def all_targets():
    # FIGURES: the figure table's names (figure_table.smk, workflow/config/figures.yaml); the
    # config's simulations and bands too, whether a figure draws them or not
    figs = expand(f"{RES}/figures/{{fig}}.{{ext}}", fig=FIGURES, ext=["pdf", "png"])
    figs += expand(f"{RES}/simulations/{{s}}.nc", s=config["simulations"])
    figs += expand(f"{RES}/bands/{{s}}.nc", s=config["bands"]["scenes"])
    return figs + [
        f"{RES}/reproduction.md",
        f"{RES}/fit/prototype.nc",
        f"{RES}/prototype/synthetic_motor.csv",
        f"{RES}/prototype/synthetic_motor_load.csv",
        f"{RES}/tables/work_precision.csv",
        f"{RES}/tables/scaling.csv",
        f"{RES}/tables/stats_cost.csv",
    ] + expand(f"{RES}/poincare/{{s}}.nc", s=list(config["poincare"])) + expand(
        f"{RES}/stats/{{s}}.nc", s=config["statistics"]
    )


def fig_out(name, caption, category):
    """results/figures/<name>.pdf and .png, the PNG in the report with its caption
    (workflow/report/<caption>.rst) in its section ``category``."""
    return {
        "pdf": f"{RES}/figures/{name}.pdf",
        "png": report(f"{RES}/figures/{name}.png", caption=f"../report/{caption}.rst",
                      category=category),
    }
