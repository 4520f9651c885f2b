"""The first-order trend: its grid solved stacked gives the bits of a row-by-row solve."""

import numpy as np
import pytest

from bouncedisk.analysis import observables as ob


@pytest.mark.parametrize("n", [2, 37, 300, 5000])
def test_the_trend_is_the_same_to_the_bit_whatever_the_grid_block(monkeypatch, n):
    """Solving the log-tau grid one value at a time (a block of one sample's worth) or all
    together gives the same trend to the bit: a row's line fit does not depend on its
    neighbours (fixed-order reductions along the row)."""
    rng = np.random.default_rng(n)
    t = np.linspace(0.0, 0.05, n)
    y = 30.0 * (1.0 - np.exp(-t / 0.004)) + rng.normal(0.0, 0.3, n)
    whole = ob.first_order_trend(t, y)
    monkeypatch.setattr(ob, "TREND_BLOCK", 1)
    assert ob.first_order_trend(t, y) == whole
    if n >= 300:  # enough samples to read the generating trend back
        assert whole.steady == pytest.approx(30.0, rel=0.02)
        assert whole.tau == pytest.approx(0.004, rel=0.1)
