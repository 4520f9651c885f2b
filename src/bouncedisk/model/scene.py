"""Scenes: parameters, initial state, effects, stop rule, outputs and solver (docs/formats.md).

A scene is read from YAML, ``--set key=value`` overrides are applied to the raw mapping, and the
result is validated field by field; every problem raises :class:`~bouncedisk.model.errors.InputError`
naming the file and the dotted field.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from ..engine.bounds import MAX_EVENTS, check_state, check_time
from . import yamlio
from .errors import InputError
from .params import Parameters, PhysicalParameters, Scales, number, whole_number

#: Effects a scene may name (docs/model.md "Optional effects").
EFFECTS = (
    "impacts",
    "contact",
    "torsion",
    "impulse_cap",
    "stator_inertia",
    "kinetic_static",
    "restitution_noise",
    "load",
)
#: Solver methods: the exact engine, and comparators for the accuracy study.
SOLVERS = ("exact", "rk45", "dop853", "lsoda", "moreau")
#: Contact models: the bouncing disk (the paper) and the earlier clipped-sinusoid spring contact.
MODELS = ("bouncing", "clipped")
DEFAULT_MAX_EVENTS = 100_000_000
TOP_KEYS = (
    "name",
    "description",
    "model",
    "parameters",
    "physical",
    "initial",
    "effects",
    "stop",
    "outputs",
    "solver",
    "ensemble",
    "stats",
)
#: Largest ensemble a scene may ask for (members run one after another on each core).
MAX_MEMBERS = 100_000
#: Smallest restitution noise, in units in the last place of ``e``, that can perturb ``e``: below
#: it ``e + e_sigma * xi`` rounds back to ``e`` for most deviates ``|xi| <~ 2`` (docs/model.md).
NOISE_MIN_ULPS = 4
_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")

if TYPE_CHECKING:  # the engine (numba) is imported only when a scene is validated
    from ..engine import InitialState


@dataclass(frozen=True)
class Stop:
    """When a run ends: after ``impacts`` events, or at ``time`` (``periods`` is converted).

    ``max_events`` is the safety cap that always applies.
    """

    impacts: int | None = None
    time: float | None = None
    max_events: int = DEFAULT_MAX_EVENTS

    @property
    def kind(self) -> str:
        """``impacts`` or ``time``: what ends the run."""
        return "impacts" if self.impacts is not None else "time"


@dataclass(frozen=True)
class Trajectory:
    """Dense trajectory sampling on ``t_start, t_start + dt, …`` up to ``t_stop``."""

    dt: float
    t_start: float | None = None
    t_stop: float | None = None


@dataclass(frozen=True)
class Outputs:
    """What a run writes: events, a dense trajectory, a stroboscopic section."""

    events: bool = True
    trajectory: Trajectory | None = None
    stroboscopic: bool = False


@dataclass(frozen=True)
class Solver:
    """The solver: ``exact`` (root tolerance ``tol``) or a comparator (``tol`` or ``step``)."""

    method: str = "exact"
    tol: float = 1e-12
    step: float | None = None  # fixed step of the Moreau–Jean comparator


@dataclass(frozen=True)
class Ensemble:
    """Ensemble of ``members`` runs differing by their restitution-noise streams under ``seed``."""

    members: int = 1
    seed: int = 0


@dataclass(frozen=True)
class StatsSettings:
    """Long-run statistics: the transient ``discard`` (time) left out of every average."""

    discard: float = 0.0


@dataclass(frozen=True)
class Scene:
    """A validated scene. ``raw`` is the resolved mapping (after overrides) that ``sha256`` hashes."""

    name: str
    params: Parameters
    initial: InitialState
    effects: frozenset[str]
    stop: Stop
    outputs: Outputs
    solver: Solver
    physical: PhysicalParameters | None = None
    description: str = ""
    model: str = "bouncing"
    ensemble: Ensemble = Ensemble()
    stats: StatsSettings = StatsSettings()
    source: str = "<scene>"
    raw: dict = field(default_factory=dict, compare=False)

    @property
    def sha256(self) -> str:
        """Hash of the resolved scene (canonical JSON), so overrides change it."""
        blob = json.dumps(self.raw, sort_keys=True, default=str).encode()
        return hashlib.sha256(blob).hexdigest()

    @property
    def scales(self) -> Scales | None:
        """SI scales when the scene was given in physical units."""
        return self.physical.scales() if self.physical else None

    def has(self, effect: str) -> bool:
        """Whether the scene asked for ``effect``."""
        return effect in self.effects


# ------------------------------------------------------------------------------------ helpers
def _mapping(src: str, name: str, v: Any, keys: tuple[str, ...]) -> dict:
    if v is None:
        return {}
    if not isinstance(v, dict):
        raise InputError(src, name, f"must be a mapping, got {type(v).__name__}")
    for k in v:
        if k not in keys:
            raise InputError(src, f"{name}.{k}", f"unknown key (known: {', '.join(keys)})")
    return v


def _bool(src: str, name: str, v: Any) -> bool:
    if not isinstance(v, bool):
        raise InputError(src, name, f"must be true or false, got {v!r}")
    return v


#: Keys of a mapping of which a scene gives exactly one: an override that sets one of them drops
#: the others the scene file gave (``--set stop.time=3000`` on a scene that stops after impacts).
EXCLUSIVE_KEYS: dict[str, tuple[str, ...]] = {"stop": ("impacts", "time", "periods")}


def apply_overrides(raw: dict, overrides: list[str] | str, source: str = "--set") -> dict:
    """Apply ``key.sub=value`` overrides (values parsed as YAML) to a copy of ``raw``.

    The rules (docs/user_guide/scenes.md "Overrides"): ``key.sub=value`` sets one field and
    keeps the mapping's other fields; ``key={a: 1}`` (a YAML mapping as the value) replaces the
    whole mapping ``key``; setting one of the exclusive keys of :data:`EXCLUSIVE_KEYS` (``stop``'s
    ``impacts``, ``time``, ``periods``) removes its siblings; an empty value gives ``None``.
    One string is one override (:func:`override_items`).
    """
    out = json.loads(json.dumps(raw, default=str)) if raw else {}
    for item in override_items(overrides, source):
        if "=" not in item:
            raise InputError(source, item, "expected KEY=VALUE, e.g. parameters.e=0.6")
        key, _, text = item.partition("=")
        key = key.strip()
        if not key or any(not part for part in key.split(".")):
            raise InputError(source, item, "expected KEY=VALUE with a dotted key")
        try:
            value = yamlio.load(text, source, key) if text.strip() else None
        except yaml.YAMLError:
            raise InputError(source, key, f"cannot parse value {text!r}") from None
        node = out
        parts = key.split(".")
        for part in parts[:-1]:
            nxt = node.get(part)
            if nxt is None:
                nxt = node[part] = {}
            if not isinstance(nxt, dict):
                raise InputError(source, key, f"{part!r} is not a mapping")
            node = nxt
        exclusive = EXCLUSIVE_KEYS.get(".".join(parts[:-1]), ())
        if parts[-1] in exclusive:
            for sibling in exclusive:
                node.pop(sibling, None)
        node[parts[-1]] = value
    return out


#: Where a scene path that does not exist is looked up: ``fig3``, ``fig3.yaml`` or the checkout's
#: ``workflow/config/scenes/fig3.yaml`` name the scene the package ships (docs/formats.md "Scene file").
SHIPPED_SCENE_FOLDERS = ("", "workflow/config/scenes")


def shipped_scene(path: str | Path) -> Path | None:
    """The scene the package ships that ``path`` names, when ``path`` itself does not exist."""
    p = Path(path)
    if p.exists() or p.parent.as_posix().rstrip("/").removesuffix(".") not in SHIPPED_SCENE_FOLDERS:
        return None
    name = p.name if p.suffix == ".yaml" else f"{p.name}.yaml"
    found = resources.files("bouncedisk") / "scenes" / name
    return Path(str(found)) if found.is_file() else None


def read_yaml(path: str | Path, what: str = "scene") -> dict:
    """Read a YAML mapping, turning every failure into one :class:`InputError` line that calls
    the file ``what`` (a scene, a sidecar, ...). A scene that does not exist but names one the
    package ships (:func:`shipped_scene`) is read from the package."""
    p = Path(path)
    src = str(path)
    if what == "scene" and (shipped := shipped_scene(p)) is not None:
        p = shipped
    if p.exists() and not p.is_dir() and not p.is_file():  # a FIFO would block in open()
        raise InputError(src, "", f"is not a regular file (a pipe or device?), not a {what} file")
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(src, "", "file not found") from None
    except IsADirectoryError:
        raise InputError(src, "", f"is a directory, not a {what} file") from None
    except UnicodeDecodeError:
        raise InputError(src, "", "not a text (UTF-8) file") from None
    except OSError as ex:
        raise InputError(src, "", f"cannot read: {ex.strerror}") from None
    try:
        data = yamlio.load(text, src)
    except yaml.YAMLError as ex:
        mark = getattr(ex, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark else "YAML"
        problem = getattr(ex, "problem", None) or "malformed YAML"
        raise InputError(src, where, f"malformed YAML: {problem}") from None
    if data is None:
        raise InputError(src, "", f"empty {what} file")
    if not isinstance(data, dict):
        raise InputError(src, "", f"a {what} must be a YAML mapping, got {type(data).__name__}")
    return data


# ------------------------------------------------------------------------------------ parsing
def _effects(src: str, v: Any) -> frozenset[str]:
    if v is None:
        v = ["impacts", "contact"]
    chosen: dict[str, bool] = {}
    if isinstance(v, str):
        v = [x.strip() for x in v.split(",") if x.strip()]
    if isinstance(v, list):
        for i, item in enumerate(v):
            if not isinstance(item, str):
                raise InputError(src, f"effects[{i}]", f"must be an effect name, got {item!r}")
            chosen[item] = True
    elif isinstance(v, dict):
        for k, on in v.items():
            chosen[str(k)] = _bool(src, f"effects.{k}", on)
    else:
        raise InputError(src, "effects", "must be a list of effect names")
    for k in chosen:
        if k not in EFFECTS:
            raise InputError(src, f"effects.{k}", f"unknown effect (known: {', '.join(EFFECTS)})")
    if chosen.get("impacts") is False:
        raise InputError(src, "effects.impacts", "cannot be turned off")
    on = {k for k, flag in chosen.items() if flag} | {"impacts"}
    if "torsion" in on and chosen.get("impulse_cap") is not False:
        on.add("impulse_cap")
    for dep in ("impulse_cap", "stator_inertia", "kinetic_static", "load"):
        if dep in on and "torsion" not in on:
            raise InputError(src, f"effects.{dep}", "needs the 'torsion' effect")
    if "kinetic_static" in on and "contact" not in on:
        raise InputError(src, "effects.kinetic_static", "needs the 'contact' effect")
    return frozenset(on)


def scene_from_mapping(raw: dict, source: str = "<scene>") -> Scene:
    """Validate a raw scene mapping into a :class:`Scene`, one section after another.

    Raises
    ------
    InputError
        Naming ``source`` and the dotted field at fault.
    """
    src = source
    if not isinstance(raw, Mapping):
        how = "load_scene(path) reads a scene file" if isinstance(raw, str | Path) else ""
        raise InputError(
            src,
            "",
            f"a scene must be a mapping (a dict of its sections), got {type(raw).__name__}"
            + (f"; {how}" if how else ""),
        )
    for k in raw:
        if k not in TOP_KEYS:
            raise InputError(src, str(k), f"unknown key (known: {', '.join(TOP_KEYS)})")
    name, description = _name(src, raw)
    params, physical = _parameters(src, raw)
    effects = _effects(src, raw.get("effects"))
    _check_effect_parameters(src, raw, effects, params)
    initial = _initial(src, raw.get("initial"), params)
    stop = _stop(src, raw.get("stop"), initial, params)
    outputs = _outputs(src, raw.get("outputs"), initial, stop, params)
    solver = _solver(src, raw.get("solver"))
    model = _model(src, raw.get("model", "bouncing"), stop, solver, effects)
    ensemble = _ensemble(src, raw.get("ensemble"), effects, params)
    stats = _stats(src, raw.get("stats"), stop, initial, physical)
    return Scene(
        name=name,
        model=model,
        ensemble=ensemble,
        stats=stats,
        params=params,
        initial=initial,
        effects=effects,
        stop=stop,
        outputs=outputs,
        solver=solver,
        physical=physical,
        description=description,
        source=src,
        raw=raw,
    )


def _name(src: str, raw: dict) -> tuple[str, str]:
    """``name`` (default: the file's stem) and ``description``."""
    default = Path(src).stem if src and not src.startswith("<") else "scene"
    name = raw.get("name", default)
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise InputError(
            src, "name", f"must be a simple name (letters, digits, _ . -), got {name!r}"
        )
    description = raw.get("description", "")
    if not isinstance(description, str):
        raise InputError(src, "description", "must be text")
    return name, description


#: How a physical scene's nondimensional parameters follow from its SI fields (docs/model.md
#: "Physical conversion"): an error in one names the fields a user wrote.
DERIVED_FROM = {
    "omega_s": "2π f t_c, t_c = sqrt(U0 / g_eff), g_eff = g + F_preload / m_r: from physical.f, "
    "U0, g, F_preload and m_r",
    "r_phi": "(r_eff / r_g)² mu U0 / (r_eff Phi0), r_eff = 2 r_c / 3: from physical.r_c, r_g, "
    "mu, U0 and Phi0",
    "load_torque": "load_torque / (mu m_r g_eff r_eff): from physical.load_torque, mu, m_r, g, "
    "F_preload and r_c",
}


def _parameters(src: str, raw: dict) -> tuple[Parameters, PhysicalParameters | None]:
    """``parameters`` (nondimensional) or ``physical`` (SI, converted: docs/model.md eqs. 2, 13–15)."""
    if "parameters" in raw and "physical" in raw:
        raise InputError(src, "physical", "give either 'parameters' or 'physical', not both")
    if "physical" in raw:
        pm = _mapping(
            src, "physical", raw["physical"], tuple(PhysicalParameters.__dataclass_fields__)
        )
        physical = PhysicalParameters.from_mapping(pm, src)
        try:
            params = physical.to_nondimensional()  # validated as it is made
        except InputError as ex:  # the nondimensional value the SI ones give, named by section
            name = ex.field.removeprefix("Parameters.")
            how = DERIVED_FROM.get(name)
            message = f"{ex.message} ({name} is {how})" if how else ex.message
            raise InputError(src, f"physical.{name}", message) from None
        return params, physical
    if "parameters" in raw:
        pm = raw["parameters"]
        if not isinstance(pm, dict):
            raise InputError(src, "parameters", "must be a mapping")
        return Parameters.from_mapping(pm, src), None
    raise InputError(src, "parameters", "is required (or 'physical')")


def _check_effect_parameters(
    src: str, raw: dict, effects: frozenset[str], params: Parameters
) -> None:
    """The parameters an effect needs are given (docs/model.md "Optional effects")."""
    if "stator_inertia" in effects and math.isinf(params.inertia_ratio):
        raise InputError(
            src, "parameters.inertia_ratio", "is required by the 'stator_inertia' effect"
        )
    if (
        "kinetic_static" in effects
        and params.mu_ratio == 1.0
        and "mu_ratio" not in (raw.get("parameters") or {})
    ):
        raise InputError(src, "parameters.mu_ratio", "is required by the 'kinetic_static' effect")
    _check_paired(src, raw, effects)


def _initial(src: str, v: Any, params: Parameters) -> InitialState:
    """``initial: {t, omega, u, v}``; ``u >= u_s(t)`` (eq. 1) for a start in flight; every
    value within the engine's bounds (:func:`bouncedisk.engine.bounds.check_state`).

    The scene holds the engine's own :class:`~bouncedisk.engine.InitialState`.
    """
    from ..engine import InitialState

    im = _mapping(src, "initial", v, ("t", "omega", "u", "v"))
    t0 = number(src, "initial.t", im.get("t", 0.0))
    om0 = number(src, "initial.omega", im.get("omega", 0.0))
    u0 = im.get("u")
    v0 = im.get("v")
    u0 = None if u0 is None else number(src, "initial.u", u0)
    v0 = None if v0 is None else number(src, "initial.v", v0)
    check_state(src, "initial.", params.omega_s, (t0, om0, u0, v0))  # in flight: above the stator
    return InitialState(t=t0, omega=om0, u=u0, v=v0)


def _stop(src: str, v: Any, initial: InitialState, params: Parameters) -> Stop:
    """``stop``: exactly one of ``impacts``, ``time``, ``periods``; the cap ``max_events``."""
    sm = _mapping(src, "stop", v, ("impacts", "time", "periods", "max_events"))
    given = [k for k in ("impacts", "time", "periods") if sm.get(k) is not None]
    if len(given) != 1:
        raise InputError(src, "stop", "give exactly one of impacts, time or periods")
    max_ev = whole_number(src, "stop.max_events", sm.get("max_events", DEFAULT_MAX_EVENTS))
    if max_ev > MAX_EVENTS:
        raise InputError(src, "stop.max_events", f"must be <= 2**63 - 1, got {max_ev}")
    if given[0] == "impacts":
        n = whole_number(src, "stop.impacts", sm["impacts"])
        if n > max_ev:
            raise InputError(
                src,
                "stop.impacts",
                f"{n} is above the safety cap stop.max_events = {max_ev}; "
                "ask for fewer impacts or raise stop.max_events",
            )
        return Stop(impacts=n, max_events=max_ev)
    if given[0] == "time":
        t_stop = number(src, "stop.time", sm["time"], positive=True)
        return Stop(time=_end_time(src, "stop.time", initial.t + t_stop, params), max_events=max_ev)
    periods = number(src, "stop.periods", sm["periods"], positive=True)
    t_end = initial.t + periods * 2.0 * math.pi / params.omega_s
    return Stop(time=_end_time(src, "stop.periods", t_end, params), max_events=max_ev)


def _end_time(src: str, name: str, t_end: float, params: Parameters) -> float:
    """The run's end time ``t_end`` within the engine's bounds (``name`` gave it)."""
    return check_time(src, name, t_end, params.omega_s)


def _outputs(src: str, v: Any, initial: InitialState, stop: Stop, params: Parameters) -> Outputs:
    """``outputs: {events, trajectory, stroboscopic}``."""
    om = _mapping(src, "outputs", v, ("events", "trajectory", "stroboscopic"))
    events = _bool(src, "outputs.events", om.get("events", True))
    traj = _trajectory(src, om.get("trajectory"), initial, stop, params.omega_s)
    strobe = _bool(src, "outputs.stroboscopic", om.get("stroboscopic", False))
    return Outputs(events=events, trajectory=traj, stroboscopic=strobe)


def _trajectory(
    src: str, tm: Any, initial: InitialState, stop: Stop, w: float
) -> Trajectory | None:
    """``outputs.trajectory``: ``true`` (``dt = 0.01``) or ``{dt, t_start, t_stop}``, its times
    within the engine's bounds at ``omega_s = w``."""
    if tm is None or tm is False:
        return None
    if tm is True:
        tm = {"dt": 0.01}
    tm = _mapping(src, "outputs.trajectory", tm, ("dt", "t_start", "t_stop"))
    if "dt" not in tm:
        raise InputError(src, "outputs.trajectory.dt", "is required")
    dt = number(src, "outputs.trajectory.dt", tm["dt"], positive=True)
    ts, te = (_time(src, f"outputs.trajectory.{k}", tm.get(k), w) for k in ("t_start", "t_stop"))
    if ts is not None and te is not None and te < ts:
        raise InputError(src, "outputs.trajectory.t_stop", "must be >= t_start")
    horizon = te if te is not None else stop.time
    if horizon is not None and (horizon - (ts if ts is not None else initial.t)) / dt > 5e8:
        raise InputError(src, "outputs.trajectory.dt", "would produce more than 5e8 samples")
    return Trajectory(dt=dt, t_start=ts, t_stop=te)


def _time(src: str, name: str, value: Any, w: float) -> float | None:
    """An optional time field within the engine's bounds at ``omega_s = w``."""
    return None if value is None else check_time(src, name, number(src, name, value), w)


def _solver(src: str, v: Any) -> Solver:
    """``solver: {method, tol, step}``."""
    vm = _mapping(src, "solver", v, ("method", "tol", "step"))
    method = vm.get("method", "exact")
    if method not in SOLVERS:
        raise InputError(
            src, "solver.method", f"unknown method {method!r} (known: {', '.join(SOLVERS)})"
        )
    tol = number(src, "solver.tol", vm.get("tol", 1e-12), positive=True)
    if tol > 1e-2:
        raise InputError(src, "solver.tol", f"must be <= 1e-2, got {tol}")
    step = vm.get("step")
    if step is not None:
        step = number(src, "solver.step", step, positive=True)
    return Solver(method=method, tol=tol, step=step)


def _model(src: str, model: Any, stop: Stop, solver: Solver, effects: frozenset[str]) -> str:
    """``model``: ``bouncing`` or ``clipped`` (the ``contact`` effect, a time stop and the exact
    solver only)."""
    if model not in MODELS:
        raise InputError(src, "model", f"unknown model {model!r} (known: {', '.join(MODELS)})")
    if model == "clipped":
        if "contact" not in effects:
            raise InputError(
                src,
                "effects",
                "the clipped model is a contact that never opens: add the 'contact' effect",
            )
        if stop.time is None:
            raise InputError(
                src, "stop", "the clipped model has no impacts: stop on time or periods"
            )
        if solver.method != "exact":
            raise InputError(
                src, "solver.method", "the clipped model runs with the exact solver only"
            )
    return model


#: Parameters that go with one effect, both or neither: (parameter, effect).
PAIRED_PARAMETERS = (("e_sigma", "restitution_noise"), ("load_torque", "load"))


def _check_paired(src: str, raw: dict, effects: frozenset[str]) -> None:
    """``parameters.e_sigma`` goes with ``restitution_noise`` and ``load_torque`` with ``load``
    (``physical.load_torque`` in a physical scene), both or neither."""
    for name, effect in PAIRED_PARAMETERS:
        section = "physical" if "physical" in raw else "parameters"
        given = name in (raw.get(section) or {})
        if effect in effects and not given:
            raise InputError(src, f"{section}.{name}", f"is required by the '{effect}' effect")
        if given and effect not in effects:
            raise InputError(src, f"{section}.{name}", f"needs the '{effect}' effect")


def _ensemble(src: str, v: Any, effects: frozenset[str], params: Parameters) -> Ensemble:
    """Validate ``ensemble: {members, seed}`` (docs/formats.md)."""
    em = _mapping(src, "ensemble", v, ("members", "seed"))
    if isinstance(em.get("members"), str):  # a quoted '3' is text, not a count
        raise InputError(
            src, "ensemble.members", f"must be a whole number, got the text {em['members']!r}"
        )
    members = whole_number(src, "ensemble.members", em.get("members", 1))
    if members > MAX_MEMBERS:
        raise InputError(src, "ensemble.members", f"must be <= {MAX_MEMBERS}, got {members}")
    seed = whole_number(src, "ensemble.seed", em.get("seed", 0), minimum=0)
    if seed >= 2**63:
        raise InputError(src, "ensemble.seed", f"must be < 2**63, got {seed}")
    least = NOISE_MIN_ULPS * math.ulp(params.e)
    if 0.0 < params.e_sigma < least:
        raise InputError(
            src,
            "parameters.e_sigma",
            f"{params.e_sigma:.3g} is below {NOISE_MIN_ULPS} ulp of e ({least:.3g}): e + e_sigma*xi "
            "rounds back to e, so the noise perturbs nothing and every member is the same run; "
            f"give e_sigma >= {least:.3g} (or 0 for a deterministic run)",
        )
    if members > 1 and ("restitution_noise" not in effects or params.e_sigma == 0.0):
        raise InputError(
            src,
            "ensemble.members",
            "members differ only by their restitution noise: add the 'restitution_noise' "
            "effect and parameters.e_sigma > 0 (e.g. 1e-9)",
        )
    return Ensemble(members=members, seed=seed)


def _stats(
    src: str, v: Any, stop: Stop, initial: InitialState, physical: PhysicalParameters | None
) -> StatsSettings:
    """Validate ``stats: {discard}``: a transient shorter than the run."""
    sm = _mapping(src, "stats", v, ("discard",))
    discard = number(src, "stats.discard", sm.get("discard", 0.0), nonneg=True)
    if stop.time is not None and discard >= stop.time - initial.t:
        raise InputError(
            src,
            "stats.discard",
            f"must be shorter than the run (stop.time - initial.t = {stop.time - initial.t:g} "
            f"time units), got {discard:g}: lower stats.discard or raise stop.time"
            f"{time_unit_note(physical)}",
        )
    return StatsSettings(discard=discard)


def time_unit_note(physical: PhysicalParameters | None) -> str:
    """For a physical scene, the note that its times are in units of ``t_c``, not seconds
    (docs/formats.md, "Physical parameters"); empty for a nondimensional one. Ends an error's line."""
    if physical is None:
        return ""
    return f" (a scene's times are in units of t_c = {physical.scales().t_c:.4g} s, not seconds)"


def check_swept(scene: Scene, axes: Mapping[str, Mapping], source: str, key: str) -> None:
    """Every value a sweep gives ``scene``'s parameters is one the model takes, checked before
    any point runs (a pipeline's sweep would otherwise run its first shards and fail on a
    later one). ``axes``: parameter -> ``{min, max, n}`` or ``{values: [...]}`` (the ends of a
    range suffice: the parameters' bounds are ranges); errors name ``key.<parameter>``.

    Raises
    ------
    InputError
        Naming ``source`` and the axis: not a parameter, or a value the model refuses.
    """
    known = [f.name for f in fields(Parameters)]
    for name, spec in axes.items():
        where = f"{key}.{name}"
        if name not in known:
            raise InputError(source, where, f"not a parameter (known: {', '.join(known)})")
        ends = spec["values"] if "values" in spec else (spec["min"], spec["max"])
        for value in ends:
            try:
                scene.params.replaced(source, **{name: float(value)})
            except InputError as ex:
                raise InputError(source, where, f"the value {value:g}: {ex.message}") from None


def require_scene(scene: object, what: str = "scene") -> Scene:
    """``scene`` if it is a :class:`Scene`, else one :class:`InputError` that says how to make
    one: the public functions that run a scene take the validated object, not its file or
    mapping."""
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, str | Path):
        how = "load_scene(path)"
    elif isinstance(scene, Mapping):
        how = "scene_from_mapping(mapping)"
    else:
        how = "load_scene(path) or scene_from_mapping(mapping)"
    raise InputError(
        "<arguments>", what, f"must be a Scene, got {type(scene).__name__}: make one with {how}"
    )


def load_scene(path: str | Path, overrides: list[str] | str | None = None) -> Scene:
    """Read, override and validate a scene file.

    ``overrides`` are ``--set`` items, ``KEY=VALUE`` (:func:`apply_overrides`); one string is
    one item.

    Raises
    ------
    InputError
        Naming the file and the field at fault; a field that a ``--set`` option gave (or a
        field inside it) also names the option: ``parameters.e (from --set parameters.e)``.
    """
    if not isinstance(path, str | Path):
        how = "; scene_from_mapping(mapping) takes a dict" if isinstance(path, Mapping) else ""
        raise InputError(
            "<arguments>", "path", f"must be a file's path, got {type(path).__name__}{how}"
        )
    raw = read_yaml(path)
    overrides = override_items(overrides)
    if not overrides:
        return scene_from_mapping(raw, str(path))
    raw = apply_overrides(raw, overrides)
    try:
        return scene_from_mapping(raw, str(path))
    except InputError as ex:
        key = override_of(ex.field, overrides)
        if key is None:
            raise
        raise InputError(ex.source, f"{ex.field} (from --set {key})", ex.message) from None


def override_items(overrides: object, source: str = "--set") -> list[str]:
    """``overrides`` as a list of ``KEY=VALUE`` items: one string is one item (not its
    characters), ``None`` none.

    Raises
    ------
    InputError
        For anything else than strings.
    """
    if overrides is None:
        return []
    items = [overrides] if isinstance(overrides, str) else overrides
    try:
        items = list(items)
    except TypeError:
        items = [items]
    for item in items:
        if not isinstance(item, str):
            raise InputError(
                source, "", f"an override is a string KEY=VALUE, got {type(item).__name__}"
            )
    return items


def override_of(field: str, overrides: list[str]) -> str | None:
    """The key of the last ``--set KEY=VALUE`` that gave ``field``, a field inside it, or a
    mapping that holds it; ``None`` when the scene file gave it."""
    for item in reversed(overrides):
        key = item.partition("=")[0].strip()
        if not key or not field:
            continue
        if field == key or field.startswith((key + ".", key + "[")) or key.startswith(field + "."):
            return key
    return None
