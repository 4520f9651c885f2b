"""What is recorded, extracted generically from output files: netCDF attributes, JSON leaves,
benchmark columns, the checks table; file hashes.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import re
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

from ..io.provenance import sha256_file
from .store import one_line

HASH_CACHE = ".tracking-hashes.json"

# global attributes that change on every run without meaning anything (never params)
VOLATILE_ATTRS = {
    "created",
    "date_created",
    "date_modified",
    "history",
    "Conventions",
    "title",
    "source",
    "references",
    # ACDD metadata: dates of this writing, the id (the run id), who made it (not inputs)
    "date_issued",
    "date_metadata_modified",
    "id",
    "naming_authority",
    "processing_level",
    "product_version",
    "standard_name_vocabulary",
    "summary",
    "keywords",
    "creator_name",
    "creator_email",
    "creator_url",
    "creator_type",
    "creator_institution",
    "institution",
    "project",
    "license",
    "acknowledgement",
    "publisher_name",
    "publisher_email",
    "publisher_url",
    "publisher_type",
    "publisher_institution",
}
# numeric global attributes that are inputs (params), not results (metrics)
PARAM_ATTRS = {
    "e",
    "omega_s",
    "r_phi",
    "psi",
    "gamma",
    "tol",
    "step",
    "inertia_ratio",
    "mu_ratio",
    "e_sigma",
    "seed",
    "members",
    "discard",
    "duration",
    "bootstrap",
    "n_bootstrap",
    "scan_points",
    "zoom_points",
    "joint_zoom_points",
    "tail",
    "shard",
    "n_shards",
    "transient_events",
    "max_events",
    "base_samples",
    "total_points",
}
PARAM_PREFIXES = ("initial_", "physical_", "ensemble_", "stop_")
# what a nested run's kind is, from its rule's name (figures first, then the first prefix that
# matches); others are "job"
KINDS = (
    ("simulate", "simulation"),
    ("sweep", "sweep"),
    ("stats", "statistics"),
    ("ensemble", "statistics"),
    ("fit", "fit"),
    ("check", "check"),
    ("reproduction", "check"),
    ("compile", "build"),
    ("poincare", "study"),
    ("clipped", "study"),
    ("work_precision", "study"),
    ("scaling", "study"),
    ("sensitivity", "study"),
    ("synthetic", "data"),
)
MAX_PARAM = 500  # characters of a param value kept (MLflow allows 6000)


# ------------------------------------------------------------------------------------------
# Generic extraction from output files
# ------------------------------------------------------------------------------------------


def _number(v: Any) -> float | None:
    """A finite float from a Python/numpy scalar (bools as 0/1), else None."""
    try:
        import numpy as np

        if isinstance(v, np.ndarray):
            if v.ndim != 0:
                return None
            v = v.item()
        if isinstance(v, np.generic):
            v = v.item()
    except ImportError:  # pragma: no cover
        pass
    if isinstance(v, bool):
        return float(v)
    if isinstance(v, int | float):
        f = float(v)
        return f if math.isfinite(f) else None
    return None


def _seq(v: Any) -> list | None:
    """A short 1-D numeric sequence (e.g. a [low, high] interval) as a list, else None."""
    try:
        import numpy as np

        if isinstance(v, np.ndarray) and v.ndim == 1:
            v = v.tolist()
    except ImportError:  # pragma: no cover
        pass
    if isinstance(v, list | tuple) and 0 < len(v) <= 10 and all(_number(x) is not None for x in v):
        return list(v)
    return None


def _seq_keys(name: str, n: int) -> list[str]:
    if n == 2 and "ci" in name.lower():
        return [f"{name}.low", f"{name}.high"]
    return [f"{name}.{i}" for i in range(n)]


def is_param_attr(name: str) -> bool:
    """Whether a numeric global attribute is an input (param) rather than a result (metric)."""
    return name in PARAM_ATTRS or name.startswith(PARAM_PREFIXES)


def _clean_key(key: str) -> str:
    """A valid MLflow key (letters, digits, ``_ - . / space``)."""
    return re.sub(r"[^A-Za-z0-9_\-./ ]", "_", key)[:250]


def _param_value(v: Any) -> str:
    if isinstance(v, float):
        text = repr(v)
    elif isinstance(v, str):
        text = v
    else:
        text = json.dumps(v, default=str, sort_keys=True)
    return text[:MAX_PARAM]


def netcdf_fields(path: Path) -> tuple[dict[str, str], dict[str, float]]:
    """Params and metrics of one netCDF file (global attributes, scalar data variables).

    Reads attributes and scalars only, with netCDF4 directly: xarray would decode every
    variable's metadata and build indexes, for each of a pipeline's outputs.
    """
    import netCDF4

    params: dict[str, str] = {}
    metrics: dict[str, float] = {}
    with netCDF4.Dataset(path, "r") as nc:
        for k in nc.ncattrs():
            if k in VOLATILE_ATTRS or "run_id" in k:
                continue
            v = nc.getncattr(k)
            num, seq = _number(v), _seq(v)
            if isinstance(v, str):
                params[k] = _param_value(v)
            elif num is not None:
                if is_param_attr(k):
                    params[k] = _param_value(num)
                else:
                    metrics[k] = num
            elif seq is not None:
                for key, x in zip(_seq_keys(k, len(seq)), seq, strict=True):
                    if is_param_attr(k):
                        params[key] = _param_value(float(x))
                    else:
                        metrics[key] = float(x)
        # scalar coordinates (named in a "coordinates" attribute) are not results
        coords = set()
        for var in nc.variables.values():
            if "coordinates" in var.ncattrs():
                coords.update(str(var.getncattr("coordinates")).split())
        for name, var in nc.variables.items():
            if var.ndim != 0 or var.dtype.kind not in "biuf" or name in coords:
                continue
            var.set_auto_maskandscale(False)
            num = _number(var[...])
            if num is not None:
                metrics[str(name)] = num
            for k in var.ncattrs():
                n = _number(var.getncattr(k))
                if n is not None and not k.startswith("_"):
                    metrics[f"{name}.{k}"] = n
    return params, metrics


def json_metrics(path: Path) -> dict[str, float]:
    """Numeric leaves of a JSON file, keys joined with dots."""
    out: dict[str, float] = {}

    def walk(prefix: str, v: Any) -> None:
        if isinstance(v, dict):
            for k, x in v.items():
                walk(f"{prefix}.{k}" if prefix else str(k), x)
        elif (seq := _seq(v)) is not None and not isinstance(v, bool):
            for key, x in zip(_seq_keys(prefix, len(seq)), seq, strict=True):
                out[key] = float(x)
        elif (n := _number(v)) is not None and prefix:
            out[prefix] = n

    try:
        walk("", json.loads(path.read_text(encoding="utf-8")))
    except (ValueError, UnicodeDecodeError):
        return {}
    return out


_NUM = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _slug(text: str, n: int = 60) -> str:
    s = re.sub(r"[^a-z0-9]+", "_", text.lower()).strip("_")
    return s[:n].rstrip("_") or "check"


def checks_metrics(path: Path) -> dict[str, float]:
    """Rows of a Markdown checks table (``| claim | measured | … | result |``) as metrics.

    Each check gives ``check.<claim>.passed`` (1/0) and ``check.<claim>.measured`` (the first
    number of the measured text, if any); the table gives ``checks.passed|failed|total``.
    """
    out: dict[str, float] = {}
    header: list[str] | None = None
    passed = total = 0
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return {}
    for line in lines:
        if not line.strip().startswith("|"):
            header = None if not line.strip() else header
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            header = [c.lower() for c in cells]
            continue
        if set("".join(cells)) <= set("-: "):
            continue
        if "claim" not in header or "result" not in header or len(cells) != len(header):
            continue
        row = dict(zip(header, cells, strict=True))
        ok = "pass" in row["result"].lower() and "fail" not in row["result"].lower()
        slug = _slug(row["claim"])
        key, i = slug, 2
        while f"check.{key}.passed" in out:
            key, i = f"{slug}_{i}", i + 1
        out[f"check.{key}.passed"] = float(ok)
        m = _NUM.search(row.get("measured", "").split(":", 1)[-1])
        if m:
            with contextlib.suppress(ValueError):
                out[f"check.{key}.measured"] = float(m.group())
        passed += ok
        total += 1
    if total:
        out.update(
            {"checks.passed": passed, "checks.failed": total - passed, "checks.total": total}
        )
    return out


def benchmark_metrics(path: Path) -> dict[str, float]:
    """Numeric columns of the last row of a Snakemake benchmark file (``s``, ``max_rss`` MB …)."""
    try:
        lines = [ln for ln in path.read_text(encoding="utf-8").splitlines() if ln.strip()]
    except (OSError, UnicodeDecodeError):
        return {}
    if len(lines) < 2:
        return {}
    head, last = lines[0].split("\t"), lines[-1].split("\t")
    out = {}
    for k, v in zip(head, last, strict=False):
        with contextlib.suppress(ValueError):
            f = float(v)
            if math.isfinite(f) and k != "h:m:s":
                out[f"benchmark.{k}"] = f
    return out


def describe_output(path: str | Path) -> tuple[dict[str, str], dict[str, float]]:
    """Params and metrics of any output file, by its kind (empty for figures and tables)."""
    p = Path(path)
    if not p.is_file():
        return {}, {}
    try:
        if p.suffix == ".nc":
            return netcdf_fields(p)
        if p.suffix == ".json":
            return {}, json_metrics(p)
        if p.suffix == ".md":
            return {}, checks_metrics(p)
    except Exception as ex:  # noqa: BLE001 - a damaged output must not lose the whole record
        return {"tracking_warning": f"{p.name}: {one_line(ex)}"}, {}
    return {}, {}


class _HashCache:
    """sha256 of files, reused while (size, mtime) are unchanged
    (``<results>/.tracking-hashes.json``)."""

    def __init__(self, path: Path | None):
        self.path = path
        self.data: dict[str, list] = {}
        if path is not None and path.is_file():
            with contextlib.suppress(ValueError, OSError):
                self.data = json.loads(path.read_text())

    def get(self, f: Path) -> str:
        st = f.stat()
        key = str(f.resolve())
        hit = self.data.get(key)
        if hit and hit[0] == st.st_size and hit[1] == st.st_mtime_ns:
            return hit[2]
        digest = sha256_file(f)
        self.data[key] = [st.st_size, st.st_mtime_ns, digest]
        return digest

    def save(self) -> None:
        if self.path is None:
            return
        with contextlib.suppress(OSError):
            tmp = self.path.with_name(self.path.name + ".tmp")
            tmp.write_text(json.dumps(self.data))
            os.replace(tmp, self.path)


def _leaves(obj: Any, prefix: str = "") -> Iterator[tuple[str, Any]]:
    """The non-mapping values of a nested mapping, each under its dotted key."""
    if isinstance(obj, Mapping):
        for k, v in obj.items():
            yield from _leaves(v, f"{prefix}.{k}" if prefix else str(k))
    else:
        yield prefix, obj


def numeric_leaves(obj: Any, prefix: str = "") -> dict[str, float]:
    """Flatten a JSON-like result (e.g. ``bouncedisk stats --json``) into metrics."""
    out: dict[str, float] = {}
    for key, leaf in _leaves(obj, prefix):
        if not key:
            continue
        if (seq := _seq(leaf)) is not None:
            out.update(dict(zip(_seq_keys(key, len(seq)), map(float, seq), strict=True)))
        elif (n := _number(leaf)) is not None:
            out[key] = n
    return out


def flatten(obj: Any, prefix: str = "") -> dict[str, str]:
    """A nested mapping as dotted ``key: text`` params."""
    return {key: _param_value(leaf) for key, leaf in _leaves(obj, prefix)}


def config_sha256(config: Mapping) -> str:
    """Hash of a pipeline config, leaving out where results and runs are kept."""
    relevant = {k: v for k, v in config.items() if k not in ("results", "tracking")}
    return hashlib.sha256(json.dumps(relevant, sort_keys=True, default=str).encode()).hexdigest()


def _netcdf_run_id(path: Path) -> str:
    try:
        import netCDF4

        with netCDF4.Dataset(path, "r") as nc:
            return str(getattr(nc, "run_id", ""))
    except Exception:  # noqa: BLE001
        return ""


def _keys(d: Mapping[str, Any]) -> dict[str, Any]:
    return {_clean_key(k): v for k, v in d.items() if k}
