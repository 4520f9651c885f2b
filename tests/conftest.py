"""Shared fixtures and settings."""

import os
import sys
from pathlib import Path

import pytest
from hypothesis import settings

sys.path.insert(0, str(Path(__file__).parent))

settings.register_profile("ci", max_examples=60, deadline=None, derandomize=True)
settings.register_profile("dev", max_examples=30, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "workflow" / "config" / "scenes"


def pytest_collection_modifyitems(config, items):
    """Run the longest tests first: the items marked ``cost(seconds)`` (measured CPU seconds of
    the test, or of the fixture its xdist group builds), most expensive first, then the rest in
    file order. A test in an xdist group moves with its whole group (the group's largest cost),
    so a module fixture the group shares is still built once. pytest-xdist (``--dist loadgroup
    --no-loadscope-reorder``, pyproject.toml) hands the work out in this order: the long tests
    start at once on both workers and the short ones fill in at the end, instead of a long one
    starting last on one worker while the other has run out of work."""

    def unit(item) -> str:
        group = item.get_closest_marker("xdist_group")
        return f"group {group.args[0]}" if group else item.nodeid

    cost: dict[str, float] = {}
    for item in items:
        mark = item.get_closest_marker("cost")
        u = unit(item)
        cost[u] = max(cost.get(u, 0.0), float(mark.args[0]) if mark else 0.0)
    items.sort(key=lambda item: -cost[unit(item)])  # stable: file order among equal costs


@pytest.fixture
def scene_file(tmp_path):
    """Write a scene YAML from text and return its path."""

    def make(text: str, name: str = "scene.yaml") -> Path:
        p = tmp_path / name
        p.write_text(text)
        return p

    return make
