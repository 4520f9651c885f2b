"""What every subcommand shares: exit statuses, ``--set``, flushing stdout."""

from __future__ import annotations

import argparse
import shlex
import sys

EXIT_USER = 2
EXIT_FAIL = 1
EXIT_INTERRUPT = 130


def _add_set_option(p: argparse.ArgumentParser, example: str) -> None:
    """``--set KEY=VALUE`` (repeatable): override a scene field."""
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help=f"override a scene field, e.g. --set {example} (repeatable)",
    )


def command_line(args: argparse.Namespace) -> str:
    """The command line that ran: ``bouncedisk`` and the words :func:`~.command.main` parsed,
    quoted for a shell (a file's ``history``, a tracked run's command)."""
    return "bouncedisk " + shlex.join(args.argv)


def flush_stdout() -> None:
    """Flush standard output; a failure (``> /dev/full``) is an ``OSError`` naming ``<stdout>``."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        raise
    except OSError as ex:
        raise OSError(ex.errno, ex.strerror or str(ex), "<stdout>") from None
