"""The deterministic limit: one run serves every member at ``σ_e = 0``, and the valley walk
(:mod:`bouncedisk.fitting.limit_walk`) follows a narrow curved valley to its floor."""

from __future__ import annotations

import math

import numpy as np

from bouncedisk.fitting import loadpart as lp
from bouncedisk.fitting import model as fm
from bouncedisk.fitting.limit_walk import deterministic_walk
from bouncedisk.fitting.objective import Evaluation
from tests.test_joint_fit import _fake_load_data, read_curve_like

THETA = {"e": 0.55, "log10_r_phi": math.log10(0.002), "psi": 0.4, "omega_s": 1.7, "e_sigma": 0.0}


def test_at_zero_noise_one_run_gives_every_member_bit_for_bit(monkeypatch):
    """The shortcut of :func:`.model.rows_records` and :meth:`.loadpart.LoadPart.values` at
    ``σ_e = 0``: the same records and readings as running each member, with one run."""
    curve = read_curve_like()
    spec = fm.EnsembleSpec(e_sigma=0.03, seed=4, cores=1)
    grid = fm.uniform_grid(curve)
    each = [fm._simulated([THETA], curve, m, 0.0, 4, grid)[0]
            + fm.measurement_noise(len(grid), curve.sigma, 4, m) for m in range(3)]  # fmt: skip
    runs = []
    real = fm._simulated
    monkeypatch.setattr(fm, "_simulated", lambda *a: runs.append(a[2]) or real(*a))
    shared = fm.member_records(THETA, curve, range(3), spec)
    assert runs == [0]  # one run for three members
    for got, want in zip(shared, each, strict=True):
        np.testing.assert_array_equal(got, want)
    assert not np.array_equal(shared[0], shared[1])  # each member's own measurement noise

    data = _fake_load_data(torques=(0.0, 1e-4))
    part = lp.LoadPart(curves=[data], e_sigma=0.03, seed=17, cores=1)
    x = np.array(list(THETA.values()))
    got = part.values(THETA, x, 3)
    want = np.array([lp.curve_readings(THETA, data, m, 0.03, 17) for m in range(3)])
    np.testing.assert_array_equal(got, want)
    noisy = {**THETA, "e_sigma": 0.03}
    assert not np.array_equal(*part.values(noisy, x + 1.0, 2))  # the shortcut is for 0 only


class _Valley:
    """A stand-in objective: ``χ²`` of a valley curved along ``e`` (``omega_s = 1.2 + 0.3 (e −
    0.3)²``, ``psi = −1 + 2 e``), ``WIDTH`` of the range of ``omega_s`` across, its floor rising
    linearly away from ``e = 0.68`` (the walk's shape on the random motor 7) and a penalty on
    ``e_sigma`` (the walk sets it to 0)."""

    names = ["e", "log10_r_phi", "psi", "omega_s", "e_sigma"]
    lo = np.array([0.05, -4.0, -math.pi, 1.05, 0.0])
    hi = np.array([0.95, -1.0, math.pi, 4.0, 0.1])
    span = hi - lo
    WIDTH = 2e-4

    def __init__(self):
        self.log: list[Evaluation] = []
        self.calls = 0

    def residuals(self, x, members):
        self.calls += 1
        e, r, psi, om, sig = x
        across = (om - 1.2 - 0.3 * (e - 0.3) ** 2) / (self.WIDTH * self.span[3])
        return np.array([across, (psi + 1.0 - 2.0 * e) / 1e-3, (r + 2.5) / 1e-2,
                         40.0 * abs(e - 0.68) ** 0.5, sig * 1e3])  # fmt: skip

    def chi2(self, x, members):
        c = float(np.sum(self.residuals(x, members) ** 2))
        self.log.append(Evaluation(np.array(x, float), members, c))
        return c

    def best(self, members):
        ev = min(self.log, key=lambda v: v.chi2)
        return Evaluation(ev.x.copy(), members, ev.chi2)


def test_the_walk_follows_a_narrow_curved_valley_to_its_floor():
    """From a point 0.1 in ``e`` away along a valley 2·10⁻⁴ of the range across (a local search
    with the usual difference step does not resolve it), the walk ends near the floor's lowest
    point (``e`` 0.68 within a quarter step) and never returns a worse point than its start."""
    obj = _Valley()
    start = np.array([0.58, -2.4, 0.1, 1.2 + 0.3 * 0.28**2 + 0.002, 0.03])
    before = Evaluation(start, 12, obj.chi2(start, 12))
    out = deterministic_walk(obj, before, 12)
    assert out.chi2 <= before.chi2
    assert abs(out.x[0] - 0.68) <= 0.25 * 0.0117 * obj.span[0]
    assert out.x[4] == 0.0
    np.testing.assert_allclose(out.x[[1, 2]], [-2.5, -1.0 + 2.0 * out.x[0]], atol=1e-3)
    assert out.chi2 < 1e-3 * before.chi2
