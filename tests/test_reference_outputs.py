"""Stored reference outputs: every simulation output is bit-identical to the stored engine's.

The references (``tests/data/reference/*.npz``) were written by ``tests/reference/make_references.py``
before the restitution-noise effect existed; scenes that do not ask for an effect must not pay
for it, not even in the last bit. Later refactors are held to the same files.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "reference"))
from cases import CASES  # noqa: E402
from make_references import arrays  # noqa: E402

REF = ROOT / "tests" / "data" / "reference"


@pytest.mark.parametrize("name", sorted(CASES))
def test_outputs_are_bit_identical_to_the_stored_reference(name, monkeypatch):
    monkeypatch.chdir(ROOT)
    stored = np.load(REF / f"{name}.npz")
    now = arrays(name)
    assert sorted(stored.files) == sorted(now)
    for key in stored.files:
        a, b = stored[key], now[key]
        assert a.shape == b.shape, key
        # bit-identical: compare the bytes (NaN-safe, and -0.0 differs from 0.0)
        assert a.tobytes() == np.ascontiguousarray(b, dtype=a.dtype).tobytes(), key
