"""Hostile YAML is one line, exit 2, never a RecursionError traceback."""

from __future__ import annotations

import pytest

from bouncedisk.cli import main
from bouncedisk.model import yamlio
from bouncedisk.model.errors import InputError


@pytest.mark.parametrize(
    "text,words",
    [
        ("a: &a [*a]\n", "refers to a value that holds it"),
        ("a: &a {b: *a}\n", "refers to a value that holds it"),
        ("[" * 1500 + "\n", "nested too deeply"),
        ("a: " + "{b: " * 1500 + "1" + "}" * 1500 + "\n", "nested too deeply"),
    ],
    ids=["alias-in-list", "alias-in-mapping", "deep-list", "deep-mapping"],
)
def test_recursive_or_deep_yaml_is_one_line(tmp_path, capsys, text, words):
    """Before: RecursionError tracebacks (exit 1)."""
    f = tmp_path / "s.yaml"
    f.write_text(text)
    out = tmp_path / "o.nc"
    assert main(["simulate", str(f), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0] and str(f) in err[0]
    assert not out.exists()


def test_shared_aliases_that_do_not_hold_themselves_still_load():
    text = "p: &p {e: 0.5}\nq: [*p, *p, {r: *p}]\n"
    assert yamlio.load(text) == {"p": {"e": 0.5}, "q": [{"e": 0.5}, {"e": 0.5}, {"r": {"e": 0.5}}]}


def test_a_set_value_nested_too_deeply_is_one_line():
    with pytest.raises(InputError, match="nested too deeply"):
        yamlio.load("[" * 1500 + "]" * 1500, "--set")
