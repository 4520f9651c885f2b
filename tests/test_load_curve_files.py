"""Load-curve files (docs/formats.md): bounded like run-ups, and their sidecars read as a
scene's fields are."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bouncedisk.cli import main
from bouncedisk.io.load_curves import MAX_LOADS, MAX_WINDOW_PERIODS, read_load_curve
from bouncedisk.model.errors import InputError

SHIPPED = Path(__file__).resolve().parents[1] / "data" / "prototype" / "synthetic_motor_load"
YAML = SHIPPED.with_suffix(".yaml").read_text()
CSV = SHIPPED.with_suffix(".csv").read_text()


def _curve(folder: Path, csv: str = CSV, yaml_text: str = YAML) -> Path:
    (folder / "load.csv").write_text(csv)
    (folder / "load.yaml").write_text(yaml_text)
    return folder / "load.csv"


def _rows(n: int) -> str:
    torque = np.linspace(0.0, 1e-4, n)
    lines = ["torque_Nm,speed_rad_s,speed_sd_rad_s", *(f"{float(t)!r},10.0,0.5" for t in torque)]
    return "\n".join(lines) + "\n"


def test_the_shipped_curve_is_within_the_bounds():
    data = read_load_curve(SHIPPED.with_suffix(".csv"))
    assert len(data.torque) <= MAX_LOADS
    assert data.window_s[1] * data.drive_frequency_hz <= MAX_WINDOW_PERIODS


def test_too_many_rows_is_one_line(tmp_path):
    """Before: a 100,000-row curve was accepted (the fit then ran silently for minutes)."""
    read_load_curve(_curve(tmp_path, _rows(MAX_LOADS)))  # the bound itself is accepted
    with pytest.raises(InputError, match=f"has 100,000 loads; at most {MAX_LOADS:,}"):
        read_load_curve(_curve(tmp_path, _rows(100_000)))


def test_too_long_a_window_is_one_line(tmp_path, capsys):
    """Before: window_s [0.06, 1000.0] (2e7 drive periods per reading) was accepted."""
    bad = _curve(tmp_path, yaml_text=YAML.replace("- 0.12", "- 1000.0"))
    with pytest.raises(InputError) as ex:
        read_load_curve(bad)
    assert ex.value.field == "window_s[1]" and "20,000 periods" in ex.value.message
    runup = SHIPPED.parent / "synthetic_motor.csv"
    out = tmp_path / "fit.nc"
    assert main(["fit", str(runup), "--load", str(bad), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "window_s[1]" in err[0] and not out.exists()


@pytest.mark.parametrize(
    "old,new,field",
    [
        ("  Phi0_rad: 0.0002\n", "  Phi0_rad: 0.0002\n  typo_hz: 3\n", "motor.typo_hz"),
        ("repeats: 5\n", "repeats: '5'\n", "repeats"),
        ("repeats: 5\n", "repeats: 2.5\n", "repeats"),
        ("repeats: 5\n", "repeats: 0\n", "repeats"),
    ],
)
def test_bad_sidecar_fields_are_named(tmp_path, old, new, field):
    """Before: an unknown motor key was accepted silently (refused under rotor:)."""
    assert old in YAML
    with pytest.raises(InputError) as ex:
        read_load_curve(_curve(tmp_path, yaml_text=YAML.replace(old, new)))
    assert ex.value.field == field


def test_repeats_as_a_whole_float_is_read_as_members_are(tmp_path):
    """Before: `repeats: 5.0` was refused though a scene takes `members: 2.0`."""
    data = read_load_curve(
        _curve(tmp_path, yaml_text=YAML.replace("repeats: 5\n", "repeats: 5.0\n"))
    )
    assert data.sidecar["repeats"] == 5 and isinstance(data.sidecar["repeats"], int)


def test_a_list_shaped_sidecar_is_called_a_sidecar(tmp_path):
    """Before: "a scene must be a YAML mapping"."""
    with pytest.raises(InputError, match="a load curve sidecar must be a YAML mapping, got list"):
        read_load_curve(_curve(tmp_path, yaml_text="- 1\n- 2\n"))
