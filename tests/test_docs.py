"""The built documentation renders: headless Chromium screenshots of the landing page, a gallery
page and an API page (file:// URLs, no network), the gallery's images on disk, an API page for
every public function and class, no page loading a script or style sheet from another host, and
the model page's equations typeset by the MathJax shipped in the site (Chromium, no network).

The site is built by ``.ci/docs`` (CI runs it before the tests) or by
``sphinx-build -W --keep-going -b html docs docs/_build/html``; without it these tests are skipped.
"""

import html
import html.parser
import importlib.util
import re
import sys
from pathlib import Path

import browser
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
SITE = ROOT / "docs" / "_build" / "html"
PAGES = {
    "landing": "index.html",
    "model": "model.html",
    "gallery": "auto_examples/plot_simulate_scene.html",
    "api": "api/generated/bouncedisk.studies.torque_speed.torque_speed.html",
}

pytestmark = [
    pytest.mark.skipif(
        not (SITE / "index.html").is_file(),
        reason="the documentation is not built (run .ci/docs, or sphinx-build -b html docs "
        "docs/_build/html)",
    ),
    pytest.mark.xdist_group("docs"),
]


def screenshot(page: str, out: Path, size: str = "1280,1000") -> np.ndarray:
    """Headless Chromium's screenshot of a built page (after its scripts ran), as an RGB array."""
    return browser.screenshot((SITE / page).as_uri(), out, size)


class _Images(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.src: list[str] = []

    def handle_starttag(self, tag, attrs):
        if tag == "img":
            self.src += [v for k, v in attrs if k == "src" and v]


@pytest.mark.parametrize("kind", list(PAGES))
def test_page_renders_in_chromium(kind, tmp_path):
    """The screenshot exists and is not blank: a page of text, code and figures has many grey
    levels; a blank (or error) page is one flat colour."""
    img = screenshot(PAGES[kind], tmp_path / f"{kind}.png")
    assert img.shape[0] >= 900 and img.shape[1] >= 1200, img.shape
    grey = img.mean(axis=2)
    assert grey.std() > 10.0, grey.std()
    dark = np.mean(grey < 128)  # text and lines
    assert 0.005 < dark < 0.6, dark


def test_gallery_page_images_exist():
    page = SITE / PAGES["gallery"]
    parser = _Images()
    parser.feed(page.read_text())
    figures = [s for s in parser.src if "sphx_glr_plot_simulate_scene" in s]
    assert figures, parser.src
    for src in parser.src:
        if not src.startswith(("http:", "https:", "data:")):
            path = (page.parent / src).resolve()
            assert path.is_file() and path.stat().st_size > 5000, src


def test_every_gallery_example_drew_a_figure():
    examples = sorted((ROOT / "docs" / "examples").glob("plot_*.py"))
    assert len(examples) >= 6
    images = SITE / "_images"
    for ex in examples:
        assert list(images.glob(f"sphx_glr_{ex.stem}_001.png")), ex.name


def test_every_public_function_and_class_has_an_api_page():
    spec = importlib.util.spec_from_file_location("apipages", ROOT / "docs" / "apipages.py")
    apipages = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("apipages", apipages)
    spec.loader.exec_module(apipages)
    names = apipages.public_pages()
    assert (
        "bouncedisk.studies.torque_speed.torque_speed" in names
        and "bouncedisk.engine.laws.impact_law" in names
    )
    assert not [n for n in names if any(part.startswith("_") for part in n.split("."))]
    generated = SITE / "api" / "generated"
    missing = [n for n in names if not (generated / f"{n}.html").is_file()]
    assert not missing, missing
    # a page documents its object: the signature is there, with the docstring's first line
    text = (generated / "bouncedisk.engine.laws.impact_law.html").read_text()
    assert 'id="bouncedisk.engine.laws.impact_law"' in text


class _Loads(html.parser.HTMLParser):
    """The scripts and style sheets a page loads (``<script src>``, ``<link href>`` of a style
    sheet or a preload, ``<img src>``)."""

    def __init__(self):
        super().__init__()
        self.urls: list[str] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "script" and a.get("src"):
            self.urls.append(a["src"])
        elif tag == "link" and a.get("rel") in ("stylesheet", "preload", "modulepreload"):
            self.urls.append(a.get("href") or "")
        elif tag == "img" and a.get("src"):
            self.urls.append(a["src"])


def test_no_page_loads_anything_from_another_host():
    """Every script, style sheet and image of every page is a file of the site: a reader without
    a network sees the same pages (links to other sites are fine, loads are not)."""
    pages = [p for p in sorted(SITE.rglob("*.html")) if "_static" not in p.parts]  # not templates
    assert len(pages) > 50
    outside = {}
    for page in pages:
        parser = _Loads()
        parser.feed(page.read_text(errors="replace"))
        for url in parser.urls:
            if url.startswith(("http:", "https:", "//")):
                outside.setdefault(url, str(page.relative_to(SITE)))
            elif not url.startswith("data:"):
                path = (page.parent / url.split("?")[0].split("#")[0]).resolve()
                assert path.is_file(), (page.relative_to(SITE), url)
    assert not outside, outside


def test_model_page_equations_are_typeset_offline(tmp_path):
    """The model page's dollar math is in the HTML, the MathJax that typesets it is a file of the
    site, and Chromium (no network) turns every formula into MathJax's output with no TeX error."""
    page = SITE / "model.html"
    text = page.read_text()
    n_math = text.count('class="math notranslate nohighlight"')
    assert n_math >= 100, n_math  # the page is written in formulas
    assert '<script defer="defer" src="_static/mathjax/tex-chtml-full.js' in text
    assert (SITE / "_static" / "mathjax" / "output" / "chtml" / "fonts" / "woff-v2").is_dir()
    dom = browser.dom(page.as_uri(), tmp_path / "profile")
    typeset = dom.count("<mjx-container")
    assert typeset >= n_math, (typeset, n_math)
    assert "<mjx-merror" not in dom and "data-mjx-error" not in dom


_MATH = re.compile(r'<(span|div) class="math notranslate nohighlight">(.*?)</\1>', re.DOTALL)


def test_every_formula_of_the_site_typesets_without_error(tmp_path):
    """Every formula of every built page (guide, model, API docstrings), typeset by the site's
    MathJax in one offline Chromium page: a TeX error (an unknown macro, a stray control
    character from an escape) shows as MathJax's error node, named here with its page."""
    formulas: dict[str, str] = {}
    for page in sorted(SITE.rglob("*.html")):
        if "_static" not in page.parts:
            for _, tex in _MATH.findall(page.read_text(errors="replace")):
                formulas.setdefault(tex.strip(), str(page.relative_to(SITE)))
    assert len(formulas) >= 150, len(formulas)
    mathjax = (SITE / "_static" / "mathjax" / "tex-chtml-full.js").as_uri()
    body = "\n".join(f'<p id="f{k}">{tex}</p>' for k, tex in enumerate(formulas))
    test_page = tmp_path / "math.html"
    test_page.write_text(
        f'<!DOCTYPE html><html><head><meta charset="utf-8"><script defer src="{mathjax}">'
        f"</script></head><body>\n{body}\n</body></html>"
    )
    dom = browser.dom(test_page.as_uri(), tmp_path / "profile")
    parts = dom.split('<p id="f')[1:]
    assert len(parts) == len(formulas)
    typeset = sum("<mjx-container" in part for part in parts)
    bad = [
        (page, tex)
        for part, (tex, page) in zip(parts, formulas.items(), strict=True)
        if "<mjx-merror" in part or "data-mjx-error" in part
    ]
    assert not bad, bad
    assert typeset == len(formulas), (typeset, len(formulas))


def test_performance_page_shows_every_benchmark_record():
    """Every record in benchmarks/out/ (its title, date and every result) is on the built
    performance page: the numbers come from the benchmarks' files, not from prose."""
    import json

    text = html.unescape((SITE / "user_guide" / "performance.html").read_text())
    records = [json.loads(p.read_text()) for p in sorted((ROOT / "benchmarks/out").glob("*.json"))]
    records = [r for r in records if "rows" in r]
    assert len(records) >= 3
    for r in records:
        assert r["title"] in text and f"Measured on {r['date']}" in text, r["title"]
        for row in r["rows"]:
            assert row["result"] in text, (r["title"], row)
