"""bouncedisk: exact event-driven simulation of a rotor bouncing on a vibrating, twisting stator.

See MODEL.md for the model; :mod:`bouncedisk.engine` for the simulator kernel.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("bouncedisk")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.0.0+unknown"
