"""Comparator solvers converge to the exact solution; the study's bookkeeping is right."""

import math

import numpy as np
import pandas as pd
import pytest

from bouncedisk.engine import EngineConfig, InitialState, simulate_arrays
from bouncedisk.model.errors import InputError
from bouncedisk.model.scene import scene_from_mapping
from bouncedisk.run.comparators import ivp_events, moreau_events
from bouncedisk.run.memory_probe import vm_hwm_mb
from bouncedisk.run.runner import run_scene_arrays
from bouncedisk.studies.scaling import peak_memory_mb
from bouncedisk.studies.work_precision import CASES, _errors, work_precision_summary

REF = simulate_arrays(EngineConfig(e=0.3, omega_s=1.5, max_events=40, tol=1e-14)).events


@pytest.mark.parametrize("method", ["rk45", "dop853", "lsoda"])
def test_solve_ivp_converges_to_exact_impacts(method):
    errs = []
    for tol in (1e-5, 1e-10):
        ev, _ = ivp_events(0.3, 1.5, method, tol, 0.0, None, None, 20)
        errs.append(np.max(np.abs(ev["t"] - REF["t"][:20])))
    assert errs[1] < 1e-7 and errs[1] < errs[0]


def test_moreau_jean_error_shrinks_with_the_step():
    errs = []
    for h in (1e-3, 1e-4):
        ev, _ = moreau_events(0.3, 1.5, h, 0.0, None, None, 10)
        errs.append(np.max(np.abs(ev["t"] - REF["t"][:10])))
    assert errs[1] < errs[0] and errs[1] < 1e-2


def test_comparators_run_behind_the_scene_interface():
    base = {
        "name": "c",
        "parameters": {"e": 0.3, "omega_s": 1.5},
        "effects": ["impacts", "contact"],
        "stop": {"impacts": 10},
    }
    for method, extra in (("dop853", {"tol": 1e-9}), ("moreau", {"step": 1e-4})):
        sc = scene_from_mapping({**base, "solver": {"method": method, **extra}})
        res = run_scene_arrays(sc)
        assert len(res.events["t"]) == 10
        assert np.max(np.abs(res.events["t"] - REF["t"][:10])) < 1e-2
    with pytest.raises(InputError, match="torsion"):
        run_scene_arrays(
            scene_from_mapping(
                {**base, "effects": ["impacts", "contact", "torsion"], "solver": {"method": "rk45"}}
            )
        )
    with pytest.raises(InputError, match="solver.step"):
        run_scene_arrays(scene_from_mapping({**base, "solver": {"method": "moreau"}}))


def test_chattering_comparator_comes_to_rest_near_the_accumulation_point():
    init = InitialState(t=0.0, u=0.5, v=0.0)
    exact = simulate_arrays(EngineConfig(e=0.5, omega_s=0.8, max_events=200), init).events
    ev, status = ivp_events(0.5, 0.8, "dop853", 1e-10, 0.0, 0.5, 0.0, 200)
    errs = _errors(CASES[1], ev, exact)
    assert errs["rest_error"] < 1e-5


def test_summary_targets_logic():
    rows = [
        # exact: cheap and accurate
        ("exact", 1e-6, 1e-4, 1e-12),
        ("exact", 1e-12, 2e-4, 1e-15),
        ("solve_ivp RK45", 1e-6, 0.1, 1e-6),
        ("solve_ivp RK45", 1e-10, 0.5, 1e-9),
        ("solve_ivp DOP853", 1e-10, 0.2, 5e-9),
        ("Moreau-Jean", 1e-3, 1e-5, 1e-2),
    ]
    table = pd.DataFrame(
        [
            {"case": CASES[0].name, "solver": s, "knob": "k", "value": v, "cpu_s": c, "error": e}
            for s, v, c, e in rows
        ]
    )
    out = work_precision_summary(table)
    assert out["speedup_vs_fastest_ivp_at_1e-8"] == pytest.approx(0.2 / 1e-4)
    assert out["exact_more_accurate_at_every_budget"]
    # a comparator better than the exact solver at its budget breaks dominance
    bad = pd.concat(
        [
            table,
            pd.DataFrame(
                [
                    {
                        "case": CASES[0].name,
                        "solver": "Moreau-Jean",
                        "knob": "h",
                        "value": 1.0,
                        "cpu_s": 1e-6,
                        "error": 1e-20,
                    }
                ]
            ),
        ]
    )
    assert not work_precision_summary(bad)["exact_more_accurate_at_every_budget"]
    assert math.isnan(
        work_precision_summary(table[table.solver != "exact"])["speedup_vs_fastest_ivp_at_1e-8"]
    )


@pytest.mark.slow  # three child processes
def test_peak_memory_is_the_childs_own_and_grows_with_the_run():
    peak_memory_mb(1_000)  # the engine's compiled cache is warm for the runs compared below
    ballast = np.ones(80_000_000)  # 640 MB resident in this process, not in the child
    assert vm_hwm_mb() > 640
    small = peak_memory_mb(1_000)
    large = peak_memory_mb(200_000)
    del ballast
    assert 20 < small < 600
    assert large >= small


def test_peak_memory_child_failure_is_a_clear_error_and_leaves_no_file(tmp_path, monkeypatch):
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    with pytest.raises(RuntimeError, match=r"child process failed .*parameters\.e: must be in"):
        peak_memory_mb(1_000, e=2.0)
    assert list(tmp_path.iterdir()) == []
