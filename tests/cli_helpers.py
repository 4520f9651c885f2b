"""Helpers of the command-line tests: the one error line, and a small chaotic motor scene."""

from __future__ import annotations

from pathlib import Path

#: A small chaotic motor: torsion, restitution noise, two members (about a second a command).
SMALL_MOTOR = """
name: small
parameters: {e: 0.6, omega_s: 1.5, r_phi: 0.01, psi: 0.0, e_sigma: 1.0e-9}
effects: [impacts, contact, torsion, restitution_noise]
stop: {time: 200.0}
ensemble: {members: 2, seed: 1}
stats: {discard: 50.0}
"""


def one_line(capsys) -> str:
    """The command's only line on stderr, with no traceback."""
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "Traceback" not in err[0]
    return err[0]


def scene_file(folder: Path, text: str = SMALL_MOTOR, name: str = "small.yaml", **times) -> str:
    """``text`` written to ``folder/name``; ``time=``, ``discard=`` replace the motor's."""
    for key, default in (("time", "200.0"), ("discard", "50.0")):
        if key in times:
            text = text.replace(f"{key}: {default}", f"{key}: {times[key]!r}")
    f = Path(folder) / name
    f.write_text(text)
    return str(f)
