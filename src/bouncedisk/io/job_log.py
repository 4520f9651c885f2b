"""Send a batch job's stdout and stderr (and warnings) to a log file."""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterator
from pathlib import Path


@contextlib.contextmanager
def log_to(path: str | Path) -> Iterator[logging.Logger]:
    """Redirect stdout/stderr to ``path`` for the duration of the block; yields a logger."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    with (
        open(p, "w", encoding="utf-8") as fh,
        contextlib.redirect_stdout(fh),
        contextlib.redirect_stderr(fh),
    ):
        logging.captureWarnings(True)
        logger = logging.getLogger("bouncedisk.job")
        handler = logging.StreamHandler(fh)
        handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
        logger.addHandler(handler)
        logger.setLevel(logging.INFO)
        try:
            yield logger
        finally:
            logger.removeHandler(handler)
