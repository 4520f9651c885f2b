"""Send a batch job's stdout and stderr (and warnings) to a log file."""

from __future__ import annotations

import contextlib
import gc
import logging
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import NoReturn


@contextlib.contextmanager
def log_to(path: str | Path) -> Iterator[logging.Logger]:
    """Redirect stdout/stderr to ``path`` for the duration of the block; yields a logger.

    A batch job is one process that ends with the block. The objects alive when the block
    starts (the imports') and when it ends live until the process exits, so both times they
    are moved out of the cyclic garbage collector's view (:func:`gc.freeze`): the collections
    during the job and the one at the interpreter's exit skip them, a fifth of a small job's
    CPU time (``benchmarks/out/job_overhead.json``). A process that goes on after the block (a
    test running a job script in its own process) gives them back with :func:`gc.unfreeze`.

    Parameters
    ----------
    path : str or Path
        The job's log file (its folder is made).

    Yields
    ------
    logging.Logger
        The ``bouncedisk.job`` logger, writing to the log file.

    Raises
    ------
    SystemExit
        Status 2 when the block raised an error the user can fix (a bad scene): its one line
        is in the log and on stderr, with no traceback, as the package's commands do.
    """
    gc.freeze()
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    user_error = None
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
        except Exception as ex:
            user_error = _user_error_line(ex)
            if user_error is None:
                raise
            logger.error("%s", user_error)
        finally:
            logger.removeHandler(handler)
            gc.freeze()
    if user_error is not None:  # one line on the job's stderr, no traceback, exit status 2
        exit_with_error(user_error)


def exit_with_error(text: str) -> NoReturn:
    """Print :func:`~bouncedisk.model.errors.error_line` of ``text`` on stderr and exit with
    status 2: a job's, or the Snakefile's, error a user can cause, with no traceback."""
    from ..model.errors import error_line

    print(error_line(text), file=sys.stderr)
    raise SystemExit(2)


def _user_error_line(ex: Exception) -> str | None:
    """The one line of an error the user can fix: the package's ``InputError`` or a subclass
    (an output too large, a tracking store). Its module is looked up, not imported: importing
    it would import the engine, and numba, into every light job, and where it was never
    imported no such error was raised."""
    errors = sys.modules.get("bouncedisk.engine.errors")
    return ex.line() if errors is not None and isinstance(ex, errors.InputError) else None
