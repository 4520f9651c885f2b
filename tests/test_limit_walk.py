"""The deterministic limit: one run serves every member at ``σ_e = 0``, and the valley walk
(:mod:`bouncedisk.fitting.limit_walk`) follows a narrow curved valley to its floor."""

from __future__ import annotations

import math

import numpy as np
from test_joint_fit import _fake_load_data, read_curve_like

from bouncedisk.fitting import limit_walk as lw
from bouncedisk.fitting import loadpart as lp
from bouncedisk.fitting import members as fm
from bouncedisk.fitting.objective import Evaluation, Objective

THETA = {"e": 0.55, "log10_r_phi": math.log10(0.002), "psi": 0.4, "omega_s": 1.7, "e_sigma": 0.0}


def test_at_zero_noise_one_run_gives_every_member_bit_for_bit(monkeypatch):
    """The shortcut of :func:`.members.rows_records` and :meth:`.loadpart.LoadPart.values` at
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
    want = np.array([lp.curve_readings(THETA, data, m, 0.03, 17) for m in range(5)])
    reads = []
    real_readings = lp.curve_readings
    monkeypatch.setattr(lp, "curve_readings", lambda *a: reads.append(a[2]) or real_readings(*a))
    part = lp.LoadPart(curves=[data], e_sigma=0.03, seed=17, cores=1)
    x = np.array(list(THETA.values()))
    np.testing.assert_array_equal(part.values(THETA, x, 2), want[:2])
    np.testing.assert_array_equal(part.values(THETA, x, 5), want)  # a cached set extended
    assert reads == [0, 2]  # one member's curve per call
    noisy = {**THETA, "e_sigma": 0.03}
    assert not np.array_equal(*part.values(noisy, x + 1.0, 2))  # the shortcut is for 0 only


class _Valley:
    """A stand-in objective: ``χ²`` of a valley that winds along ``e`` (``omega_s = 1.3 + 0.05
    sin(40 e)``, ``psi = −1 + 2 e``), ``WIDTH`` of the range of ``omega_s`` across, its floor
    rising away from ``e = 0.68`` (the walk's shape on the random motor 7), and a penalty on
    ``e_sigma`` away from ``noise``."""

    names = ["e", "log10_r_phi", "psi", "omega_s", "e_sigma"]
    lo = np.array([0.05, -4.0, -math.pi, 1.05, 0.0])
    hi = np.array([0.95, -1.0, math.pi, 4.0, 0.1])
    span = hi - lo
    WIDTH = 2e-4
    to_unit, from_unit = Objective.to_unit, Objective.from_unit  # the unit box: lo, span only

    def __init__(self, noise: float = 0.0):
        self.log: list[Evaluation] = []
        self.noise = noise  # the e_sigma the stand-in's data prefer

    @staticmethod
    def omega(e: float) -> float:
        return 1.3 + 0.05 * math.sin(40.0 * e)

    def residuals(self, x, members):
        e, r, psi, om, sig = x
        return np.array([(om - self.omega(e)) / (self.WIDTH * self.span[3]),
                         (psi + 1.0 - 2.0 * e) / 1e-3, (r + 2.5) / 1e-2,
                         40.0 * abs(e - 0.68) ** 0.5, (sig - self.noise) * 1e3])  # fmt: skip

    def chi2(self, x, members):
        c = float(np.sum(self.residuals(x, members) ** 2))
        self.log.append(Evaluation(np.array(x, float), members, c))
        return c

    def best(self, members):
        ev = min(self.log, key=lambda v: v.chi2)
        return Evaluation(ev.x.copy(), members, ev.chi2)


def _start(obj: _Valley) -> Evaluation:
    x = np.array([0.58, -2.4, 0.1, obj.omega(0.58) + 0.002, 0.03])
    return Evaluation(x, 12, obj.chi2(x, 12))


def test_the_walk_follows_a_narrow_winding_valley_to_its_floor():
    """From 0.1 in ``e`` away along a valley 2·10⁻⁴ of the range across that winds in
    ``omega_s``, the walk alone (:func:`_one_way`, no last refit) ends within a quarter step of the
    floor's lowest point; the whole walk reaches it to ``χ²`` below 10⁻³, sets ``e_sigma`` to 0 and
    never returns a worse point than its start. Without the walk (only the last refit) the end
    is 0.004 short at ``χ²`` 7.9; without the halving, ``χ²`` 0.002."""
    quarter = 0.25 * lw.STEP * _Valley.span[0]
    obj = _Valley()
    before = _start(obj)
    y0 = before.x.copy()
    y0[4] = 0.0
    y0, c0 = lw._refit(obj, y0, 12)
    end, _ = lw._one_way(obj, y0, c0, 1.0, 12)
    assert abs(end[0] - 0.68) <= quarter
    obj = _Valley()
    before = _start(obj)
    out = lw.deterministic_walk(obj, before, 12)
    assert out.chi2 <= before.chi2 and out.x[4] == 0.0
    assert abs(out.x[0] - 0.68) <= quarter
    np.testing.assert_allclose(out.x[[1, 2]], [-2.5, -1.0 + 2.0 * out.x[0]], atol=1e-3)
    assert out.chi2 < 1e-3


def test_no_walk_where_the_deterministic_limit_reads_far_worse():
    """Where ``σ_e = 0`` reads over :data:`WORTH` times the best ``χ²`` (data that want noise) the
    walk stops after its first refit, and the best point is the one it was given."""
    obj = _Valley(noise=0.03)
    x = np.array([0.58, -2.5, -1.0 + 2.0 * 0.58, obj.omega(0.58), 0.03])  # on the floor: chi2 160
    best = Evaluation(x, 12, obj.chi2(x, 12))
    n = len(obj.log)
    out = lw.deterministic_walk(obj, best, 12)
    assert len(obj.log) == n + 1  # only the start's refit at sigma_e = 0 (chi2 about 1060)
    assert obj.log[-1].chi2 > lw.WORTH * best.chi2
    np.testing.assert_array_equal(out.x, x)
