"""Only the command line prints: the library raises or returns its text.

``bouncedisk.cli`` is the one layer that writes to the terminal (its docstring: "the only place
that parses argv and prints"); the Snakefile's handlers print the line
:func:`bouncedisk.tracking.store.error_report` returns, and a pipeline job's boundary,
:func:`bouncedisk.io.job_log.log_to`, prints the one line of a user's error as the command line
does (:data:`BOUNDARIES`).
"""

from __future__ import annotations

import ast
from pathlib import Path

from bouncedisk.model.errors import InputError
from bouncedisk.tracking.store import TrackingError, error_report

SRC = Path(__file__).resolve().parents[1] / "src" / "bouncedisk"


def print_calls(source: str) -> list[int]:
    """Line numbers of the calls of the builtin ``print`` in ``source``."""
    return [
        node.lineno
        for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.Call)
        and isinstance(node.func, ast.Name)
        and node.func.id == "print"
    ]


#: Modules outside ``cli`` that end a process and say why: a pipeline job's log block.
BOUNDARIES = {"io/job_log.py"}


def test_no_print_outside_cli():
    found = [
        f"{path.relative_to(SRC).as_posix()}:{line}"
        for path in sorted(SRC.rglob("*.py"))
        if "cli" not in path.relative_to(SRC).parts
        and path.relative_to(SRC).as_posix() not in BOUNDARIES
        for line in print_calls(path.read_text(encoding="utf-8"))
    ]
    assert len(print_calls((SRC / "io" / "job_log.py").read_text(encoding="utf-8"))) == 1
    assert not found, "print outside bouncedisk.cli: " + ", ".join(found)


def test_the_check_finds_a_planted_print():
    assert print_calls("import sys\n\ndef f(x):\n    print(x, file=sys.stderr)\n") == [4]
    assert print_calls("def f(x):\n    return x.print()\n") == []


def test_error_report_is_one_line_naming_the_store():
    ex = TrackingError("sqlite:///x.db", "not writable: Permission denied")
    assert error_report(ex) == (
        "bouncedisk: error: tracking store sqlite:///x.db: not writable: Permission denied"
    )
    assert (
        error_report(InputError("a.yaml", "stop", "bad")) == "bouncedisk: error: a.yaml: stop: bad"
    )
    # any other error: its first line, without the driver's autoflush preamble
    raw = RuntimeError("(raised as a result of Query-invoked autoflush; x)  disk I/O error\nmore")
    assert error_report(raw) == "bouncedisk: error: disk I/O error"
