"""The API reference's page list: every public module, function and class of ``bouncedisk``.

Used by ``conf.py`` (which writes the pages on every build) and by ``tests/test_docs.py`` (which
checks that the built site has a page for each object). Names starting with ``_`` are private.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
from pathlib import Path

import bouncedisk

DOCS = Path(__file__).resolve().parent


def public_objects(module) -> tuple[list[str], list[str]]:
    """Public functions (numba ones included) and classes defined in ``module``, in source order."""
    functions, classes = [], []
    for name, obj in vars(module).items():
        if name.startswith("_"):
            continue
        target = getattr(obj, "py_func", obj)  # a numba dispatcher documents its Python function
        if getattr(target, "__module__", None) != module.__name__:
            continue
        if inspect.isclass(target):
            classes.append(name)
        elif inspect.isfunction(target):
            functions.append(name)
    return functions, classes


def public_modules() -> list[str]:
    """Every module of the package whose dotted name has no part starting with ``_``."""
    names = ["bouncedisk"]
    for info in pkgutil.walk_packages(bouncedisk.__path__, "bouncedisk."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    return sorted(names)


def _block(title: str, names: list[str], template: str) -> list[str]:
    if not names:
        return []
    lines = [title, "-" * len(title), "", ".. autosummary::", "   :toctree: generated/"]
    lines += [f"   :template: autosummary/{template}", ""]
    lines += [f"   {name}" for name in names]
    return lines + [""]


def write_api_pages(out: Path = DOCS / "api") -> list[str]:
    """Write ``api/<module>.rst`` for every public module and ``api/index.rst`` listing them."""
    out.mkdir(exist_ok=True)
    modules = public_modules()
    index = [
        "API reference",
        "=============",
        "",
        "Every public function and class of the package, one page each, from its numpydoc",
        "docstring (generated on every build; names starting with ``_`` are private and left out).",
        "",
        ".. toctree::",
        "   :maxdepth: 1",
        "",
    ]
    for name in modules:
        module = importlib.import_module(name)
        functions, classes = public_objects(module)
        title = f"``{name}``"
        lines = [title, "=" * len(title), "", f".. automodule:: {name}", "   :no-members:", ""]
        lines += [f".. currentmodule:: {name}", ""]
        lines += _block("Classes", classes, "class.rst")
        lines += _block("Functions", functions, "function.rst")
        text = "\n".join(lines)
        path = out / f"{name}.rst"
        if not path.exists() or path.read_text() != text:  # unchanged pages stay up to date
            path.write_text(text)
        index.append(f"   {name}")
    for page in out.glob("bouncedisk*.rst"):  # modules gone (renamed or removed)
        if page.stem not in modules:
            page.unlink()
    generated = out / "generated"
    if generated.is_dir():  # autosummary's pages of objects no longer public
        keep = set(public_pages())
        for page in generated.glob("bouncedisk*.rst"):
            if page.stem not in keep:
                page.unlink()
    text = "\n".join(index) + "\n"
    if not (out / "index.rst").exists() or (out / "index.rst").read_text() != text:
        (out / "index.rst").write_text(text)
    return modules


def public_pages() -> list[str]:
    """Dotted names of every public function and class: one API page each."""
    out = []
    for name in public_modules():
        functions, classes = public_objects(importlib.import_module(name))
        out += [f"{name}.{obj}" for obj in classes + functions]
    return out
