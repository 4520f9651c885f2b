"""The guide pages' Markdown sources (no build needed): their code blocks fit the page, no line
longer than :data:`WIDTH` characters, and each task page is short and quotes no date.

The Sphinx theme's text column holds about 90 characters of code at 1280 px; a longer line is
cut and scrolls sideways, so a reader copying the command misses its end.
"""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
WIDTH = 90
#: The pages checked (the README is GitHub's front page).
PAGES = (
    "README.md",
    "docs/index.md",
    "docs/user_guide/scenes.md",
    "docs/user_guide/ensembles.md",
    "docs/user_guide/pipeline.md",
    "docs/user_guide/cluster.md",
    "docs/user_guide/performance.md",
)


def long_code_lines(text: str, width: int = WIDTH) -> list[tuple[int, int]]:
    """``(line number, length)`` of each line longer than ``width`` inside a fenced code block
    (MyST directives such as ```` ```{image} ```` are not code)."""
    found, fence, code = [], None, False
    for n, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if fence is None:
            if stripped.startswith("```"):
                fence = stripped[: len(stripped) - len(stripped.lstrip("`"))]
                code = not stripped.startswith(fence + "{")
            continue
        if stripped == fence:
            fence = None
        elif code and len(line) > width:
            found.append((n, len(line)))
    return found


@pytest.mark.parametrize("page", PAGES)
def test_code_blocks_fit_the_page(page):
    long = long_code_lines((ROOT / page).read_text(encoding="utf-8"))
    assert not long, f"{page}: code lines over {WIDTH} characters (line, length): {long}"


def test_the_check_finds_a_long_line_in_code_only():
    text = "x" * 120 + "\n```bash\nshort\n" + "y" * 91 + "\n```\n```{image} a.png\n"
    text += ":alt: " + "z" * 100 + "\n```\n" + "x" * 120 + "\n"
    assert long_code_lines(text) == [(4, 91)]


#: The user-guide pages that teach one task each (their figures and numbers are elsewhere).
TASK_PAGES = ["getting_started.md"] + [
    f"user_guide/{p}.md"
    for p in (
        "scenes",
        "ensembles",
        "fitting",
        "load",
        "sensitivity",
        "basins",
        "pipeline",
        "reproducible",
        "tracking",
        "cluster",
        "performance",
    )
]


@pytest.mark.parametrize("page", TASK_PAGES)
def test_task_pages_are_short_and_quote_no_dated_measurement(page):
    """A task page stays under about 1,200 words (1,500 at most) and quotes no date: dated
    measurements live in benchmarks/out/ and the performance page renders them."""
    import re

    text = (ROOT / "docs" / page).read_text()
    assert len(text.split()) <= 1500, len(text.split())
    assert not re.search(r"\b20\d\d-\d\d-\d\d\b", text), re.search(r"\b20\d\d-\d\d-\d\d\b", text)
