"""The repository stands on its own: every file it points at is in it, every cited section of
``docs/model.md`` and ``docs/formats.md`` exists, and nothing points at an issue tracker or at
files outside the repository.

A citation names a section by its heading (``## Events``) or by the bold label that opens a
paragraph or list item (``**Chattering**``); a citation may shorten the name to its start
(``"Long-run statistics"``). ``docs/changelog.md`` is history and is not checked.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: Text files checked: everything git tracks with these endings, and the CI scripts.
SUFFIXES = {".py", ".md", ".yaml", ".yml", ".smk", ".toml", ".rst", ".txt", ".cfg", ".json", ""}
SKIP = {"docs/changelog.md", "tests/test_self_contained.py"}  # history; the planted errors
#: What the pipeline, the commands and the documentation build write (not in the repository).
GENERATED = (
    "results/",
    "docs/_build",
    "../_build/generated",
    "docs/api",
    "docs/auto_examples",
    "docs/sg_execution_times",
)
#: Pages whose sections are cited, as they are written in code and in the MyST pages.
PAGES = {"docs/model.md": "docs/model.md", "docs/formats.md": "docs/formats.md",
         "{doc}`/model`": "docs/model.md", "{doc}`/formats`": "docs/formats.md"}  # fmt: skip

_PAGE = "|".join(re.escape(p) for p in PAGES)
_CITATION = re.compile(rf'({_PAGE}),? ((?:"[^"\n]+"(?:,? (?:and )?)?)+)')
_QUOTED = re.compile(r'"([^"\n]+)"')
_CONTINUED = re.compile(r"^\s*(?:#:?|//)?\s*")
_MD_PATH = re.compile(r"(?<![\w/.{-])((?:\.\./|\./)?[\w.-]+(?:/[\w.-]+)*\.md)\b")
_REPO_PATH = re.compile(
    r"(?<![\w/.-])((?:src|tests|workflow|benchmarks|docs|data|tools|\.ci)/[\w./-]*[\w-])"
)
_OUTSIDE = re.compile(r"(?<![\w-])(?:\.\./shared|shared/|seed/)")
_ISSUE = re.compile(r"\b(?:[Ii]ssues?|[Ii]tems?) #?\d+\b")
_HEADING = re.compile(r"^#{1,6}\s+(.+?)\s*$", re.M)
_LABEL = re.compile(r"^\s*(?:[-*]\s+)?\*\*(.+?)\*\*", re.M)


def _normal(name: str) -> str:
    """A section name as cited: no backticks, emphasis or math delimiters (``$w \\le 1$`` is
    cited as "w ≤ 1"), no trailing punctuation."""
    name = name.replace("\\le ", "≤ ").replace("\\ge ", "≥ ")
    return re.sub(r"[`*$]", "", name).strip().rstrip(".:").strip()


def sections(text: str) -> list[str]:
    """The names a page's sections can be cited by: headings and bold paragraph labels."""
    return [_normal(m) for m in _HEADING.findall(text) + _LABEL.findall(text)]


def _cited_ok(name: str, names: list[str]) -> bool:
    n = _normal(name)
    return any(s == n or s.startswith(n + " ") or s.startswith(n + ",") for s in names)


def _exists(ref: str, here: Path, root: Path) -> bool:
    """A path as written exists beside the file, from the root, or under ``docs/``; or it is
    written by the project (:data:`GENERATED`), or it is a lower-case bare file name (a name
    the code gives a file it writes, such as ``reproduction.md``; pages are ``README.md``)."""
    ref = ref.rstrip(".")
    if ref.startswith(GENERATED) or ("/" not in ref and ref[:1].islower()):
        return True
    return any((base / ref).exists() for base in (here.parent, root, root / "docs"))


def problems(root: Path, files: list[str]) -> list[str]:
    """Every reference in ``files`` (paths relative to ``root``) that does not resolve."""
    pages = {p: sections((root / p).read_text(encoding="utf-8")) for p in set(PAGES.values())
             if (root / p).exists()}  # fmt: skip
    out = []
    for rel in files:
        path = root / rel
        lines = path.read_text(encoding="utf-8").splitlines()
        for lineno, line in enumerate(lines, 1):
            where = f"{rel}:{lineno}"
            # a citation may go on over the next line (docstrings, comments, paragraphs)
            nxt = _CONTINUED.sub("", lines[lineno]) if lineno < len(lines) else ""
            for m in _CITATION.finditer(f"{line} {nxt}"):
                if m.start() >= len(line):
                    continue  # the next line's own citation
                names = pages.get(PAGES[m.group(1)], [])
                for cited in _QUOTED.findall(m.group(2)):
                    if not _cited_ok(cited, names):
                        out.append(f'{where}: {PAGES[m.group(1)]} has no section "{cited}"')
            for ref in _MD_PATH.findall(line) + _REPO_PATH.findall(line):
                if not any(c in ref for c in "{}*<>$") and not _exists(ref, path, root):
                    out.append(f"{where}: {ref} is not in the repository")
            if _OUTSIDE.search(line):
                out.append(f"{where}: points outside the repository: {line.strip()[:80]}")
            if m := _ISSUE.search(line):
                out.append(f"{where}: names an issue or its item: {m.group(0)!r}")
    return out


def _tracked() -> list[str]:
    listed = subprocess.run(
        ["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    return [
        f for f in listed
        if Path(f).suffix in SUFFIXES and f not in SKIP and (ROOT / f).is_file()
        and not f.startswith("tests/data/")
    ]  # fmt: skip


def test_every_reference_resolves_inside_the_repository():
    try:
        files = _tracked()
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")
    found = problems(ROOT, files)
    assert not found, f"{len(found)} references do not resolve:\n" + "\n".join(found)


def test_the_check_catches_every_kind_of_bad_reference(tmp_path):
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "model.md").write_text(
        "# Model\n\n## Events\n\n**Chattering** (complete).\n\n- **`w ≤ 1`.** Rests.\n"
    )
    good = (
        'see docs/model.md "Events", "Chattering" and {doc}`/model`, "w ≤ 1"; '
        "docs/model.md and ./docs/model.md exist\n"
    )
    bad_wrapped = '(docs/model.md "Chattering", "no such\n    section")\n'

    bad = [
        'docs/model.md "Flight"',  # no such section
        "MODEL.md",  # a page that is not in the repository
        "tests/nowhere.py",  # nor is this file
        "the paper (../shared/seed/paper.md)",  # outside the repository
        "as issue 20 asked",  # an issue number
        "item 14 of the review",  # an issue's item
    ]
    (tmp_path / "a.py").write_text(good + "\n".join(bad) + "\n" + bad_wrapped)
    found = problems(tmp_path, ["a.py"])
    lines = sorted({int(p.split(":")[1]) for p in found})
    assert lines == list(range(2, 3 + len(bad))), found


def test_the_scenes_are_one_copy_that_the_package_ships():
    """``workflow/config/scenes`` is a relative link to the package's ``scenes`` folder, every
    scene there is package data (pyproject.toml), and the checks find theirs in it
    (importlib.resources), so an installed package runs ``bouncedisk check`` (.ci/wheel)."""
    import fnmatch
    import os
    import tomllib

    from bouncedisk.studies import reproduction_files as files

    link, shipped = ROOT / "workflow" / "config" / "scenes", ROOT / "src" / "bouncedisk" / "scenes"
    assert link.is_symlink() and not os.path.isabs(os.readlink(link))
    assert link.resolve() == shipped.resolve()
    data = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    patterns = data["tool"]["setuptools"]["package-data"]["bouncedisk"]
    scenes = sorted(p.name for p in shipped.glob("*.yaml"))
    assert scenes and all(any(fnmatch.fnmatch(f"scenes/{s}", p) for p in patterns) for s in scenes)
    for name in ("fig5", "basins_fig3", *files.STATS_SCENES, *files.LOAD_CURVES):
        assert files.scene_file(name).is_file(), name
