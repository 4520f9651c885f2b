"""numba's on-disk cache of the engine notices a change to any engine source (engine/_cache.py)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from bouncedisk.engine import _cache, laws
from bouncedisk.engine import kernel as K


def test_stamp_covers_every_source(tmp_path: Path) -> None:
    for name in ("kernel.py", "laws.py"):
        (tmp_path / name).write_text(f"# {name}\n")
    before = _cache.sources_stamp(tmp_path)
    (tmp_path / "laws.py").write_text("# laws.py, changed\n")
    assert _cache.sources_stamp(tmp_path) != before


def test_engine_functions_use_the_engine_stamp() -> None:
    for fn in (K.run_chunk, K.flight_next_impact, laws.impact_law):
        locator = fn._cache._impl.locator
        assert isinstance(locator, tuple(_cache._LOCATORS)), type(locator)
        assert locator.get_source_stamp() == _cache.sources_stamp()


CHILD = """
from bouncedisk.engine import EngineConfig, simulate_arrays
r = simulate_arrays(EngineConfig(e=0.3, omega_s=1.5, max_events=5))
print(repr(float(r.events["t"][-1])))
"""


@pytest.mark.slow
@pytest.mark.cost(17)  # one compilation of the engine
def test_changing_laws_alone_recompiles_the_kernel(tmp_path: Path) -> None:
    """A copy of the engine, run, then ``laws.py`` edited: the kernel must use the new law.

    The copy takes the engine's on-disk cache with it when there is one (the stamp is a hash of
    the sources, not of their place), so only the edited engine is compiled here: the first runs
    read the warm cache the edit must not be served from (a cold copy compiles it first)."""
    src = Path(K.__file__).resolve().parent
    pkg = tmp_path / "bouncedisk"
    shutil.copytree(src, pkg / "engine")
    (pkg / "__init__.py").write_text("")
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)

    def run() -> str:
        out = subprocess.run(
            [sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, check=True
        )
        return out.stdout.strip()

    first = run()
    assert run() == first  # from the cache
    law = pkg / "engine" / "laws.py"
    text = law.read_text()
    assert "v_plus = vs + e * v_rel" in text
    law.write_text(text.replace("v_plus = vs + e * v_rel", "v_plus = vs + 0.5 * e * v_rel"))
    assert run() != first
