"""A pipeline job's log and heap: every job script enters ``io.job_log.log_to``, which writes its
log and freezes the heap at the block's start and end (``gc.freeze``)."""

import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted((ROOT / "workflow" / "scripts").glob("*.py"))

#: Run in a process of its own: freezing the test process's heap would keep its garbage.
PROBE = """
import gc, sys
from bouncedisk.io.job_log import log_to

before = gc.get_freeze_count()
with log_to(sys.argv[1]) as log:
    inside = gc.get_freeze_count()
    made = [[i] for i in range(5000)]
    log.info("made %d lists", len(made))
after = gc.get_freeze_count()
print(before, inside, after)
"""


def test_every_job_script_runs_inside_log_to():
    assert SCRIPTS
    for path in SCRIPTS:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        entered = [
            item.context_expr.func.id
            for node in ast.walk(tree)
            if isinstance(node, ast.With)
            for item in node.items
            if isinstance(item.context_expr, ast.Call)
            and isinstance(item.context_expr.func, ast.Name)
        ]
        assert "log_to" in entered, f"{path.name} does not enter log_to"


def test_log_to_writes_the_log_and_freezes_the_heap_at_start_and_end(tmp_path):
    log = tmp_path / "logs" / "job.log"
    p = subprocess.run(
        [sys.executable, "-c", PROBE, str(log)],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    before, inside, after = map(int, p.stdout.split())
    assert before == 0
    assert inside > 1000  # the imports' objects
    assert after >= inside + 5000  # and those made inside the block, alive at its end
    assert "made 5000 lists" in log.read_text(encoding="utf-8")


#: A job whose scene is bad, as the simulate job meets it (a scene edited after Snakemake
#: planned the run), and one whose code fails.
BAD_JOB = """
import sys
from bouncedisk.io.job_log import log_to
from bouncedisk.model.scene import load_scene

with log_to(sys.argv[1]):
    if sys.argv[2] == "scene":
        load_scene(sys.argv[3])
    if sys.argv[2] == "subclass":  # as an output too large or a tracking store's error
        from bouncedisk.model.errors import InputError

        class TooLarge(InputError):
            pass

        raise TooLarge("out.nc", "--max-output", "the file would be too large")
    raise ZeroDivisionError("a bug")
"""


def test_a_bad_scene_in_a_job_is_one_line_and_status_2(tmp_path):
    """The user's error: one line on stderr and in the log, exit 2, no traceback; a bug keeps
    its traceback (and its status 1)."""
    scene = tmp_path / "bad.yaml"
    scene.write_text("parameters: {e: 1.7, omega_s: 1.5}\nstop: {impacts: 5}\n")
    log = tmp_path / "job.log"
    run = subprocess.run(
        [sys.executable, "-c", BAD_JOB, str(log), "scene", str(scene)],
        capture_output=True,
        text=True,
    )
    line = f"{scene}: parameters.e: must be in [0, 1], got 1.7"
    assert run.returncode == 2 and run.stderr == f"bouncedisk: error: {line}\n"
    assert log.read_text().rstrip().endswith(f"ERROR {line}")
    sub = subprocess.run(
        [sys.executable, "-c", BAD_JOB, str(log), "subclass", ""], capture_output=True, text=True
    )
    line = "out.nc: --max-output: the file would be too large"
    assert sub.returncode == 2 and sub.stderr == f"bouncedisk: error: {line}\n"
    bug = subprocess.run(
        [sys.executable, "-c", BAD_JOB, str(log), "bug", ""], capture_output=True, text=True
    )
    assert bug.returncode == 1 and "ZeroDivisionError: a bug" in bug.stderr
