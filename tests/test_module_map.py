"""The module map of ``docs/internals.md`` against the package: every module named, none invented.

The map is the newcomer's index of the code, so it must name every module of
``src/bouncedisk`` as ``folder/module`` and name no module that does not exist.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "bouncedisk"
INTERNALS = ROOT / "docs" / "internals.md"

#: ``folder/module`` as the map writes it: ``engine/roots``, ``cli/__main__``
NAME = re.compile(r"\b([a-z]+)/(_{0,2}[a-z][a-z0-9_]*)\b")


def package_modules() -> set[str]:
    """Every module of the package below a folder, as ``folder/module`` (``__init__`` left out)."""
    return {
        f"{path.parent.name}/{path.stem}"
        for path in PACKAGE.glob("*/*.py")
        if path.stem != "__init__"
    }


def map_section() -> str:
    """The text of the "Module map" section of the internals page."""
    text = INTERNALS.read_text(encoding="utf-8")
    start = text.index("### Module map")
    end = text.find("\n#", start + 1)
    return text[start : end if end > 0 else len(text)]


def named_modules() -> set[str]:
    """The ``folder/module`` names the map's table mentions, in the package's folders only."""
    folders = {path.name for path in PACKAGE.iterdir() if path.is_dir()}
    table = "\n".join(line for line in map_section().splitlines() if line.startswith("|"))
    return {f"{a}/{b}" for a, b in NAME.findall(table) if a in folders}


def test_every_module_is_on_the_map():
    missing = sorted(package_modules() - named_modules())
    assert not missing, f"modules missing from docs/internals.md's module map: {missing}"


def test_the_map_names_no_module_that_does_not_exist():
    invented = sorted(named_modules() - package_modules())
    assert not invented, (
        f"docs/internals.md's module map names modules that do not exist: {invented}"
    )


def test_the_check_sees_a_planted_omission(monkeypatch):
    """A map with one row dropped fails the first test (the check can fail)."""
    dropped = "engine/roots"
    real = map_section()
    monkeypatch.setattr(
        sys.modules[__name__], "map_section", lambda: real.replace(dropped, "engine/xroots")
    )
    assert dropped not in named_modules()
