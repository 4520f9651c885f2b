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


# ---------------------------------------------------------------- units and the motor, one rule
RUNUP_YAML = (SHIPPED.parent / "synthetic_motor.yaml").read_text()
UNITS = "units:\n  torque: N m\n  speed: rad/s\n"


@pytest.mark.parametrize(
    "units,field",
    [
        ("units:\n  torque: N m\n  speed: rpm\n", "units.speed"),
        ("units:\n  torque: mN m\n  speed: rad/s\n", "units.torque"),
        ("", "units"),
    ],
)
def test_load_units_are_checked(tmp_path, units, field):
    """rpm, mN m or no units at all would be fitted as rad/s and N m."""
    assert UNITS in YAML
    with pytest.raises(InputError) as ex:
        read_load_curve(_curve(tmp_path, yaml_text=YAML.replace(UNITS, units)))
    assert ex.value.field == field and "\n" not in ex.value.line()


def test_load_units_accept_the_spellings_of_n_m(tmp_path):
    text = YAML.replace(UNITS, "units:\n  torque: N·m\n  speed: rad s-1\n")
    assert read_load_curve(_curve(tmp_path, yaml_text=text)).torque[-1] == pytest.approx(3e-4)


@pytest.mark.parametrize(
    "old,new,field",
    [
        ("  Phi0_rad: 0.0002\n", "  Phi0_rad: 4.0\n", "motor.Phi0_rad"),
        (
            "  drive_frequency_hz: 20000.0\n",
            "  drive_frequency_hz: 1.0e+12\n",
            "motor.drive_frequency_hz",
        ),
        ("  Phi0_rad: 0.0002\n", "  Phi0_rad: 0.0002\n  U0_m: 5.0\n", "motor.U0_m"),
        ("  Phi0_rad: 0.0002\n", "  Phi0_rad: 0.0002\n  U0_m: banana\n", "motor.U0_m"),
    ],
)
def test_load_and_runup_sidecars_read_the_motor_alike(tmp_path, old, new, field):
    """One schema for the motor fields: the same value gets the same one-line error."""
    from bouncedisk.io.runup_curves import read_sidecar

    assert old in YAML and old in RUNUP_YAML
    with pytest.raises(InputError) as load:
        read_load_curve(_curve(tmp_path, yaml_text=YAML.replace(old, new)))
    (tmp_path / "runup.yaml").write_text(RUNUP_YAML.replace(old, new))
    with pytest.raises(InputError) as runup:
        read_sidecar(tmp_path / "runup.yaml")
    assert load.value.field == runup.value.field == field
    assert load.value.message == runup.value.message


def test_a_load_sidecar_accepts_u0_as_a_runup_sidecar_does(tmp_path):
    text = YAML.replace("  Phi0_rad: 0.0002\n", "  Phi0_rad: 0.0002\n  U0_m: 1.0e-06\n")
    assert read_load_curve(_curve(tmp_path, yaml_text=text)).sidecar["motor"]["U0_m"] == 1e-6


# ---------------------------------------------------------------- columns named like repeats
def _with_column(csv: str, name: str, value: str) -> str:
    head, *rows = csv.strip().splitlines()
    return "\n".join([f"{head},{name}", *(f"{r},{value}" for r in rows)]) + "\n"


def test_a_column_named_note_1_is_not_a_duplicate(tmp_path):
    """pandas renames a repeated `note` to `note.1`; a column written `note.1` is its own."""
    data = read_load_curve(_curve(tmp_path, csv=_with_column(CSV, "note.1", "x")))
    assert len(data.torque) == 16


def test_a_repeated_column_is_named_from_the_header(tmp_path):
    with pytest.raises(InputError) as ex:
        read_load_curve(_curve(tmp_path, csv=_with_column(CSV, "speed_rad_s", "1.0")))
    assert ex.value.field == "speed_rad_s" and "more than once" in ex.value.message


def test_a_runup_column_named_omega_1_is_not_a_duplicate(tmp_path):
    from bouncedisk.io.runup_curves import read_curve

    runup = SHIPPED.parent / "synthetic_motor.csv"
    (tmp_path / "r.csv").write_text(_with_column(runup.read_text(), "omega_rad_s.1", "0"))
    (tmp_path / "r.yaml").write_text(RUNUP_YAML)
    assert len(read_curve(tmp_path / "r.csv").omega) == 6001


# ---------------------------------------------------------------- values beyond the motor
@pytest.mark.parametrize(
    "column,value",
    [
        ("torque_Nm", 1e300),
        ("speed_rad_s", 1e300),
        ("speed_sd_rad_s", 1e300),
        ("speed_rad_s", -3e4),
    ],
)
def test_values_beyond_the_motor_are_refused_when_read(tmp_path, capsys, column, value):
    """The fit used to stop on LinAlgError or OverflowError, or exit 0 with RuntimeWarnings."""
    import pandas as pd

    df = pd.read_csv(SHIPPED.with_suffix(".csv"))
    df.loc[3, column] = value if column != "torque_Nm" else df.loc[3, column] * value
    df = df.sort_values("torque_Nm")
    bad = _curve(tmp_path, csv=df.to_csv(index=False))
    with pytest.raises(InputError) as ex:
        read_load_curve(bad)
    assert ex.value.field == column and "check the units" in ex.value.message
    out = tmp_path / "fit.nc"
    runup = SHIPPED.parent / "synthetic_motor.csv"
    assert main(["fit", str(runup), "--load", str(bad), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{column}: row" in err[0] and not out.exists()


def test_the_shipped_curve_is_well_inside_the_speed_bound():
    from bouncedisk.model import limits

    d = read_load_curve(SHIPPED.with_suffix(".csv"))
    drive = 2 * np.pi * d.drive_frequency_hz * d.phi0_rad
    assert np.max(np.abs(d.speed)) <= drive < limits.max_speed(d.drive_frequency_hz, d.phi0_rad)


@pytest.mark.parametrize(
    "old,new,field",
    [
        ("repeats: 5\n", "repeats: 1.0e+30\n", "repeats"),
        ("  m_r_kg: 0.01\n", "  m_r_kg: 1.0e+300\n", "rotor.m_r_kg"),
        ("  r_g_m: 0.004\n", "  r_g_m: 1.0e-300\n", "rotor.r_g_m"),
        ("preload_N: 0.77\n", "preload_N: 1.0e+300\n", "preload_N"),
    ],
)
def test_sidecar_values_beyond_the_motor_are_refused(tmp_path, old, new, field):
    """`repeats: 1e30` reached the fit as an integer (TypeError in its search)."""
    assert old in YAML
    with pytest.raises(InputError) as ex:
        read_load_curve(_curve(tmp_path, yaml_text=YAML.replace(old, new)))
    assert ex.value.field == field and "must be in [" in ex.value.message


@pytest.mark.parametrize("new", ["8.0000000000000007e-05", "-0.0001"])
def test_a_number_in_a_message_is_a_plain_float(tmp_path, new):
    """Messages printed `np.float64(8e-05)` (a repeated or a negative torque)."""
    assert "\n0.0001," in CSV
    with pytest.raises(InputError) as ex:
        read_load_curve(_curve(tmp_path, csv=CSV.replace("\n0.0001,", f"\n{new},")))
    message = ex.value.message
    assert ex.value.field == "torque_Nm" and repr(float(new)) in message and "np." not in message
