"""Settings of the global sensitivity study (``sensitivity`` and ``sensitivity_study`` in the config).

Standard library only (the Snakefile checks them when it is parsed, before the JSON schema and
before any job runs): every bad range or size is one :class:`~bouncedisk.model.errors.InputError`
naming the field. :data:`LIMITS` and :data:`DOMAIN` are the one copy of the bounds; the schema
``workflow/schemas/config.schema.yaml`` repeats them and a test checks that it does.

Times are in units of ``1/R_φ``, the run-up's own time scale: the rotor's ``x = R_φ Ω`` evolves
at a rate proportional to ``R_φ`` (docs/model.md "Events", "Contact, slipping"), so a run of
``discard + duration`` in these units covers the same number of run-up time constants at every
``R_φ``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from ..model.errors import InputError
from ..model.params import number, whole_number

#: The sampled parameters, in the order of SALib's problem (``log10_r_phi`` is log10 of ``R_φ``).
PARAMETERS = ("e", "omega_s", "log10_r_phi", "psi")
#: What each parameter's range must lie in (the model's domain; ``R_φ`` limited by the cost
#: ``∝ 1/R_φ`` of a run).
DOMAIN: dict[str, tuple[float, float]] = {
    "e": (0.0, 1.0),
    "omega_s": (1.0, 100.0),
    "log10_r_phi": (-4.0, 0.0),
    "psi": (-2.0 * math.pi, 2.0 * math.pi),
}
#: Bounds of the sizes: name -> (minimum, maximum).
LIMITS: dict[str, tuple[float, float]] = {
    "base_samples": (4, 65536),  # SALib Saltelli/Sobol' N, a power of 2
    "shards": (1, 10000),
    "members": (2, 1024),
    "duration": (1.0, 10000.0),  # averaging time after the transient, units 1/R_phi
    "discard": (0.0, 10000.0),  # transient left out, units 1/R_phi
    "resamples": (10, 100000),  # SALib bootstrap resamples
    "map_points": (2, 400),  # design-map grid points per axis
    "load": (0.0, 2.0),  # load torques tau_L (in units of the friction torque)
}
#: The sizes a study must have; ``full`` must have at least this many base samples.
SIZES = ("small", "full")
FULL_MIN_BASE_SAMPLES = 1024
SOURCE = "pipeline config"


@dataclass(frozen=True)
class StudySettings:
    """One size of the study, its ranges and its design maps (all checked).

    Attributes
    ----------
    size : str
        ``small`` or ``full``.
    ranges : dict
        Parameter -> ``(low, high)``, in the order of :data:`PARAMETERS`.
    base_samples, shards, members, resamples : int
        SALib's ``N`` (``N (D + 2)`` points), shard jobs, ensemble members per point, bootstrap
        resamples of the indices.
    duration, discard : float
        Averaging time and transient, in units of ``1/R_φ``.
    loads : tuple of float
        Load torques of each point's torque–speed curve, from 0 (empty: no load figures).
    seed : int
        Seed of the Sobol' sequence's scrambling, the ensembles and the bootstrap.
    e_sigma : float
        Restitution noise of the members (docs/model.md "Long-run statistics of chaotic motion").
    map_e, map_omega_s, map_points
        Design maps over ``(psi, log10_r_phi)``: one per ``e`` in ``map_e`` at ``map_omega_s``,
        ``map_points = (n_psi, n_r_phi)``.
    runup : float
        Transient added to ``discard`` for each point's first run, from rest, in units of
        ``1/R_φ`` (the design maps': the run-up is slower at small ``R_φ``); the continued loads
        start near their own speed and leave out ``discard``.
    running : bool
        Load figures in the motor's own running direction (the load opposes the no-load
        motion, :class:`bouncedisk.studies.sensitivity.MotorModel`); the design maps keep the
        sign convention of the torque–speed curves (load against positive rotation), ``False``.
    """

    size: str
    ranges: dict[str, tuple[float, float]]
    base_samples: int
    shards: int
    members: int
    duration: float
    discard: float
    resamples: int
    loads: tuple[float, ...]
    seed: int
    e_sigma: float
    map_e: tuple[float, ...]
    map_omega_s: float
    map_points: tuple[int, int]
    running: bool = True
    runup: float = 0.0

    @classmethod
    def from_params(cls, params: Mapping) -> StudySettings:
        """Back from :func:`dataclasses.asdict` (a pipeline rule's params)."""
        p = dict(params)
        p["ranges"] = {k: tuple(v) for k, v in p["ranges"].items()}
        for k in ("loads", "map_e", "map_points"):
            p[k] = tuple(p[k])
        return cls(**p)

    @property
    def n_points(self) -> int:
        """Points of the Sobol' design without second-order indices: ``N (D + 2)``."""
        return self.base_samples * (len(self.ranges) + 2)


def _within(field: str, x: float, lo: float, hi: float) -> float:
    if not lo <= x <= hi:
        raise InputError(SOURCE, field, f"must be in [{lo:g}, {hi:g}], got {x:g}")
    return x


def _size(field: str, value: object, name: str) -> int:
    lo, hi = LIMITS[name]
    return int(_within(field, whole_number(SOURCE, field, value, minimum=int(lo)), lo, hi))


#: The keys of the config's ``sensitivity_study`` mapping.
STUDY_KEYS = ("ranges", "seed", "e_sigma", "design_map", "sizes")


def _mapping(field: str, value: object, keys: Sequence[str] | None = None) -> Mapping:
    """``value`` as a mapping; with ``keys``, one whose every key is one of them."""
    if not isinstance(value, Mapping):
        raise InputError(SOURCE, field, f"must be a mapping, got {value!r}")
    unknown = [k for k in value if keys is not None and k not in keys]
    if unknown:
        raise InputError(
            SOURCE, f"{field}.{unknown[0]}", f"unknown key; expected one of {list(keys)}"
        )
    return value


def _ranges(value: object) -> dict[str, tuple[float, float]]:
    where = "sensitivity_study.ranges"
    given = _mapping(where, value)
    if set(given) != set(PARAMETERS):
        raise InputError(SOURCE, where, f"must give exactly {list(PARAMETERS)}, got {list(given)}")
    out = {}
    for name in PARAMETERS:
        field = f"{where}.{name}"
        pair = given[name]
        if not isinstance(pair, Sequence) or isinstance(pair, str) or len(pair) != 2:
            raise InputError(SOURCE, field, f"must be [low, high], got {pair!r}")
        lo, hi = (number(SOURCE, field, v) for v in pair)
        if not lo < hi:
            raise InputError(SOURCE, field, f"low must be below high, got [{lo:g}, {hi:g}]")
        for x in (lo, hi):
            _within(field, x, *DOMAIN[name])
        out[name] = (lo, hi)
    return out


def _numbers(field: str, value: object, lo: float, hi: float) -> tuple[float, ...]:
    if not isinstance(value, Sequence) or isinstance(value, str):
        raise InputError(SOURCE, field, f"must be a list of numbers, got {value!r}")
    xs = tuple(_within(field, number(SOURCE, field, v), lo, hi) for v in value)
    if any(b <= a for a, b in zip(xs, xs[1:], strict=False)):
        raise InputError(SOURCE, field, f"must increase, got {list(xs)}")
    return xs


def _size_settings(size: str, sizes: Mapping) -> dict:
    where = f"sensitivity_study.sizes.{size}"
    s = _mapping(where, sizes.get(size))
    keys = ("base_samples", "shards", "members", "duration", "discard", "resamples", "loads")
    unknown = set(s) - set(keys) - {"map_points"}
    if unknown or not set(keys) <= set(s):
        raise InputError(SOURCE, where, f"must give {list(keys)} and map_points, got {list(s)}")
    out = {k: _size(f"{where}.{k}", s[k], k) for k in ("base_samples", "members", "resamples")}
    n = out["base_samples"]
    if n & (n - 1):
        raise InputError(SOURCE, f"{where}.base_samples", f"must be a power of 2, got {n}")
    if size == "full" and n < FULL_MIN_BASE_SAMPLES:
        raise InputError(
            SOURCE, f"{where}.base_samples", f"must be >= {FULL_MIN_BASE_SAMPLES}, got {n}"
        )
    out["shards"] = _size(f"{where}.shards", s["shards"], "shards")
    for k in ("duration", "discard"):
        out[k] = _within(f"{where}.{k}", number(SOURCE, f"{where}.{k}", s[k]), *LIMITS[k])
    out["loads"] = _numbers(f"{where}.loads", s["loads"], *LIMITS["load"])
    if out["loads"] and out["loads"][0] != 0.0:
        # the curve's first load is the point's no-load run (MotorModel)
        raise InputError(SOURCE, f"{where}.loads", f"must start at 0, got {list(out['loads'])}")
    mp = s.get("map_points")
    if not isinstance(mp, Sequence) or isinstance(mp, str) or len(mp) != 2:
        raise InputError(SOURCE, f"{where}.map_points", f"must be [n_psi, n_r_phi], got {mp!r}")
    out["map_points"] = tuple(_size(f"{where}.map_points", v, "map_points") for v in mp)
    return out


def study_settings(config: Mapping) -> StudySettings:
    """The study the pipeline config asks for (``sensitivity``: ``small`` or ``full``).

    Raises
    ------
    InputError
        One line naming the field: an unknown size, a range outside :data:`DOMAIN` or empty, a
        size outside :data:`LIMITS`, more shards than points, a missing key.
    """
    size = config.get("sensitivity", "small")
    if size not in SIZES:
        raise InputError(SOURCE, "sensitivity", f"must be small or full, got {size!r}")
    study = _mapping("sensitivity_study", config.get("sensitivity_study"), STUDY_KEYS)
    ranges = _ranges(study.get("ranges"))
    sizes = _mapping("sensitivity_study.sizes", study.get("sizes"))
    s = _size_settings(size, sizes)
    n_points = s["base_samples"] * (len(PARAMETERS) + 2)
    if s["shards"] > n_points:
        raise InputError(
            SOURCE,
            f"sensitivity_study.sizes.{size}.shards",
            f"{s['shards']} shards for only {n_points} points",
        )
    dm = _mapping("sensitivity_study.design_map", study.get("design_map"), ("e", "omega_s"))
    map_e = _numbers("sensitivity_study.design_map.e", dm.get("e"), *DOMAIN["e"])
    if not map_e:
        raise InputError(SOURCE, "sensitivity_study.design_map.e", "must name at least one e")
    map_w = _within(
        "sensitivity_study.design_map.omega_s",
        number(SOURCE, "sensitivity_study.design_map.omega_s", dm.get("omega_s")),
        *DOMAIN["omega_s"],
    )
    seed = whole_number(SOURCE, "sensitivity_study.seed", study.get("seed"), minimum=0)
    sigma = number(SOURCE, "sensitivity_study.e_sigma", study.get("e_sigma"), positive=True)
    _within("sensitivity_study.e_sigma", sigma, 0.0, 0.5)
    return StudySettings(
        size=size,
        ranges=ranges,
        seed=seed,
        e_sigma=sigma,
        map_e=map_e,
        map_omega_s=map_w,
        **s,
    )
