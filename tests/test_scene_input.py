"""Scene values that cannot work are refused: restitution noise below an ulp of ``e``, an
averaging window shorter than a stator period, YAML alias bombs.
"""

import math
import time

import pytest
from cli_checks import QUICK_STATS, S6, leftovers, one_line

from bouncedisk.cli import main


# --------------------------------------------------------------------------- noise below an ulp
@pytest.mark.parametrize("sigma", ["1e-17", "1e-320", "2e-16"])
def test_noise_that_cannot_perturb_e_is_refused(tmp_path, capsys, sigma):
    out = tmp_path / "s.nc"
    argv = ["stats", S6, *QUICK_STATS, "--set", f"parameters.e_sigma={sigma}", "-o", str(out)]
    assert main([*argv, "--json"]) == 2
    line = one_line(capsys)
    assert "parameters.e_sigma" in line and "ulp of e" in line
    assert not leftovers(tmp_path, "s.nc")
    # 4 ulp of e = 0.6 is the least noise accepted; it does make members differ
    least = 4 * math.ulp(0.6)
    assert f"{least:.3g}" in line


def test_least_accepted_noise_gives_distinct_members(capsys):
    import json

    argv = ["stats", S6, *QUICK_STATS, "--set", f"parameters.e_sigma={4 * math.ulp(0.6)!r}"]
    assert main([*argv, "--json", "-q"]) == 0
    s = json.loads(capsys.readouterr().out)
    low, high = s["mean_omega_ci95"]
    assert high - low > 0.0  # members are distinct runs: the interval has a width


# ----------------------------------------------------------------------------- averaging window
@pytest.mark.parametrize("discard", ["1999.9999999", "1996"])
def test_window_shorter_than_a_stator_period_is_an_error(capsys, discard):
    argv = ["stats", S6, "--set", "stop.time=2000", "--set", "ensemble.members=4"]
    assert main([*argv, "--set", f"stats.discard={discard}", "--json"]) == 2
    line = one_line(capsys)
    assert "stats.discard" in line and "stator period (4.189)" in line
    assert capsys.readouterr().out == ""


def test_window_of_one_period_is_accepted(capsys):
    period = 2 * math.pi / 1.5
    argv = ["stats", S6, "--set", "stop.time=2000", "--set", "ensemble.members=2", "-q"]
    assert main([*argv, "--set", f"stats.discard={2000 - 1.001 * period!r}"]) == 0


# ----------------------------------------------------------------------------------- YAML bombs
def test_nested_aliases_are_refused_quickly(tmp_path, capsys):
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    for i in range(1, 10):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]")
    f = tmp_path / "bomb.yaml"
    f.write_text("\n".join(lines) + "\nname: x\n")
    assert f.stat().st_size < 600
    start = time.process_time()
    assert main(["simulate", str(f), "-o", str(tmp_path / "o.nc")]) == 2
    assert time.process_time() - start < 10.0  # CPU seconds (it ran for minutes before)
    assert "aliases (*name) expand to more than 100,000 values" in one_line(capsys)


def test_ordinary_aliases_still_load():
    from bouncedisk.model import yamlio

    text = "p: &p {e: 0.3, omega_s: 1.5}\nq: *p\nr: {<<: *p, e: 0.5}\n"
    data = yamlio.load(text, "x")
    assert data["q"] == {"e": 0.3, "omega_s": 1.5} and data["r"] == {"e": 0.5, "omega_s": 1.5}
    assert yamlio._expanded_size(yamlio.Loader(text).get_single_node(), "x") == 23


# ------------------------------------------------------------------ restitution noise, one bound
PHYSICAL = dict(m_r=0.01, r_g=0.004, r_c=0.002, mu=0.3, e=0.5, g=9.81, f=2e4, U0=1e-6, Phi0=2e-4)


def test_scene_noise_has_the_command_lines_bound():
    """`e_sigma` in [0, 0.5] on the command line, >= 0 in a scene: one bound for both."""
    from bouncedisk.model.errors import InputError
    from bouncedisk.model.limits import E_SIGMA
    from bouncedisk.model.params import PhysicalParameters
    from bouncedisk.model.scene import load_scene

    with pytest.raises(InputError) as ex:
        load_scene(S6, ["parameters.e_sigma=0.7"])
    assert ex.value.field.startswith("parameters.e_sigma") and E_SIGMA.text() in ex.value.message
    assert load_scene(S6, [f"parameters.e_sigma={E_SIGMA.high}"]).params.e_sigma == 0.5
    with pytest.raises(InputError) as ex:
        PhysicalParameters.from_mapping({**PHYSICAL, "e_sigma": 0.7}, "m.yaml")
    assert ex.value.field == "physical.e_sigma" and E_SIGMA.text() in ex.value.message
