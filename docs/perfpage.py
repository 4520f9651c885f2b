"""The measured numbers of docs/user_guide/performance.md, rendered from the benchmarks' own
outputs at every docs build (``docs/conf.py`` calls :func:`write_tables`).

Each ``benchmarks/out/*.json`` that holds ``title``, ``command``, ``date``, ``machine`` and
``rows`` (``measurement``, ``result``) becomes one table headed by the command, date and machine
that produced it; a summary JSON without them (``work_precision_summary.json``) is listed as its
keys and values. The prose of the user guide carries no measurement of its own.
"""

from __future__ import annotations

import json
from pathlib import Path

#: The order of the tables; any other record follows, by file name.
ORDER = ("pipeline.json", "engine.json", "ensemble.json", "cluster.json", "reproducible.json")


def _cell(text: object) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def render_record(record: dict) -> str:
    """One record as a MyST section: heading, provenance line, two-column table."""
    lines = [f"### {record['title']}", ""]
    lines += [
        f"Measured on {record['date']}, {record['machine']}, by `{record['command']}`.",
        "",
        "| measurement | result |",
        "| --- | --- |",
    ]
    lines += [f"| {_cell(r['measurement'])} | {_cell(r['result'])} |" for r in record["rows"]]
    return "\n".join(lines) + "\n"


def render_summary(name: str, data: dict) -> str:
    """A JSON summary without provenance (a benchmark's own output) as a key/value table."""
    lines = [f"### `benchmarks/out/{name}`", "", "| key | value |", "| --- | --- |"]
    lines += [f"| `{_cell(k)}` | {_cell(v) or '(none)'} |" for k, v in data.items()]
    return "\n".join(lines) + "\n"


def render(out_dir: Path) -> str:
    """Every JSON file of ``out_dir`` rendered, records first in :data:`ORDER`."""
    files = sorted(
        out_dir.glob("*.json"),
        key=lambda p: (p.name not in ORDER, ORDER.index(p.name) if p.name in ORDER else 0, p.name),
    )
    parts = []
    for path in files:
        data = json.loads(path.read_text())
        if {"title", "command", "date", "machine", "rows"} <= data.keys():
            parts.append(render_record(data))
        else:
            parts.append(render_summary(path.name, data))
    return "\n".join(parts)


def write_tables(out_dir: Path, target: Path) -> Path:
    """Write the rendered tables to ``target`` (only when they changed: no needless rebuild)."""
    text = render(out_dir)
    if not target.is_file() or target.read_text() != text:
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text)
    return target
