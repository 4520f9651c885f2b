"""A scene the package ships is found by its name from any folder (an installed wheel has no
checkout): ``fig3``, ``fig3.yaml`` and the checkout's ``workflow/config/scenes/fig3.yaml``."""

from __future__ import annotations

import pytest

from bouncedisk.model.errors import InputError
from bouncedisk.model.scene import load_scene


@pytest.mark.parametrize("name", ["fig3", "fig3.yaml", "workflow/config/scenes/fig3.yaml"])
def test_a_shipped_scene_is_found_by_name_from_an_empty_folder(tmp_path, monkeypatch, name):
    monkeypatch.chdir(tmp_path)
    scene = load_scene(name)
    assert scene.params.e == pytest.approx(0.3)


def test_a_file_beside_the_name_wins_and_other_folders_are_not_searched(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "fig3.yaml").write_text(
        "parameters: {e: 0.45, omega_s: 1.5}\nstop: {impacts: 10}\n"
    )
    assert load_scene("fig3.yaml").params.e == pytest.approx(0.45)
    with pytest.raises(InputError, match="file not found"):
        load_scene("elsewhere/fig3.yaml")
