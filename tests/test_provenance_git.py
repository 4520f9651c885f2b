"""The code version a file and a tracked run carry: one git query for both
(:func:`bouncedisk.io.provenance.git_state`)."""

from __future__ import annotations

import subprocess
from pathlib import Path

from bouncedisk.io.provenance import git_state
from bouncedisk.tracking.writing import provenance_tags


def _repo(tmp_path: Path) -> tuple[Path, str]:
    """A repository with one commit holding ``pkg/a.py`` and ``other.txt``; its commit."""
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg/a.py").write_text("x = 1\n")
    (tmp_path / "other.txt").write_text("text\n")
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t", "-c", "commit.gpgsign=false"]
    for args in (["init", "-q"], ["add", "."], ["commit", "-q", "-m", "one"]):
        subprocess.run([*git, *args], cwd=tmp_path, check=True, capture_output=True)
    head = subprocess.run(
        ["git", "rev-parse", "HEAD"], cwd=tmp_path, check=True, capture_output=True, text=True
    ).stdout.strip()
    return tmp_path, head


def test_git_state_reads_the_commit_and_scopes_the_dirty_check(tmp_path):
    repo, head = _repo(tmp_path)
    assert git_state(repo) == {"git_commit": head, "git_dirty": "false"}
    (repo / "other.txt").write_text("changed\n")  # outside pkg/
    assert git_state(repo)["git_dirty"] == "true"
    assert git_state(repo / "pkg", under=".") == {"git_commit": head, "git_dirty": "false"}
    (repo / "pkg/a.py").write_text("x = 2\n")
    assert git_state(repo / "pkg", under=".")["git_dirty"] == "true"


def test_outside_a_checkout_the_version_is_unknown(tmp_path):
    assert git_state(tmp_path) == {"git_commit": "unknown", "git_dirty": "unknown"}
    tags = provenance_tags("simulate", tmp_path)
    assert tags["bouncedisk.git_commit"] == "unknown"
    assert "mlflow.source.git.commit" not in tags
