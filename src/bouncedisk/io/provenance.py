"""Provenance of results: run ids, code version and git commit, scene hashes, file hashes."""

from __future__ import annotations

import datetime as _dt
import functools
import hashlib
import os
import platform
import subprocess
import uuid
from pathlib import Path

from .. import __version__

REFERENCES = (
    "Nonlinear dynamics of a bouncing disk on the tip of a vibrating pretwisted beam (the model's "
    "source; its corrected statement: docs/model.md in the bouncedisk repository); "
    "Nordmark & Piiroinen, Nonlinear Dyn. 58 (2009) for chattering; "
    "Luck & Mehta, Phys. Rev. E 48, 3988 (1993) for the bouncing ball."
)


#: The package's own source tree (``src/bouncedisk`` in a checkout).
PACKAGE_DIR = Path(__file__).resolve().parents[1]


def _git(*args: str, cwd: Path) -> str | None:
    """The output of ``git ARGS`` run in ``cwd``, or None where git fails or is missing."""
    try:
        r = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return r.stdout.strip() if r.returncode == 0 else None


def git_state(cwd: Path | None = None, under: str | None = None) -> dict[str, str]:
    """``git_commit`` of the working tree at ``cwd`` (default: the package's source tree) and
    ``git_dirty``, whether tracked files (those under ``under``, if given) differ from it;
    both ``unknown`` outside a checkout."""
    cwd = cwd or PACKAGE_DIR
    commit = _git("rev-parse", "HEAD", cwd=cwd)
    if commit is None:
        return {"git_commit": "unknown", "git_dirty": "unknown"}
    scope = ("--", under) if under else ()
    dirty = _git("status", "--porcelain", "--untracked-files=no", *scope, cwd=cwd)
    return {"git_commit": commit, "git_dirty": "true" if dirty else "false"}


@functools.lru_cache(maxsize=1)
def git_commit() -> str:
    """Commit of the source tree this package runs from, ``-dirty`` when its files differ from
    it (``unknown`` outside a checkout)."""
    state = git_state(PACKAGE_DIR, under=".")
    return state["git_commit"] + ("-dirty" if state["git_dirty"] == "true" else "")


def new_run_id(scene_name: str, scene_sha256: str) -> str:
    """A unique run id ``<scene>-<scene hash 8>-<random 8>``."""
    return f"{scene_name}-{scene_sha256[:8]}-{uuid.uuid4().hex[:8]}"


def utc_now() -> str:
    """ISO-8601 UTC timestamp."""
    return _dt.datetime.now(_dt.UTC).replace(microsecond=0).isoformat().replace("+00:00", "Z")


def sha256_file(path: str | Path, block: int = 1 << 20) -> str:
    """SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while chunk := fh.read(block):
            h.update(chunk)
    return h.hexdigest()


#: Global attributes of a simulation file (docs/formats.md "netCDF files"), the one list: the run's
#: scene and solver, the run itself, and the CF/ACDD attributes every file carries.
SCENE_ATTRS = (
    "e",
    "omega_s",
    "r_phi",
    "psi",
    "effects",
    "solver",
    "tol",
    "scene_name",
    "scene_sha256",
)
RUN_ATTRS = (
    "run_id",
    "bouncedisk_version",
    "git_commit",
    "created",
    "wall_time_s",
    "n_impacts",
    "status",
)
CF_ATTRS = ("Conventions", "title", "history", "source", "references")
#: Every attribute docs/formats.md requires of a simulation file.
REQUIRED_ATTRS = SCENE_ATTRS + RUN_ATTRS + CF_ATTRS
#: MLflow tags of the code version a tracked run ran (:mod:`bouncedisk.tracking` writes them).
TAG_VERSION = "bouncedisk.version"
TAG_GIT_COMMIT = "bouncedisk.git_commit"
TAG_GIT_DIRTY = "bouncedisk.git_dirty"


#: ACDD ``naming_authority`` of the ``id`` attribute (the run id).
NAMING_AUTHORITY = "bouncedisk"

KEYWORDS = (
    "bouncing disk, ultrasonic motor, piezoelectric motor, impact oscillator, bouncing ball, "
    "restitution, friction, stick-slip, chattering, Zeno, nonsmooth dynamics, event-driven "
    "simulation"
)


#: Who made the files (ACDD-1.3 creator/institution/publisher attributes): the pipeline config's
#: ``metadata`` section (the Snakefile exports it as these variables to every job), or these
#: environment variables for the commands; the defaults say that nobody set them.
METADATA_ENV = {
    "creator_name": "BOUNCEDISK_CREATOR_NAME",
    "creator_email": "BOUNCEDISK_CREATOR_EMAIL",
    "creator_url": "BOUNCEDISK_CREATOR_URL",
    "creator_type": "BOUNCEDISK_CREATOR_TYPE",
    "institution": "BOUNCEDISK_INSTITUTION",
    "project": "BOUNCEDISK_PROJECT",
    "license": "BOUNCEDISK_LICENSE",
    "acknowledgement": "BOUNCEDISK_ACKNOWLEDGEMENT",
}
METADATA_DEFAULTS = {
    "creator_name": "unknown (set metadata.creator_name in the pipeline config or "
    "BOUNCEDISK_CREATOR_NAME)",
    "creator_email": "unknown (metadata.creator_email, BOUNCEDISK_CREATOR_EMAIL)",
    "creator_url": "unknown (metadata.creator_url, BOUNCEDISK_CREATOR_URL)",
    "creator_type": "person",
    "institution": "unknown (set metadata.institution in the pipeline config or "
    "BOUNCEDISK_INSTITUTION)",
    "project": "bouncedisk: the bouncing-disk model of a piezoelectric ultrasonic motor",
    "license": "MIT (the bouncedisk package's licence; metadata.license to change)",
    "acknowledgement": "none given (metadata.acknowledgement, BOUNCEDISK_ACKNOWLEDGEMENT)",
}
#: The controlled vocabulary of ``standard_name``: no variable has one (the table names no
#: quantity of a bouncing rotor, and a nondimensional or undated time is not CF's ``time``); no
#: version number, so that checkers use their own copy and never download one.
STANDARD_NAME_VOCABULARY = (
    "CF Standard Name Table (none used: no standard name fits these quantities)"
)
#: The dates of a file (``created`` of docs/formats.md and ACDD-1.3's), all the time of writing.
DATE_ATTRS = ("created", "date_created", "date_modified", "date_issued", "date_metadata_modified")


def metadata() -> dict[str, str]:
    """The ACDD creator/institution attributes: environment (pipeline config), else defaults."""
    out = {}
    for key, env in METADATA_ENV.items():
        value = os.environ.get(env, "").strip()
        out[key] = value or METADATA_DEFAULTS[key]
    out["creator_institution"] = out["institution"]
    out["publisher_name"] = out["creator_name"]
    out["publisher_email"] = out["creator_email"]
    out["publisher_url"] = out["creator_url"]
    out["publisher_type"] = out["creator_type"]
    out["publisher_institution"] = out["institution"]
    return out


#: ACDD ``processing_level`` and CF/ACDD ``comment`` of model output (the default) and of a
#: file that holds measured data with the model fitted to it (a fit).
PROCESSING = {
    "model": (
        "model output (simulated), not measured data",
        "Quantities are nondimensional (units '1') unless their units say otherwise; "
        "time is in units of t_c = sqrt(U0/g) (docs/model.md, 'Variables and scales').",
    ),
    "fit": (
        "measured run-ups (omega_measured: their mean) and the model fitted to them (simulated)",
        "Variables named *measured* are the measured data (coverage_content_type "
        "physicalMeasurement), the others model results; time is in seconds from the start "
        "of the measured run-up, the fitted parameters nondimensional (docs/model.md).",
    ),
}


def base_attrs(title: str, summary: str | None = None, kind: str = "model") -> dict[str, str]:
    """CF/ACDD global attributes shared by every file the package writes; ``kind`` (a key of
    :data:`PROCESSING`) sets ``processing_level`` and ``comment``.

    ACDD-1.3's highly recommended and recommended attributes that mean something here: the
    creator, institution and publisher from :func:`metadata`, dates, ``naming_authority`` and
    ``processing_level``; ``id``, ``history`` (and the dates, for a file joined from parts
    written at different times) are added when the file is written
    (:func:`bouncedisk.io.netcdf.finalize`), and the time coverage's duration and resolution
    when its time is in seconds. Geospatial coverage, and the start and end of the time
    coverage (dates), have no meaning for a laboratory rotor in nondimensional or undated time.
    """
    now = utc_now()
    return {
        "Conventions": "CF-1.10, ACDD-1.3",
        "title": title,
        "summary": summary
        or (
            f"{title}: output of bouncedisk, an exact event-driven simulator of a rotor bouncing "
            "on an ultrasonically vibrating, twisting stator (the bouncing-disk model of a "
            "piezoelectric ultrasonic motor)."
        ),
        "keywords": KEYWORDS,
        "source": f"bouncedisk {__version__} (python {platform.python_version()})",
        "references": REFERENCES,
        "bouncedisk_version": __version__,
        "git_commit": git_commit(),
        **dict.fromkeys(DATE_ATTRS, now),
        "comment": PROCESSING[kind][1],
        "naming_authority": NAMING_AUTHORITY,
        "processing_level": PROCESSING[kind][0],
        "product_version": __version__,
        "standard_name_vocabulary": STANDARD_NAME_VOCABULARY,
        **metadata(),
    }
