"""Code and guide pages say what is, not what was.

Dates, run logs, "before/after" narratives and the names of benchmark cases belong in the
records (``benchmarks/out/``) and the changelog (``docs/changelog.md``); the performance page's
tables are generated from the records at build time. This test reads the source, the
benchmarks, the workflow and the documentation pages and fails on a line that carries history.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Where history must not appear: the package, the benchmarks' code, the workflow, the pages.
PLACES = ("src", "benchmarks", "workflow", "docs", "README.md")
SUFFIXES = {".py", ".smk", ".yaml", ".yml", ".md", ".rst"}
#: Where it belongs: the changelog, the records, the generated and built pages.
EXCEPT = ("docs/changelog.md", "benchmarks/out", "docs/_build", "docs/api", "docs/auto_examples")

#: What history looks like, each with the reason it is history.
PATTERNS = {
    "a date": re.compile(r"\b20\d\d-[01]\d-[0-3]\d\b"),
    "a benchmark case's name": re.compile(r"(?<![-\w])(?:random )?motors? \d+\b", re.IGNORECASE),
    "a 'was ... now' narrative": re.compile(r"\bwas\b(?:[^.\n]|\.\d){0,60}\bnow\b", re.IGNORECASE),
    "a narrative of an earlier version": re.compile(
        r"\b(?:used to be|previously|formerly|the version before|before the change|"
        r"last session|this session|not re-measured|not explained)\b",
        re.IGNORECASE,
    ),
    "a 'Before, ...' anecdote": re.compile(r"\bBefore, (?:it|the|this|a)\b"),
}


def _files() -> list[Path]:
    out = []
    for place in PLACES:
        path = ROOT / place
        candidates = [path] if path.is_file() else sorted(path.rglob("*"))
        for f in candidates:
            rel = f.relative_to(ROOT).as_posix()
            if f.is_file() and f.suffix in SUFFIXES and not rel.startswith(EXCEPT):
                out.append(f)
    return out


def history_lines(text: str) -> list[tuple[int, str, str]]:
    """``(line number, reason, line)`` of each line of ``text`` that carries history."""
    found = []
    for n, line in enumerate(text.splitlines(), start=1):
        for reason, pattern in PATTERNS.items():
            if pattern.search(line):
                found.append((n, reason, line.strip()))
                break
    return found


def test_no_history_in_code_or_pages():
    found = [
        f"{f.relative_to(ROOT)}:{n}: {reason}: {line[:90]}"
        for f in _files()
        for n, reason, line in history_lines(f.read_text(encoding="utf-8", errors="replace"))
    ]
    assert not found, "history outside the changelog and the records:\n" + "\n".join(found)


@pytest.mark.parametrize(
    "line",
    [
        "# made it 1.7x as slow (4.1 against 2.4 ms, 2026-11-25)",
        "On motor 7 the walk lowers chi2 from 5.5 to 1.98.",
        "The default was 0.03; it is now fitted.",
        "This used to be computed twice.",
        "Before, it killed the process with status 130.",
    ],
)
def test_planted_history_is_found(line):
    assert history_lines(line), line


@pytest.mark.parametrize(
    "line",
    [
        "The velocity before the impact and after it (eq. 4).",
        "A temporary file that no longer exists is skipped.",
        "The motor's stall torque is 1.0 in units of T0.",
        "Run: python benchmarks/random_motors.py --motors 16 --first 0",
    ],
)
def test_physics_is_not_history(line):
    assert not history_lines(line), line
