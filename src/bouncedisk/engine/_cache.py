"""numba's on-disk cache for the engine, keyed on every engine source file.

numba stamps a cached function with the content hash of the one file that defines it. The
engine's compiled functions call each other across files (``kernel`` compiles ``laws``,
``roots`` and ``noise`` into its own machine code), so a change to ``laws.py`` alone left
``kernel``'s cache in place and the old law running. The locators below stamp every function
defined in this package with one hash over all of the package's ``*.py`` files: a change to any
of them recompiles the whole engine once.

Importing this module registers the locators (before any engine function is decorated: the
package ``__init__`` imports it first). Functions outside this package keep numba's own
locators. Setting ``NUMBA_CACHE_LOCATOR_CLASSES`` replaces numba's list and these with it.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from numba.core import caching

ENGINE_DIR = Path(__file__).resolve().parent


def sources_stamp(folder: Path = ENGINE_DIR) -> bytes:
    """SHA-256 over the names and contents of the ``*.py`` files in ``folder``, in name order."""
    h = hashlib.sha256()
    for path in sorted(folder.glob("*.py")):
        h.update(path.name.encode())
        h.update(b"\0")
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.digest()


class _EngineStamp:
    """Locator mixin: only for files of this package, stamped by :func:`sources_stamp`."""

    def get_source_stamp(self) -> bytes:
        return sources_stamp()

    @classmethod
    def from_function(cls, py_func, py_file):
        if Path(os.path.abspath(py_file)).parent != ENGINE_DIR:
            return None
        return super().from_function(py_func, py_file)


def _numba_locator(name: str) -> type:
    """numba's locator class ``name`` (spelled with a leading underscore before numba 0.61)."""
    return getattr(caching, name, None) or getattr(caching, "_" + name)


class EngineUserProvidedLocator(_EngineStamp, _numba_locator("UserProvidedCacheLocator")):
    """``NUMBA_CACHE_DIR`` set: cache there."""


class EngineInTreeLocator(_EngineStamp, _numba_locator("InTreeCacheLocator")):
    """The package's ``__pycache__`` (numba's default)."""


class EngineUserWideLocator(_EngineStamp, _numba_locator("UserWideCacheLocator")):
    """The user's cache folder, when ``__pycache__`` is not writable."""


_LOCATORS = [EngineUserProvidedLocator, EngineInTreeLocator, EngineUserWideLocator]


def register() -> None:
    """Put the engine's locators first in numba's list (once).

    ``CacheImpl._locator_classes`` is numba's (private) list; were it ever gone, numba's own
    per-file stamps stay in force and a change to ``laws.py`` alone needs ``engine/__pycache__``
    deleted, as before these locators.
    """
    classes = getattr(caching.CacheImpl, "_locator_classes", None)
    if isinstance(classes, list) and classes[: len(_LOCATORS)] != _LOCATORS:
        classes[:0] = _LOCATORS


register()
