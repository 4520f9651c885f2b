"""Write a benchmark's measurements as a record of the performance page.

``docs/perfpage.py`` renders every ``benchmarks/out/*.json`` record (``title``, ``command``,
``date``, ``machine``, ``rows`` of ``measurement`` and ``result``) into
``docs/user_guide/performance.md`` at each docs build: a benchmark run with ``--record`` replaces
its own record with what it just measured, stamped with the date and this machine.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import platform
import shlex
import sys
from pathlib import Path

OUT = Path(__file__).resolve().parent / "out"
ROOT = OUT.parents[1]


def _script() -> str:
    """The running script, relative to the project root when it lies inside it."""
    path = Path(sys.argv[0]).resolve()
    return (path.relative_to(ROOT) if path.is_relative_to(ROOT) else path).as_posix()


def machine() -> str:
    """This machine as the records name it: architecture, cores, Python."""
    return f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"


def write_record(name: str, title: str, rows: list[tuple[str, str]]) -> Path:
    """Write ``benchmarks/out/<name>.json`` from ``rows`` of ``(measurement, result)``; the
    command is this process's command line, the date today's (UTC)."""
    record = {
        "title": title,
        "command": "python " + shlex.join([_script(), *sys.argv[1:]]),
        "date": dt.datetime.now(dt.UTC).date().isoformat(),
        "machine": machine(),
        "rows": [{"measurement": m, "result": r} for m, r in rows],
    }
    path = OUT / f"{name}.json"
    path.write_text(json.dumps(record, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return path
