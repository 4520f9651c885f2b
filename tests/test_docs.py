"""The built documentation renders: headless Chromium screenshots of the landing page, a gallery
page and an API page (file:// URLs, no network), the gallery's images on disk, and an API page for
every public function and class.

The site is built by ``.ci/docs`` (CI runs it before the tests) or by
``sphinx-build -W --keep-going -b html docs docs/_build/html``; without it these tests are skipped.
"""

import html.parser
import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
SITE = ROOT / "docs" / "_build" / "html"
PAGES = {
    "landing": "index.html",
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


def chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.fail("the documentation is built but chromium is missing (.ci/docs installs it)")
    return exe


def screenshot(page: str, out: Path) -> np.ndarray:
    """Headless Chromium's screenshot of a built page, as an RGB array; no host resolves."""
    from PIL import Image

    url = (SITE / page).as_uri()
    cmd = [chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars"]
    cmd += ["--no-first-run", "--disable-background-networking", "--disable-component-update"]
    cmd += ["--host-resolver-rules=MAP * ~NOTFOUND", f"--user-data-dir={out.parent / 'profile'}"]
    cmd += ["--window-size=1280,1000", f"--screenshot={out}", url]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert p.returncode == 0 and out.is_file(), p.stderr[-2000:]
    return np.asarray(Image.open(out).convert("RGB"), dtype=float)


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
