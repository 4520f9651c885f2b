"""Sphinx configuration of the bouncedisk documentation.

Build (from the project root): ``sphinx-build -W --keep-going -b html docs docs/_build/html``.

The API reference is generated on every build: ``apipages.write_api_pages`` walks the package and
writes one page per public module (``docs/api/``, not in git) with an ``autosummary`` of every
public function and class defined there, numba-compiled functions included; autosummary then
writes one page per object from their numpydoc docstrings. Names starting with ``_`` are left out.

Equations are MyST dollar math (``$...$``, ``$$...$$``) rendered by MathJax 3, whose files come
from PyPI (``django-static-mathjax``, in the ``docs`` extra) and are copied into the site's
``_static/mathjax/``: the pages load no script from another host and render offline.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(DOCS))
os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("MLFLOW_DISABLE_TELEMETRY", "true")

from apipages import write_api_pages  # noqa: E402
from perfpage import write_tables  # noqa: E402

import bouncedisk  # noqa: E402

project = "bouncedisk"
author = "bouncedisk developers"
copyright = "bouncedisk developers"
release = version = bouncedisk.__version__

extensions = [
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "examples/GALLERY_HEADER.rst", "examples/data"]
templates_path = ["_templates"]
myst_enable_extensions = ["deflist", "colon_fence", "dollarmath", "amsmath"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]

# --- API reference ------------------------------------------------------------------------
autosummary_generate = True
autosummary_imported_members = False
autodoc_typehints = "none"  # numpydoc's Parameters sections say the types
autodoc_default_options = {"member-order": "bysource"}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
nitpicky = False

# --- HTML -----------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = "bouncedisk"


def mathjax_static() -> Path:
    """Copy MathJax's browser build (one combined TeX-to-HTML script, its fonts and the
    accessibility and menu components it loads) from the installed ``django-static-mathjax``
    into ``_build/mathjax_static/mathjax/``, a folder that becomes the site's
    ``_static/mathjax/``; returns the folder to list in ``html_static_path``."""
    spec = importlib.util.find_spec("mathjax")
    if spec is None or spec.origin is None:
        raise RuntimeError("MathJax is missing: pip install -e '.[docs]' (django-static-mathjax)")
    es5 = Path(spec.origin).parent / "static" / "mathjax" / "es5"
    out = DOCS / "_build" / "mathjax_static"
    dest = out / "mathjax"
    if not (dest / "tex-chtml-full.js").is_file():
        shutil.rmtree(out, ignore_errors=True)
        dest.mkdir(parents=True)
        shutil.copy2(es5 / "tex-chtml-full.js", dest)
        shutil.copy2(es5.parent / "LICENSE", dest)  # Apache-2.0
        for sub in ("output/chtml/fonts/woff-v2", "a11y", "ui"):
            shutil.copytree(es5 / sub, dest / sub)
    return out


html_static_path = [str(mathjax_static())]
mathjax_path = "mathjax/tex-chtml-full.js"  # under _static/: shipped with the site
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
}
# top-level pages without sub-pages: no left sidebar (it would show an empty "Section Navigation")
html_sidebars = {
    page: [] for page in ("index", "changelog", "getting_started", "model", "formats", "internals")
}

# --- Gallery --------------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": False,
    "only_warn_on_example_error": False,
    "min_reported_time": 1,
    # its timing page loads jQuery and DataTables from CDNs: the site loads nothing from outside
    "write_computation_times": False,
    "image_scrapers": ("matplotlib",),
    "matplotlib_animations": False,
    "capture_repr": (),
    "reference_url": {},
}


write_api_pages()
# the measured numbers of user_guide/performance.md, from the benchmarks' own outputs
write_tables(ROOT / "benchmarks" / "out", DOCS / "_build" / "generated" / "performance_tables.md")
