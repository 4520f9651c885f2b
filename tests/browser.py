"""Headless Chromium for the tests that look at pages (the documentation site, the MLflow UI):
a screenshot or the DOM after the page's scripts ran, with no host but 127.0.0.1 resolving, so
nothing reaches the network. ``.ci/docs install`` installs Debian's chromium."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest


def chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.fail("chromium is missing (.ci/docs install installs it)")
    return exe


def _run(url: str, profile: Path, extra: list[str], budget_ms: int) -> subprocess.CompletedProcess:
    cmd = [chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars"]
    cmd += ["--no-first-run", "--disable-background-networking", "--disable-component-update"]
    cmd += ["--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1"]
    cmd += [f"--user-data-dir={profile}", f"--virtual-time-budget={budget_ms}", *extra, url]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=90)
    assert p.returncode == 0, p.stderr[-2000:]
    return p


def screenshot(url: str, out: Path, size: str = "1280,1000", budget_ms: int = 10000) -> np.ndarray:
    """The page's screenshot (after its scripts ran for ``budget_ms`` of virtual time), RGB."""
    from PIL import Image

    _run(url, out.parent / "profile", [f"--window-size={size}", f"--screenshot={out}"], budget_ms)
    assert out.is_file()
    return np.asarray(Image.open(out).convert("RGB"), dtype=float)


def dom(url: str, profile: Path, budget_ms: int = 20000) -> str:
    """The page's DOM as HTML after its scripts ran for ``budget_ms`` of virtual time."""
    return _run(url, profile, ["--dump-dom"], budget_ms).stdout
