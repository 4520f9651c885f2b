"""Re-lay the package out by layer (issue 24): move modules, cut the big ones, rewrite references.

Run from the root of a clean checkout (``git status`` empty), then review and commit::

    python tools/relayout.py --dry-run     # the table, and what would move
    python tools/relayout.py               # git mv / cut / rewrite, staged in the index

What it does, from the one table below (``MOVES``, ``SPLITS``, ``PACKAGES``):

1. checks that every module of ``src/bouncedisk`` is in the table (a module added since the
   table was written stops the run, naming it), and that every top-level statement of a module
   to be cut is placed (a function added since stops it too);
2. ``git mv``s each whole module to its new place (``Path(__file__).parents[N]`` follows);
3. cuts each split module by name with ``ast`` (comments above a definition go with it), each
   new module importing what its code uses: the old module's imports, pruned by ``ruff``, and
   the names that went to its sibling modules;
4. rewrites every reference in src/, tests/, benchmarks/, workflow/, docs/, .ci/, Snakefile,
   pyproject.toml and README.md: absolute and relative imports (relative stay relative in
   src/), ``from bouncedisk import split_module`` used as ``split_module.name`` (each name to
   its new module), and dotted names in strings, comments and docs (``mock.patch`` targets,
   ``python -m bouncedisk.x``, ``bouncedisk.cli:main``, ``{mod}`` roles);
5. sorts imports and formats the files it touched (``ruff``).

Running it again on the result changes nothing. Old module names that became new folders
(``analysis``, ``studies``, ``tracking``) are read as old while their ``.py`` file exists.
"""

from __future__ import annotations

import argparse
import ast
import re
import shutil
import subprocess
import sys
import textwrap
from dataclasses import dataclass, field
from pathlib import Path

# =========================================================================================
# The table: the one source of truth of the new layout
# =========================================================================================

#: The new folders, lowest layer first, and what lives in each (their ``__init__.py`` docstring).
PACKAGES: dict[str, str] = {
    "model": (
        "The model: what is simulated.\n\nParameters (and the physical conversion), scenes, "
        "stator kinematics, YAML as users write it, the one-line user error, and a scene "
        "translated into the engine's configuration."
    ),
    "io": (
        "Files: what is read and written.\n\nThe engine's records named, netCDF writing "
        "(streamed, atomic) and reading, provenance keys, output checks, measured curves, job "
        "logs."
    ),
    "run": (
        "Running a scene: model + engine (or a comparator solver) -> a streamed file.\n\n"
        "Provenance and interrupts of a run, and the child process whose memory the scaling "
        "study measures."
    ),
    "analysis": (
        "Analyses: what a run or an ensemble shows.\n\nObservables, ensembles, statistics "
        "with intervals, bands, sweeps and continuation, Poincaré maps."
    ),
    "studies": (
        "Studies built on the analyses.\n\nWork–precision, scaling, statistics cost, the "
        "clipped comparison, torque–speed curves, global sensitivity, the paper's reproduction "
        "checks."
    ),
    "tracking": (
        "Experiment tracking on MLflow.\n\nThe store, what is extracted from output files, "
        "writing (a command's run; one parent run per pipeline, nested per job) and reading "
        "(``bouncedisk runs``)."
    ),
    "figures": (
        "Figures: one module per family, each figure a pure function of Datasets.\n\n"
        ":mod:`.registry` declares them (standard library only: the Snakefile reads it), "
        ":mod:`.drawing` opens their inputs and draws. Importing this package imports no "
        "matplotlib."
    ),
    "cli": (
        "The ``bouncedisk`` command: one module per subcommand.\n\nThe only place that parses "
        "argv and prints; :mod:`.command` holds the entry point, :func:`main`."
    ),
}

#: Names a new folder's ``__init__.py`` re-exports: ``bouncedisk.cli:main`` (the console
#: script of every existing install) and ``from bouncedisk.cli import main`` keep working.
REEXPORTS: dict[str, dict[str, list[str]]] = {"cli": {"command": ["main"]}}

#: Whole modules, old -> new.
MOVES: dict[str, str] = {
    # engine/ (no change: it imports nothing of the package)
    "engine": "engine",
    "engine._cache": "engine._cache",
    "engine.driver": "engine.driver",
    "engine.kernel": "engine.kernel",
    "engine.laws": "engine.laws",
    "engine.noise": "engine.noise",
    "engine.roots": "engine.roots",
    # model/
    "errors": "model.errors",
    "params": "model.params",
    "scene": "model.scene",
    "stator": "model.stator",
    "yamlio": "model.yamlio",
    # io/
    "records": "io.records",
    "atomic": "io.atomic",
    "outputs": "io.output_checks",
    "datasets": "io.netcdf",
    "provenance": "io.provenance",
    "curves": "io.runup_curves",
    "loaddata": "io.load_curves",
    "logutil": "io.job_log",
    # run/
    "solvers": "run.comparators",
    "memprobe": "run.memory_probe",
    # analysis/
    "observables": "analysis.observables",
    "ensemble": "analysis.ensembles",
    "stats": "analysis.statistics",
    "bands": "analysis.bands",
    "sweeps": "analysis.sweeps",
    # studies/
    "stats_cost": "studies.statistics_cost",
    "loadcurve": "studies.torque_speed",
    "sensitivity": "studies.sensitivity",
    "sensitivity_config": "studies.sensitivity_settings",
    "checks": "studies.reproduction",
    # fitting/ (no change)
    "fitting": "fitting",
    "fitting.basins": "fitting.basins",
    "fitting.command": "fitting.command",
    "fitting.core": "fitting.core",
    "fitting.detlinalg": "fitting.detlinalg",
    "fitting.joint": "fitting.joint",
    "fitting.load_output": "fitting.load_output",
    "fitting.loadpart": "fitting.loadpart",
    "fitting.model": "fitting.model",
    "fitting.objective": "fitting.objective",
    "fitting.output": "fitting.output",
    "fitting.runs": "fitting.runs",
    "fitting.search": "fitting.search",
    "fitting.statistics": "fitting.statistics",
    "fitting.synthetic": "fitting.synthetic",
    "fitting.uncertainty": "fitting.uncertainty",
    # tracking/
    "registry": "tracking.reading",
    # figures/
    "plot_load": "figures.load",
    "plot_fit_load": "figures.joint_fit",
    "figure_registry": "figures.registry",
}

#: Modules cut by name: old -> {"primary": new module a bare reference to the old one means,
#: "targets": {new module: [top-level names]}}. ``__main__`` is an ``if __name__ ==
#: "__main__":`` block. A target that is also a ``MOVES`` destination gets the names appended.
SPLITS: dict[str, dict] = {
    "runner": {
        "primary": "run.runner",
        "targets": {
            "model.engine_config": ["engine_config"],
            "run.runner": [
                "_chunks",
                "_status_text",
                "Progress",
                "StopRequest",
                "deferred_interrupts",
                "RunSummary",
                "scene_attrs",
                "run_scene",
                "_writer",
                "_stream",
                "_run_attrs",
                "_raise_missing_effect",
                "run_scene_arrays",
            ],
        },
    },
    "analysis": {
        "primary": "analysis",
        "targets": {
            "analysis.poincare": ["poincare_dataset"],
            "studies.clipped": ["clipped_comparison"],
        },
    },
    "studies": {
        "primary": "studies",
        "targets": {
            "studies.work_precision": [
                "Case",
                "CASES",
                "IVP_TOLS",
                "MOREAU_STEPS",
                "EXACT_TOLS",
                "_cpu",
                "_rest_time",
                "_errors",
                "work_precision",
                "work_precision_summary",
            ],
            "studies.scaling": ["_stream", "_rate", "peak_memory_mb", "scaling"],
        },
    },
    "statscli": {
        "primary": "cli.stats",
        "targets": {
            "run.cores": ["available_cores"],
            "io.history": ["write_with_history"],
            "cli.stats": ["_progress", "format_summary", "_g", "_row", "stats_command"],
        },
    },
    "loadcli": {
        "primary": "cli.torque_speed",
        "targets": {
            "cli.torque_speed": [
                "DEFAULT_LOADS",
                "format_curve",
                "_g",
                "torque_speed_command",
                "_with_load",
                "add_torque_speed",
            ],
        },
    },
    "cli": {
        "primary": "cli",
        "targets": {
            "cli.common": [
                "EXIT_USER",
                "EXIT_FAIL",
                "EXIT_INTERRUPT",
                "_add_set_option",
                "flush_stdout",
            ],
            "cli.tracking_options": ["_add_track_options", "_tracking_store", "_track"],
            "cli.simulate": ["_cmd_simulate", "_add_simulate"],
            "cli.stats": ["_cmd_stats", "_add_stats"],
            "cli.torque_speed": ["_cmd_torque_speed", "_add_torque_speed"],
            "cli.info": ["_cmd_info", "_add_info"],
            "cli.runs": ["RUNS_ACTIONS", "_cmd_runs", "_one_line_error", "_add_runs"],
            "cli.check": ["_cmd_check", "_add_check"],
            "cli.fit": ["_cmd_fit", "_add_fit"],
            "cli.command": [
                "OneLineParser",
                "build_parser",
                "_interrupt",
                "_install_signal_handlers",
                "main",
                "_discard_stdout",
                "_NamedStdout",
                "_run_command",
                "_report",
            ],
            "cli.__main__": ["__main__"],
        },
    },
    "plotting": {
        "primary": "figures.drawing",
        "targets": {
            "figures.common": ["TWO_PI", "COLORS", "save_figure", "_param", "_title"],
            "figures.schematic": ["fig2_schematic"],
            "figures.trajectory": ["_band", "fig_trajectory"],
            "figures.motor": ["fig5_motor", "_fig5_fitted", "fig_fit_profiles"],
            "figures.dynamics": [
                "fig_poincare",
                "_param_where",
                "fig_bifurcation",
                "REGIME_COLORS",
                "fig_regime_map",
                "fig_speed_vs_psi",
                "fig_clipped_vs_bouncing",
            ],
            "figures.cost": ["fig_work_precision", "fig_scaling", "fig_stats_cost"],
            "figures.sensitivity": [
                "_short",
                "fig_sensitivity_indices",
                "fig_sensitivity_scatter",
                "fig_design_maps",
            ],
            "figures.drawing": [
                "Opener",
                "_netcdf",
                "_curve",
                "_fig5_with_fit",
                "_poincare_labelled",
                "FigureSpec",
                "OPENERS",
                "_resolve",
                "FIGURES",
                "draw_figure",
            ],
        },
        # figures.drawing looks the drawing functions up by name (``globals()[decl.draw]``)
        "keep": {
            "figures.drawing": [
                "fig2_schematic",
                "fig_trajectory",
                "fig_fit_profiles",
                "fig_poincare",
                "fig_bifurcation",
                "fig_regime_map",
                "fig_speed_vs_psi",
                "fig_clipped_vs_bouncing",
                "fig_work_precision",
                "fig_scaling",
                "fig_stats_cost",
                "fig_sensitivity_indices",
                "fig_sensitivity_scatter",
                "fig_design_maps",
            ],
        },
    },
    "tracking": {
        "primary": "tracking",
        "targets": {
            "tracking.store": [
                "ENV_URI",
                "DB_NAME",
                "ARTIFACTS_NAME",
                "EXPERIMENT",
                "SCHEMES",
                "SQLITE_SUFFIXES",
                "MLFLOW_TABLES",
                "HTTP_TIMEOUT_S",
                "HTTP_RETRIES",
                "HTTP_BACKOFF",
                "LOCK_TIMEOUT_S",
                "TrackingError",
                "Store",
                "resolve_store",
                "preflight",
                "_preflight_sqlite",
                "_http_request",
                "_preflight_http",
                "_AUTOFLUSH",
                "_one_line",
                "_client",
                "store_lock",
                "experiment_id",
                "_log_batch",
                "print_error",
            ],
            "tracking.extraction": [
                "HASH_CACHE",
                "VOLATILE_ATTRS",
                "PARAM_ATTRS",
                "PARAM_PREFIXES",
                "KINDS",
                "MAX_PARAM",
                "_number",
                "_seq",
                "_seq_keys",
                "is_param_attr",
                "_clean_key",
                "_param_value",
                "netcdf_fields",
                "json_metrics",
                "_NUM",
                "_slug",
                "checks_metrics",
                "benchmark_metrics",
                "describe_output",
                "sha256_file",
                "_HashCache",
                "_leaves",
                "numeric_leaves",
                "flatten",
                "config_sha256",
                "_netcdf_run_id",
                "_keys",
            ],
            "tracking.writing": [
                "ENV_TRACK",
                "TAG_KIND",
                "TAG_HOST",
                "TAG_PID",
                "TAG_PSTART",
                "TAG_RUN_ID",
                "TAG_STATE",
                "COPIED",
                "_git",
                "git_state",
                "_process_start",
                "process_alive",
                "provenance_tags",
                "tracking_wanted",
                "log_command_run",
            ],
            "tracking.pipeline": [
                "PIPELINE",
                "mark_stale_runs",
                "JobRecord",
                "PipelineSettings",
                "_switch",
                "PipelineTracker",
            ],
        },
    },
}

#: Text an old module builds a module path from at run time, which no rewrite can see: replaced
#: as it is cut or moved (the run stops if the text is not there).
PATCHES: dict[str, list[tuple[str, str]]] = {
    "studies": [('f"{__package__}.memprobe"', '"bouncedisk.run.memory_probe"')],
}

#: Docstrings of the modules the splits create (a split target that is a ``MOVES`` destination
#: keeps its own).
DOCSTRINGS: dict[str, str] = {
    "run.cores": "The cores this process may use (its CPU affinity).",
    "io.history": (
        "A command's dataset written atomically, its ``history`` the command line that made it."
    ),
    "model.engine_config": "A scene translated into the engine's configuration (one place).",
    "run.runner": None,  # the old runner's docstring
    "analysis.poincare": "Poincaré and stroboscopic maps of a run, as a Dataset.",
    "studies.clipped": (
        "The bouncing model against the clipped-contact one: the same scene run both ways."
    ),
    "studies.work_precision": (
        "What accuracy costs in time: the exact engine against the comparator solvers."
    ),
    "studies.scaling": (
        "Scaling measurements: events per second and peak memory against the run's length."
    ),
    "cli.common": "What every subcommand shares: exit statuses, ``--set``, flushing stdout.",
    "cli.tracking_options": (
        "``--track`` / ``--tracking-uri``: a command's work recorded in the tracking store."
    ),
    "cli.simulate": "``bouncedisk simulate SCENE -o OUT.nc``: one scene, one netCDF file.",
    "cli.stats": None,  # the old statscli's docstring
    "cli.torque_speed": None,  # the old loadcli's docstring
    "cli.info": "``bouncedisk info FILE``: what a simulation file holds.",
    "cli.runs": "``bouncedisk runs [list | show RUN | diff A B]``: the tracked runs.",
    "cli.check": "``bouncedisk check``: the paper's claims, pass or fail.",
    "cli.fit": "``bouncedisk fit CURVE.csv ... -o FIT.nc``: the options of the fit command.",
    "cli.command": None,  # the old cli's docstring
    "cli.__main__": "``python -m bouncedisk.cli``: the command, as the console script runs it.",
    "figures.common": "What every figure shares: colours, parameter labels, saving atomically.",
    "figures.schematic": "The paper's Fig. 2: the stator–rotor interface, drawn.",
    "figures.trajectory": "A run's trajectory (paper Fig. 3), with its ensemble band.",
    "figures.motor": "The motor's run-up against a measured curve (Fig. 5) and fit profiles.",
    "figures.dynamics": (
        "Dynamics: Poincaré maps, bifurcation diagrams, regime maps, speed against ψ, the "
        "clipped comparison."
    ),
    "figures.cost": "What accuracy and statistics cost: work–precision, scaling, stats cost.",
    "figures.sensitivity": "The global sensitivity study: Sobol' indices, scatter, design maps.",
    "figures.drawing": (
        "Drawing a figure by name: the openers of its inputs and :data:`FIGURES`, the registry "
        ":mod:`bouncedisk.figures.registry` resolved to functions."
    ),
    "tracking.store": (
        "The tracking store: where it is, whether it can be used (cheap, no mlflow import), "
        "the MLflow client, locks and batches."
    ),
    "tracking.extraction": (
        "What is recorded, extracted generically from output files: netCDF attributes, JSON "
        "leaves, benchmark columns, the checks table; file hashes."
    ),
    "tracking.writing": (
        "Writing runs: the provenance tags every run carries, and a tracked command's one "
        "top-level run."
    ),
    "tracking.pipeline": (
        "Writing a pipeline invocation: one parent run, a nested run per job, stale runs marked."
    ),
}

#: Text that names an old module but must stay as it is (none so far).
KEEP_TEXT: tuple[str, ...] = ()

# =========================================================================================
# The machinery (nothing below needs changing to change the layout)
# =========================================================================================

PKG = "bouncedisk"
SRC = Path("src") / PKG
#: Where references are rewritten (git-tracked text files only).
REWRITE_ROOTS = ("src", "tests", "benchmarks", "workflow", "docs", ".ci")
REWRITE_FILES = ("Snakefile", "pyproject.toml", "README.md")
TEXT_SUFFIXES = {".py", ".smk", ".md", ".rst", ".toml", ".yaml", ".yml", ".txt", ".cfg", ".ini",
                 ".json", ".sh", ""}  # fmt: skip
SKIP_PARTS = {"_build", "api", "generated"}


class RelayoutError(RuntimeError):
    """Something the table does not cover: fix the table, then run again."""


def die(message: str) -> None:
    raise RelayoutError(message)


# ------------------------------------------------------------------------------ the table


@dataclass
class Table:
    """The table, checked and indexed."""

    moves: dict[str, str]
    splits: dict[str, dict]
    names: dict[tuple[str, str], str] = field(default_factory=dict)  # (old split, name) -> new
    news: set[str] = field(default_factory=set)  # every new module and package

    @classmethod
    def load(cls) -> Table:
        t = cls(dict(MOVES), dict(SPLITS))
        for old, spec in t.splits.items():
            if old in t.moves:
                die(f"table: {old} is both moved and split")
            seen: dict[str, str] = {}
            for new, names in spec["targets"].items():
                for n in names:
                    if n in seen:
                        die(f"table: {old}.{n} is sent to both {seen[n]} and {new}")
                    seen[n] = new
                    t.names[(old, n)] = new
        for new in [*t.moves.values(), *(n for s in t.splits.values() for n in s["targets"])]:
            parts = new.split(".")
            for i in range(1, len(parts) + 1):
                t.news.add(".".join(parts[:i]))
        t.news |= set(PACKAGES)
        return t

    @property
    def olds(self) -> set[str]:
        return set(self.moves) | set(self.splits)

    def split_targets(self) -> set[str]:
        return {n for s in self.splits.values() for n in s["targets"]}

    def dump(self) -> str:
        """The table as text: what --dry-run and --help print."""
        lines = ["whole modules (git mv):"]
        for old, new in self.moves.items():
            lines.append(f"  {PKG}.{old:<22} -> {PKG}.{new}")
        lines.append("modules cut by name (ast):")
        for old, spec in self.splits.items():
            lines.append(f"  {PKG}.{old} (a bare reference means {PKG}.{spec['primary']})")
            for new, names in spec["targets"].items():
                lines.append(f"    -> {PKG}.{new}: {', '.join(names)}")
        n_names = sum(len(v) for s in self.splits.values() for v in s["targets"].values())
        lines.append(
            f"{len(self.moves)} whole modules, {len(self.splits)} modules cut into "
            f"{len(self.split_targets())} ({n_names} names), {len(PACKAGES)} new folders"
        )
        return "\n".join(lines)


# ------------------------------------------------------------------------------ paths


def module_of(path: Path) -> str:
    """``src/bouncedisk/a/b.py`` -> ``a.b``; a package's ``__init__.py`` -> the package."""
    rel = path.relative_to(SRC).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def path_of(module: str, package: bool = False) -> Path:
    """The file of module ``a.b`` (relative to the package)."""
    parts = module.split(".") if module else []
    if package or not parts:
        return SRC.joinpath(*parts, "__init__.py")
    return SRC.joinpath(*parts[:-1], parts[-1] + ".py")


def is_package_module(module: str, files: set[str]) -> bool:
    return str(path_of(module, package=True)) in files


# ------------------------------------------------------------------------------ state


@dataclass
class State:
    """The tree as found: which old modules are still there (the rest were moved before)."""

    root: Path
    files: set[str]  # git-tracked files, relative paths
    present: set[str]  # old modules still in their old place
    old_packages: set[str]  # old modules that are packages (their __init__.py)

    def old_file(self, module: str) -> Path:
        return path_of(module, package=module in self.old_packages)


def inventory(table: Table, root: Path) -> State:
    """Classify every module of the tree; a module in no table is an error."""
    files = set(
        subprocess.run(
            ["git", "ls-files"], cwd=root, capture_output=True, text=True, check=True
        ).stdout.split()
    )
    present, packages, unknown = set(), set(), []
    for f in sorted(files):
        p = Path(f)
        if p.suffix != ".py" or SRC not in p.parents or not (root / p).exists():
            continue
        mod = module_of(p)
        if mod == "":
            continue  # bouncedisk/__init__.py: hand-written
        is_pkg = p.name == "__init__.py"
        if mod in table.olds and not (mod in table.news and _is_new_file(table, mod, is_pkg)):
            present.add(mod)
            if is_pkg:
                packages.add(mod)
        elif mod in table.news:
            continue
        else:
            unknown.append(f)
    if unknown:
        die(
            "modules in no table (add each to MOVES or SPLITS in tools/relayout.py, or to a "
            "split's names):\n  " + "\n  ".join(unknown)
        )
    # an old module that is also a new folder (analysis, studies, tracking) is old while its
    # .py file exists
    return State(root, files, present, packages)


def _is_new_file(table: Table, mod: str, is_pkg: bool) -> bool:
    """Whether the file of ``mod`` is the new one (identity moves are both)."""
    if table.moves.get(mod) == mod:
        return False
    return is_pkg and mod in PACKAGES  # e.g. tracking/__init__.py, new


# ------------------------------------------------------------------------------ resolving


@dataclass
class Resolver:
    """Maps an old dotted path (module, or module.name) to the new one."""

    table: Table
    state: State

    def is_old(self, mod: str) -> bool:
        """``mod`` read as an old module: present, or gone and not also a new path."""
        if mod not in self.table.olds:
            return False
        if mod in self.state.present:
            return True
        return mod not in self.table.news

    def module(self, mod: str) -> str:
        """The new module a bare old module path means."""
        if mod in self.table.moves and self.is_old(mod):
            return self.table.moves[mod]
        if mod in self.table.splits and self.is_old(mod):
            return self.table.splits[mod]["primary"]
        return mod

    def name(self, mod: str, name: str) -> str | None:
        """The new module of ``mod.name`` when ``mod`` is an old split module, else None."""
        if mod in self.table.splits and self.is_old(mod):
            new = self.table.names.get((mod, name))
            primary = self.table.splits[mod]["primary"]
            if any(name in ns for ns in REEXPORTS.get(primary, {}).values()):
                return primary
            if new is None:
                if f"{mod}.{name}" in self.table.news:
                    return None
                die(f"{PKG}.{mod}.{name}: name not in the split table of {PKG}.{mod}")
            return new
        return None

    def dotted(self, dotted: str, where: str) -> str:
        """Rewrite ``bouncedisk.a.b.c`` (text); unchanged when it names no old module."""
        parts = dotted.split(".")[1:]
        for i in range(len(parts), 0, -1):
            head, rest = ".".join(parts[:i]), parts[i:]
            if self.is_old(head):
                if head in self.table.splits:
                    if rest:
                        try:
                            new = self.name(head, rest[0])
                        except RelayoutError as ex:
                            die(f"{where}: {ex}")
                        if new is None:
                            return dotted
                        return ".".join([PKG, new, *rest])
                    return f"{PKG}.{self.table.splits[head]['primary']}"
                return ".".join([PKG, self.table.moves[head], *rest])
            if head in self.table.news:
                return dotted
        return dotted


# ------------------------------------------------------------------------------ imports


def absolute(node: ast.ImportFrom, module: str, is_pkg: bool) -> str:
    """The absolute module of a ``from`` import in ``module`` (relative to the package)."""
    if node.level == 0:
        return node.module or ""
    base = [PKG, *module.split(".")] if module else [PKG]
    if not is_pkg:
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    if node.module:
        base += node.module.split(".")
    return ".".join(base)


def strip(full: str) -> str | None:
    """``bouncedisk.a.b`` -> ``a.b``; ``bouncedisk`` -> ``""``; other packages -> None."""
    if full == PKG:
        return ""
    if full.startswith(PKG + "."):
        return full[len(PKG) + 1 :]
    return None


def relative(target: str, here: str, here_is_pkg: bool) -> str:
    """``from X`` text for module ``target`` seen from module ``here`` (relative form)."""
    base = [PKG, *here.split(".")] if here else [PKG]
    if not here_is_pkg:
        base = base[:-1]
    tgt = [PKG, *target.split(".")] if target else [PKG]
    common = 0
    while common < min(len(base), len(tgt)) and base[common] == tgt[common]:
        common += 1
    level = len(base) - common + 1
    return "." * level + ".".join(tgt[common:])


@dataclass
class Emit:
    """How import statements are written in one file."""

    relative: bool  # src/ uses relative imports
    here: str = ""  # the file's (new) module
    here_is_pkg: bool = False

    def from_(self, mod: str) -> str:
        if self.relative:
            return relative(mod, self.here, self.here_is_pkg)
        return f"{PKG}.{mod}" if mod else PKG


def split_parent(mod: str) -> tuple[str, str]:
    parts = mod.split(".")
    return ".".join(parts[:-1]), parts[-1]


def alias_text(name: str, alias: str | None) -> str:
    return f"{name} as {alias}" if alias and alias != name else name


class FileRewriter:
    """Rewrites one Python source: its imports (ast) and dotted names in the rest (text)."""

    def __init__(self, res: Resolver, text: str, old_module: str | None, old_is_pkg: bool,
                 emit: Emit, where: str):  # fmt: skip
        self.res, self.text, self.where = res, text, where
        self.old_module, self.old_is_pkg, self.emit = old_module, old_is_pkg, emit
        self.tree = ast.parse(text)
        self.lines = text.splitlines(keepends=True)
        self.offsets = [0]
        for line in self.lines:
            self.offsets.append(self.offsets[-1] + len(line))
        self.edits: list[tuple[int, int, str]] = []
        self.identifiers = {
            getattr(n, "id", None) or getattr(n, "arg", None) or getattr(n, "name", None)
            for n in ast.walk(self.tree)
            if isinstance(n, ast.Name | ast.arg | ast.FunctionDef | ast.ClassDef)
        }
        self.parents: dict[ast.AST, ast.AST] = {}
        for n in ast.walk(self.tree):
            for c in ast.iter_child_nodes(n):
                self.parents[c] = n

    def pos(self, line: int, col: int) -> int:
        return self.offsets[line - 1] + len(self.lines[line - 1].encode()[:col].decode())

    def span(self, node: ast.AST) -> tuple[int, int]:
        return self.pos(node.lineno, node.col_offset), self.pos(
            node.end_lineno, node.end_col_offset
        )

    def scope(self, node: ast.AST) -> ast.AST:
        p = self.parents.get(node)
        while p is not None and not isinstance(p, ast.FunctionDef | ast.AsyncFunctionDef):
            p = self.parents.get(p)
        return p or self.tree

    # ---- the module a relative import is read from
    def resolve(self, node: ast.ImportFrom) -> str | None:
        if node.level and self.old_module is None:
            die(f"{self.where}: a relative import outside the package")
        full = absolute(node, self.old_module or "", self.old_is_pkg)
        return strip(full)

    def run(self) -> str:
        for node in ast.walk(self.tree):
            if isinstance(node, ast.ImportFrom):
                self.import_from(node)
            elif isinstance(node, ast.Import):
                self.import_(node)
        self.text_names()
        out, last = [], 0
        for a, b, new in sorted(self.edits):
            if a < last:
                die(f"{self.where}: overlapping edits")
            out += [self.text[last:a], new]
            last = b
        out.append(self.text[last:])
        return "".join(out)

    # ---- from X import a, b
    def import_from(self, node: ast.ImportFrom) -> None:
        mod = self.resolve(node)
        if mod is None:
            return
        res = self.res
        groups: dict[str, list[str]] = {}  # new "from" module -> names (with aliases)
        self_module = self.emit.here
        for a in node.names:
            if a.name == "*":
                die(f"{self.where}:{node.lineno}: import * from {PKG}")
            sub = f"{mod}.{a.name}" if mod else a.name
            named = mod in res.table.splits and res.is_old(mod) and (mod, a.name) in res.table.names
            if not named and (res.is_old(sub) or sub in res.table.news):
                if res.is_old(sub) and sub in res.table.splits:
                    self.split_module_object(node, sub, a)
                    continue
                new = res.module(sub)
                parent, leaf = split_parent(new)
                groups.setdefault(parent, []).append(alias_text(leaf, a.asname or a.name))
                continue
            target = res.name(mod, a.name) if mod else None
            new_mod = target if target is not None else res.module(mod)
            if new_mod == self_module and not isinstance(self.scope(node), ast.Module):
                continue  # a function's import of its own module's globals: not needed
            groups.setdefault(new_mod, []).append(alias_text(a.name, a.asname))
        self.replace_import(node, groups)

    def replace_import(self, node: ast.ImportFrom, groups: dict[str, list[str]]) -> None:
        indent = " " * node.col_offset
        stmts = [f"from {self.emit.from_(m)} import {', '.join(ns)}" for m, ns in groups.items()]
        stmts += getattr(node, "_extra", [])
        new = f"\n{indent}".join(stmts) if stmts else "pass"
        a, b = self.span(node)
        old = self.text[a:b]
        if new != old and not self._same(old, groups):
            self.edits.append((a, b, new))

    def _same(self, old: str, groups: dict[str, list[str]]) -> bool:
        """An import that already reads as it should (kept as written: idempotence)."""
        try:
            tree = ast.parse(old.strip())
        except SyntaxError:
            return False
        if len(groups) != 1 or not isinstance(tree.body[0], ast.ImportFrom):
            return False
        (m, ns), n = next(iter(groups.items())), tree.body[0]
        head = self.emit.from_(m)
        was = "." * n.level + (n.module or "")
        return was == head and sorted(alias_text(a.name, a.asname) for a in n.names) == sorted(ns)

    # ---- from bouncedisk import tracking [as tr]: a split module used as an object
    def split_module_object(self, node: ast.ImportFrom, old: str, a: ast.alias) -> None:
        """Each ``local.name`` to the module ``name`` went to; the object itself (``getattr``,
        ``local.__name__``) to the split's primary module."""
        local = a.asname or a.name
        scope = self.scope(node)
        primary = self.res.table.splits[old]["primary"]
        uses: list[tuple[ast.Name, str]] = []
        for n in ast.walk(scope):
            if isinstance(n, ast.Name) and n.id == local and isinstance(n.ctx, ast.Load):
                p = self.parents.get(n)
                if isinstance(p, ast.Attribute) and not p.attr.startswith("__"):
                    uses.append((n, self.res.name(old, p.attr)))
                else:
                    if primary in PACKAGES:
                        die(f"{self.where}:{n.lineno}: split module {PKG}.{old} used as an "
                            "object, and its primary is a folder")  # fmt: skip
                    uses.append((n, primary))
        targets = sorted({t for _, t in uses})
        if not targets:
            die(f"{self.where}:{node.lineno}: {PKG}.{old} imported but never used")
        taken = self.identifiers - {local}
        names = {}
        for t in targets:
            parent, leaf = split_parent(t)
            alias = leaf if leaf not in taken else f"{parent.rsplit('.', 1)[-1]}_{leaf}"
            names[t] = alias
            extra = f"from {self.emit.from_(parent)} import {alias_text(leaf, alias)}"
            node.__dict__.setdefault("_extra", []).append(extra)
        for n, t in uses:
            if names[t] != local:
                a0, b0 = self.span(n)
                self.edits.append((a0, b0, names[t]))

    # ---- import bouncedisk.x [as y]
    def import_(self, node: ast.Import) -> None:
        parts, changed = [], False
        for a in node.names:
            mod = strip(a.name)
            if mod is None or not mod:
                parts.append(alias_text(a.name, a.asname))
                continue
            new = self.res.module(mod)
            if mod in self.res.table.splits and self.res.is_old(mod) and a.asname:
                die(f"{self.where}:{node.lineno}: import {a.name} as {a.asname} (a split module)")
            changed |= new != mod
            parts.append(alias_text(f"{PKG}.{new}", a.asname))
            if mod in self.res.table.splits and self.res.is_old(mod):
                # bouncedisk.x.name chains elsewhere in the file name other targets too
                for t in sorted(set(self.res.table.splits[mod]["targets"]) - {new}):
                    if re.search(rf"\b{PKG}\.{re.escape(mod)}\.(" + "|".join(
                        re.escape(n) for n in self.res.table.splits[mod]["targets"][t]) + r")\b",
                        self.text):  # fmt: skip
                        parts.append(f"{PKG}.{t}")
        if changed:
            a, b = self.span(node)
            indent = " " * node.col_offset
            self.edits.append((a, b, f"\n{indent}".join(f"import {p}" for p in parts)))

    # ---- dotted names in strings, comments, docstrings and attribute chains
    def text_names(self) -> None:
        imports = [
            self.span(n) for n in ast.walk(self.tree) if isinstance(n, ast.Import | ast.ImportFrom)
        ]
        self.edits += text_edits(self.res, self.text, self.where, imports)


#: ``bouncedisk.a.b`` (and ``bouncedisk.a:main`` entry points), not part of a longer name.
DOTTED = re.compile(r"(?<![\w.])bouncedisk((?:\.[A-Za-z_]\w*)+)(?::([A-Za-z_]\w*))?")


#: ``from bouncedisk.x import a, b as c`` in a string or a document (a child process's code).
FROM_TEXT = re.compile(
    r"(?<![\w.])from (bouncedisk(?:\.[A-Za-z_]\w*)*) import "
    r"([A-Za-z_]\w*(?: as \w+)?(?:, ?[A-Za-z_]\w*(?: as \w+)?)*)"
)


def rewrite_from_text(res: Resolver, m: re.Match, where: str) -> str:
    """A ``from bouncedisk... import ...`` written in text, its names all in one new module."""
    mod = strip(m.group(1))
    groups: dict[str, list[str]] = {}
    for item in m.group(2).split(","):
        name, _, alias = item.strip().partition(" as ")
        sub = f"{mod}.{name}" if mod else name
        named = mod in res.table.splits and res.is_old(mod) and (mod, name) in res.table.names
        if not named and (res.is_old(sub) or sub in res.table.news):
            if res.is_old(sub) and sub in res.table.splits:
                die(f"{where}: {m.group(0)!r}: a split module imported in text")
            parent, leaf = split_parent(res.module(sub))
            groups.setdefault(parent, []).append(alias_text(leaf, alias or name))
        else:
            target = res.name(mod, name) if mod else None
            new = target if target is not None else res.module(mod)
            groups.setdefault(new, []).append(alias_text(name, alias or None))
    if len(groups) != 1:
        die(f"{where}: {m.group(0)!r} in text: its names now live in {sorted(groups)}; "
            "write one import per module")  # fmt: skip
    ((new, names),) = groups.items()
    return f"from {PKG + ('.' + new if new else '')} import {', '.join(names)}"


def text_edits(res: Resolver, text: str, where: str, skip: list[tuple[int, int]]):
    """Edits of ``from bouncedisk... import`` and dotted names in text, outside ``skip``."""
    edits = []
    froms = [m for m in FROM_TEXT.finditer(text) if not any(a <= m.start() < b for a, b in skip)]
    for m in froms:
        new = rewrite_from_text(res, m, where)
        if new != m.group(0):
            edits.append((m.start(), m.end(), new))
    done = skip + [(m.start(), m.end()) for m in froms]
    for m in DOTTED.finditer(text):
        if any(a <= m.start() < b for a, b in done):
            continue
        new = rewrite_match(res, m, where)
        if new != m.group(0):
            edits.append((m.start(), m.end(), new))
    return edits


def rewrite_match(res: Resolver, m: re.Match, where: str) -> str:
    dotted = PKG + m.group(1)
    if m.group(2):  # module:attribute
        mod = strip(dotted)
        new = res.name(mod, m.group(2)) if res.is_old(mod) else None
        return f"{PKG}.{new or res.module(mod)}:{m.group(2)}"
    return res.dotted(dotted, where)


# ---- text files: dotted names, and the import lines of Snakefile and .smk files

SMK_IMPORT = re.compile(
    r"^([ \t]*)(from[ \t]+(\.*[\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n#]*)|import[ \t]+bouncedisk[^\n#]*)",
    re.M,
)


def rewrite_text(res: Resolver, text: str, where: str, python_lines: bool) -> str:
    edits: list[tuple[int, int, str]] = []
    if python_lines:
        for m in SMK_IMPORT.finditer(text):
            stmt = m.group(2)
            if "bouncedisk" not in stmt:
                continue
            snippet = stmt.strip()
            try:
                fr = FileRewriter(res, snippet + "\n", None, False, Emit(relative=False), where)
                fr.rest_text = text
                new = _rewrite_smk_import(fr, text)
            except SyntaxError:
                continue
            if new is None:
                continue
            replacement, attr_edits = new
            edits.append((m.start(2), m.end(2), replacement.replace("\n", "\n" + m.group(1))))
            edits += attr_edits
    edits += text_edits(res, text, where, [(a, b) for a, b, _ in edits])
    out, last = [], 0
    for a, b, new in sorted(edits):
        out += [text[last:a], new]
        last = b
    out.append(text[last:])
    return "".join(out)


def _rewrite_smk_import(fr: FileRewriter, whole: str):
    """An import line of a Snakemake file; attribute uses of a split module found by text."""
    node = fr.tree.body[0]
    attr_edits = []
    if isinstance(node, ast.ImportFrom) and node.level == 0:
        mod = strip(node.module or "")
        if mod is None:
            return None
        for a in node.names:
            sub = f"{mod}.{a.name}" if mod else a.name
            if fr.res.is_old(sub) and sub in fr.res.table.splits:
                local = a.asname or a.name
                uses = [(m.start(1), m.group(2)) for m in
                        re.finditer(rf"(?<![\w.])({re.escape(local)})\.(\w+)", whole)]  # fmt: skip
                uses = [(p, n) for p, n in uses if not whole[p - 5 : p].endswith("as ")]
                if len(uses) == 0:
                    die(f"{fr.where}: {PKG}.{sub} imported as {local} but not used as {local}.X")
                targets = sorted({fr.res.name(sub, n) for _, n in uses})
                if len(targets) != 1:
                    stmts = []
                    for t in targets:
                        parent, leaf = split_parent(t)
                        stmts.append(f"from {PKG}.{parent} import {leaf} as _{leaf}")
                    for p, n in uses:
                        attr_edits.append(
                            (p, p + len(local), "_" + split_parent(fr.res.name(sub, n))[1])
                        )
                    return "\n".join(stmts), attr_edits
                parent, leaf = split_parent(targets[0])
                return f"from {PKG}.{parent} import {alias_text(leaf, local)}", []
    new = fr.run().strip()
    return (new, []) if new != fr.text.strip() else None


# ------------------------------------------------------------------------------ moving files

FILE_PATH = re.compile(r"Path\(__file__\)\.resolve\(\)\.parent(?:s\[(\d+)\]|\b)")


def deepen(text: str, delta: int) -> str:
    """``Path(__file__).resolve().parent[s[N]]`` of a module moved ``delta`` folders deeper."""
    if delta == 0:
        return text

    def sub(m: re.Match) -> str:
        n = int(m.group(1)) + 1 if m.group(1) is not None else 1
        return f"Path(__file__).resolve().parents[{n - 1 + delta}]"

    return FILE_PATH.sub(sub, text)


def depth(module: str, is_pkg: bool) -> int:
    return len(module.split(".")) - (1 if not is_pkg else 0) if module else 0


def absolutize(text: str, module: str, is_pkg: bool) -> str:
    """Every relative import of ``text`` (module ``module``) written absolute."""
    tree = ast.parse(text)
    lines = text.splitlines(keepends=True)
    offs = [0]
    for line in lines:
        offs.append(offs[-1] + len(line))

    def pos(ln, col):
        return offs[ln - 1] + len(lines[ln - 1].encode()[:col].decode())

    edits = []
    for n in ast.walk(tree):
        if isinstance(n, ast.ImportFrom) and n.level:
            full = absolute(n, module, is_pkg)
            names = ", ".join(alias_text(a.name, a.asname) for a in n.names)
            edits.append((pos(n.lineno, n.col_offset), pos(n.end_lineno, n.end_col_offset),
                          f"from {full} import {names}"))  # fmt: skip
    out, last = [], 0
    for a, b, new in sorted(edits):
        out += [text[last:a], new]
        last = b
    out.append(text[last:])
    return "".join(out)


def patched(old: str, text: str, path: Path) -> str:
    """``text`` of old module ``old`` with its ``PATCHES`` applied; ``__package__`` left
    unpatched stops the run (a module path built at run time)."""
    for was, now in PATCHES.get(old, []):
        if was not in text:
            die(f"{path}: {was!r} (PATCHES[{old!r}]) is not there any more")
        text = text.replace(was, now)
    if "__package__" in text:
        die(f"{path}: builds a module path from __package__: add a PATCHES entry")
    return text


def statement_key(node: ast.stmt) -> list[str]:
    """The names a top-level statement defines (what the split table lists)."""
    if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
        return [node.name]
    if isinstance(node, ast.Assign) and all(isinstance(t, ast.Name) for t in node.targets):
        return [t.id for t in node.targets]
    if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
        return [node.target.id]
    if (
        isinstance(node, ast.If)
        and isinstance(node.test, ast.Compare)
        and isinstance(node.test.left, ast.Name)
        and node.test.left.id == "__name__"
    ):
        return ["__main__"]
    return []


@dataclass
class Piece:
    """Part of a new module: chunks of one source, and the imports they need."""

    source: str
    docstring: str | None
    future: bool
    imports: list[str]
    chunks: list[str]
    cross: dict[str, set[str]]  # new module -> names


def cut(state: State, table: Table, old: str) -> dict[str, Piece]:
    """Cut old module ``old`` into its targets (ast); every top-level statement is placed."""
    spec = table.splits[old]
    is_pkg = old in state.old_packages
    path = state.root / state.old_file(old)
    text = patched(old, path.read_text(), path)
    tree = ast.parse(text)
    doc = ast.get_docstring(tree, clean=False)
    where = {n: t for t, names in spec["targets"].items() for n in names}
    imports, future, placed = [], False, {}
    lines = text.splitlines(keepends=True)
    prev_end = 0
    body = tree.body[1:] if doc is not None else tree.body
    chunks: dict[str, list[str]] = {t: [] for t in spec["targets"]}
    top_names: dict[str, str] = {}
    for node in body:
        start = min([node.lineno] + [d.lineno for d in getattr(node, "decorator_list", [])])
        seg = "".join(lines[start - 1 : node.end_lineno])
        lead = "".join(lines[prev_end : start - 1])
        prev_end = node.end_lineno
        if isinstance(node, ast.ImportFrom) and node.module == "__future__":
            future = True
            continue
        if isinstance(node, ast.Import | ast.ImportFrom):
            imports.append(seg.strip())
            continue
        keys = statement_key(node)
        if not keys:
            die(f"{path}:{node.lineno}: a top-level statement the split cannot place: "
                f"{ast.unparse(node)[:60]!r}")  # fmt: skip
        targets = {where.get(k) for k in keys}
        if None in targets:
            missing = [k for k in keys if k not in where]
            die(
                f"{path}:{node.lineno}: {', '.join(missing)} is in no target of the split of "
                f"{PKG}.{old}: add it to SPLITS[{old!r}] in tools/relayout.py"
            )
        if len(targets) != 1:
            die(f"{path}:{node.lineno}: {keys} go to several targets")
        (t,) = targets
        chunks[t].append(lead + seg)  # the comments and blank lines above it go with it
        for k in keys:
            placed[k] = t
            top_names[k] = t
    stale = sorted(set(where) - set(placed))
    if stale:
        die(f"{path}: the split table of {PKG}.{old} lists names that are not there: {stale}")
    abs_imports = [absolutize(i, old, is_pkg) for i in imports]
    pieces = {}
    delta_src = depth(old, is_pkg)
    for t, cs in chunks.items():
        body_text = "".join(absolutize(c, old, is_pkg) for c in cs).strip("\n") + "\n"
        body_text = deepen(body_text, depth(t, False) - delta_src)
        used = {n.id for n in ast.walk(ast.parse(body_text)) if isinstance(n, ast.Name)}
        cross: dict[str, set[str]] = {}
        for name in used:
            other = top_names.get(name)
            if other is not None and other != t:
                cross.setdefault(other, set()).add(name)
        for spec_name in spec.get("keep", {}).get(t, []):
            mod, _, name = spec_name.rpartition(":")
            cross.setdefault(mod or top_names[name], set()).add(name)
        pieces[t] = Piece(old, doc, future, abs_imports, [body_text] if cs else [], cross)
    return pieces


def check_cycles(pieces: dict[str, list[Piece]]) -> None:
    """Module-level imports among the new modules of the splits must not go round."""
    graph = {t: {m for p in ps for m in p.cross} - {t} for t, ps in pieces.items()}
    seen, stack = set(), []

    def visit(n: str) -> None:
        if n in stack:
            die("an import circle among split modules: " + " -> ".join([*stack, n]))
        if n in seen:
            return
        stack.append(n)
        for m in sorted(graph.get(n, ())):
            visit(m)
        stack.pop()
        seen.add(n)

    for n in sorted(graph):
        visit(n)


def init_exports(pkg: str) -> str:
    """The re-exports of a new folder's ``__init__.py`` (``REEXPORTS``)."""
    names = []
    lines = ["", "from __future__ import annotations", ""]
    for mod, ns in REEXPORTS.get(pkg, {}).items():
        lines.append(f"from .{mod} import {', '.join(ns)}")
        names += ns
    if not names:
        return ""
    return "\n".join([*lines, "", f"__all__ = {names!r}", ""]).replace("'", '"')


def docstring(doc: str) -> str:
    """A module docstring, its paragraphs wrapped at 99 columns."""
    paras = [textwrap.fill(p, 96) for p in doc.split("\n\n")]
    text = "\n\n".join(paras)
    return f'"""{text}"""\n' if "\n" not in text else f'"""{text}\n"""\n'


def assemble(t: str, ps: list[Piece], table: Table, keep: set[tuple[str, str]]) -> str:
    """The text of new module ``t`` from its pieces (imports absolute, ``bouncedisk.old``)."""
    doc = DOCSTRINGS.get(t)
    if doc is None:
        primary = [p for p in ps if table.splits[p.source]["primary"] == t]
        doc = (primary or ps)[0].docstring or ""
    out = [docstring(doc)]
    if any(p.future for p in ps):
        out.append("from __future__ import annotations\n")
    out.append(import_block(t, ps, keep))
    out.append(
        "\n\n" + "\n\n\n".join(c.strip("\n") for p in ps for c in p.chunks) + "\n"
    )  # sources
    return "\n".join(out)


def import_block(t: str, ps: list[Piece], keep: set[tuple[str, str]]) -> str:
    lines = []
    for p in ps:
        for i in p.imports:
            if i not in lines:
                lines.append(i)
    for p in ps:
        for mod, names in sorted(p.cross.items()):
            if mod == t:
                continue
            for n in sorted(names):
                noqa = "  # noqa: F401 (looked up by name)" if (mod, n) in keep else ""
                lines.append(f"from {PKG}.{mod} import {n}{noqa}")
    return "\n".join(lines) + "\n"


def append_to(text: str, ps: list[Piece], t: str, keep) -> str:
    """Append pieces to an existing (moved) module: imports after its last import."""
    tree = ast.parse(text)
    last = 0
    for node in tree.body:
        if isinstance(node, ast.Import | ast.ImportFrom):
            last = node.end_lineno
    lines = text.splitlines(keepends=True)
    block = import_block(t, ps, keep)
    body = "\n\n" + "\n\n\n".join(c.strip("\n") for p in ps for c in p.chunks) + "\n"
    return "".join(lines[:last]) + block + "".join(lines[last:]).rstrip("\n") + "\n" + body


# ------------------------------------------------------------------------------ the run


def git(root: Path, *args: str) -> None:
    subprocess.run(["git", *args], cwd=root, check=True, capture_output=True, text=True)


def rewrite_targets(state: State) -> list[Path]:
    out = []
    for f in sorted(state.files):
        p = Path(f)
        if not (p.parts[0] in REWRITE_ROOTS or f in REWRITE_FILES):
            continue
        if SKIP_PARTS & set(p.parts) or p.parts[0] == "tools":
            continue
        if p.suffix not in TEXT_SUFFIXES and p.name != "Snakefile":
            continue
        out.append(p)
    return out


def apply(root: Path, dry_run: bool = False) -> dict:
    """Run the re-layout on the checkout at ``root``; returns what it did.

    Everything is computed first and written only when no check failed: an error leaves the
    checkout as it was.
    """
    table = Table.load()
    state = inventory(table, root)
    res = Resolver(table, state)
    report = {"moved": [], "cut": [], "created": [], "rewritten": []}

    # 1. cut the split modules
    pieces: dict[str, list[Piece]] = {}
    for old in table.splits:
        if old in state.present:
            for t, p in cut(state, table, old).items():
                pieces.setdefault(t, []).append(p)
            report["cut"].append(old)
    check_cycles(pieces)
    keep = {
        (mod or _target_of(table, spec, n), n)
        for spec in table.splits.values()
        for lst in spec.get("keep", {}).values()
        for mod, _, n in (s.rpartition(":") for s in lst)
    }
    moves = [(o, n) for o, n in table.moves.items() if o in state.present and o != n]
    report["moved"] = moves

    # 2. the new tree, in memory: path -> (text, module its relative imports are read from)
    texts: dict[Path, str] = {}
    context: dict[Path, tuple[str, bool]] = {}
    gone: set[Path] = set()
    for pkg, doc in PACKAGES.items():
        init = path_of(pkg, package=True)
        if not (root / init).exists():
            texts[init] = docstring(doc) + init_exports(pkg)
            context[init] = (pkg, True)
            report["created"].append(pkg)
    for old, new in moves:
        src, dst = state.old_file(old), path_of(new)
        delta = depth(new, False) - depth(old, old in state.old_packages)
        texts[dst] = deepen(patched(old, (root / src).read_text(), src), delta)
        context[dst] = (old, old in state.old_packages)
        gone.add(src)
    for old in report["cut"]:
        gone.add(state.old_file(old))
    generated = []
    for t, ps in sorted(pieces.items()):
        dst = path_of(t)
        if dst in texts:
            texts[dst] = append_to(texts[dst], ps, t, keep)
        elif (root / dst).exists() and dst not in gone:
            texts[dst] = append_to((root / dst).read_text(), ps, t, keep)
            context[dst] = (t, False)
        else:
            texts[dst] = assemble(t, ps, table, keep)
            context[dst] = (t, False)
        generated.append(dst)
    for rel in rewrite_targets(state):
        if rel not in gone and rel not in texts and (root / rel).exists():
            texts[rel] = (root / rel).read_text()
            if SRC in rel.parents:
                context[rel] = (module_of(rel), rel.name == "__init__.py")

    # 3. every reference, in every file
    out: dict[Path, str] = {}
    for rel, text in sorted(texts.items()):
        if rel.suffix == ".py":
            if SRC in rel.parents:
                old, old_pkg = context[rel]
                emit = Emit(True, module_of(rel), rel.name == "__init__.py")
            else:
                old, old_pkg, emit = None, False, Emit(False)
            new = FileRewriter(res, text, old, old_pkg, emit, str(rel)).run()
        else:
            smk = rel.suffix == ".smk" or rel.name == "Snakefile"
            new = rewrite_text(res, text, str(rel), python_lines=smk)
        out[rel] = new
    changed = {
        rel: t
        for rel, t in out.items()
        if not (root / rel).exists() or (root / rel).read_text() != t
    }
    report["rewritten"] = sorted(str(r) for r in changed if r not in context or r in generated
                                 or (root / r).exists())  # fmt: skip
    if dry_run:
        report["created"] += [str(g) for g in generated]
        return report

    # 4. write: git mv the whole modules (history), remove the cut ones, write the rest
    for old, new in moves:
        dst = root / path_of(new)
        dst.parent.mkdir(parents=True, exist_ok=True)
        git(root, "mv", str(state.old_file(old)), str(path_of(new)))
    for old in moves:
        if old[0] in state.old_packages:
            folder = root / state.old_file(old[0]).parent
            if folder.is_dir() and not any(p.suffix == ".py" for p in folder.rglob("*")):
                shutil.rmtree(folder)
    for old in report["cut"]:
        if (root / state.old_file(old)).exists():
            git(root, "rm", "-q", str(state.old_file(old)))
    for rel, text in changed.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    py = sorted(str(r) for r in changed if r.suffix == ".py")
    cut_files = [str(g) for g in generated]
    if cut_files:
        ruff(root, "check", "--fix", "--select", "F401,I", "--quiet", *cut_files)
    if py:
        ruff(root, "check", "--fix", "--select", "I", "--quiet", *py)
        ruff(root, "format", "--quiet", *py)
    git(root, "add", "-A", "--", "src", *[str(r) for r in changed])
    return report


def _target_of(table: Table, spec: dict, name: str) -> str:
    for t, names in spec["targets"].items():
        if name in names:
            return t
    die(f"keep: {name} is in no target")


def ruff(root: Path, *args: str) -> None:
    r = subprocess.run(["ruff", *args], cwd=root, capture_output=True, text=True)
    if r.returncode not in (0, 1):
        die(f"ruff {' '.join(args[:3])}: {r.stderr or r.stdout}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="tools/relayout.py",
        description=__doc__,
        epilog="The table:\n" + Table.load().dump(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("root", nargs="?", default=".", help="the checkout (default: .)")
    parser.add_argument("--dry-run", action="store_true", help="print the table and the plan")
    args = parser.parse_args(argv)
    root = Path(args.root).resolve()
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root,
                           capture_output=True, text=True).stdout  # fmt: skip
    if dirty and not args.dry_run:
        print("relayout: error: the checkout has changes; commit or stash them", file=sys.stderr)
        return 2
    try:
        report = apply(root, dry_run=args.dry_run)
    except RelayoutError as ex:
        print(f"relayout: error: {ex}", file=sys.stderr)
        return 2
    if args.dry_run:
        print(Table.load().dump())
        print(f"\nwould move {len(report['moved'])} modules, cut {report['cut']} into "
              f"{len(report['created'])} modules and folders")  # fmt: skip
        return 0
    if not (report["moved"] or report["cut"] or report["rewritten"]):
        print("relayout: already applied; nothing to do")
        return 0
    print(
        f"relayout: moved {len(report['moved'])} modules, cut {len(report['cut'])} "
        f"({', '.join(report['cut'])}), created {len(report['created'])} folders, rewrote "
        f"references in {len(report['rewritten'])} files; review with `git status`"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
