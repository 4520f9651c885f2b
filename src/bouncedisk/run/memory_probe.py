"""The child process of :func:`bouncedisk.studies.scaling.peak_memory_mb`: one streamed run, its own peak.

``python -m bouncedisk.run.memory_probe`` reads one JSON request on stdin (``n_events``, ``e``,
``omega_s``, ``out``) and writes ``{"peak_mb": ...}`` on stdout. It imports only what the run
needs, so that the peak measured is the run's and not that of the study around it.
"""

from __future__ import annotations

import contextlib
import json
import sys
from pathlib import Path


def vm_hwm_mb() -> float:
    """This process's own peak resident memory (MB): ``VmHWM`` from ``/proc/self/status``.

    Where there is no ``/proc`` (not Linux), ``ru_maxrss``, which may include the high-water
    mark a parent passed on across fork and exec.
    """
    with contextlib.suppress(OSError), open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024.0
    import resource

    kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return kb / (1024.0 * 1024.0 if sys.platform == "darwin" else 1024.0)


def stream_events_peak_mb(n_events: int, e: float, omega_s: float, out: str | Path) -> float:
    """Stream an events-only run of ``n_events`` to ``out``; this process's peak memory (MB).

    The body of :func:`bouncedisk.studies.scaling.peak_memory_mb`'s child process: in a fresh process,
    the peak is that of the imports and of this one run alone.
    """
    from ..model.scene import scene_from_mapping
    from .runner import run_scene

    scene = scene_from_mapping(
        {
            "name": "mem",
            "parameters": {"e": e, "omega_s": omega_s},
            "effects": ["impacts", "contact"],
            "stop": {"impacts": n_events},
        }
    )
    run_scene(scene, out, progress=False)
    return vm_hwm_mb()


def _child_main() -> None:
    """``python -m bouncedisk.run.memory_probe``: one JSON request on stdin, ``{"peak_mb": ...}`` out."""
    request = json.loads(sys.stdin.read())
    peak = stream_events_peak_mb(**request)
    sys.stdout.write(json.dumps({"peak_mb": peak}) + "\n")


if __name__ == "__main__":
    _child_main()
