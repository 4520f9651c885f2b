"""No function of the package is longer than about a screen: ``MAX_LINES`` lines, decorators
and docstring included (the project's standard; a long function is split where it does two
things)."""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "bouncedisk"
MAX_LINES = 100
#: Functions allowed to be longer, with the reason (``"module.py:function"``: reason); none now.
EXCEPTIONS: dict[str, str] = {}


def _lengths(tree: ast.Module) -> list[tuple[str, int]]:
    """``(name, lines)`` of every function and method in a module, nested ones included."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            first = min([node.lineno] + [d.lineno for d in node.decorator_list])
            out.append((node.name, node.end_lineno - first + 1))
    return out


def test_no_function_in_src_is_over_the_limit():
    long = []
    for path in sorted(SRC.rglob("*.py")):
        for name, n in _lengths(ast.parse(path.read_text(encoding="utf-8"))):
            key = f"{path.relative_to(SRC).as_posix()}:{name}"
            if n > MAX_LINES and key not in EXCEPTIONS:
                long.append(f"{key} ({n} lines)")
    assert not long, "functions over the limit: " + ", ".join(long)


def test_the_check_finds_a_long_function():
    body = "\n".join(f"    x{i} = {i}" for i in range(MAX_LINES))
    tree = ast.parse(f"@decorated\ndef long():\n{body}\n\ndef short():\n    return 1\n")
    assert _lengths(tree) == [("long", MAX_LINES + 2), ("short", 2)]
    assert all(k.split(":")[0].endswith(".py") for k in EXCEPTIONS)
