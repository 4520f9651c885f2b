"""What every subcommand shares: exit statuses, ``--set``, flushing stdout."""

from __future__ import annotations

import argparse
import contextlib
import json
import shlex
import sys
from collections.abc import Iterator

from ..model.errors import InputError

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


def named_override(ex: InputError, overrides: list[str] | None) -> InputError:
    """``ex`` naming the ``--set`` option that gave its field, as a scene's own errors do
    (``stop.max_events (from --set stop.max_events)``); ``ex`` itself when the file gave it."""
    from ..model.scene import override_of

    key = override_of(ex.field, overrides or [])
    if key is None or "(from --set" in ex.field:
        return ex
    return InputError(ex.source, f"{ex.field} (from --set {key})", ex.message)


@contextlib.contextmanager
def naming_overrides(overrides: list[str] | None) -> Iterator[None]:
    """Re-raise an :class:`InputError` of the block naming the ``--set`` option that gave its
    field (:func:`named_override`): a check or a run after the scene was read."""
    try:
        yield
    except InputError as ex:
        raise named_override(ex, overrides) from None


def flush_stdout() -> None:
    """Flush standard output; a failure (``> /dev/full``) is an ``OSError`` naming ``<stdout>``."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        raise
    except OSError as ex:
        raise OSError(ex.errno, ex.strerror or str(ex), "<stdout>") from None


def print_result(args: argparse.Namespace, summary: dict, table: str, saved: str) -> None:
    """A command's result on standard output: ``summary`` as one JSON object (``--json``, no
    NaN or infinity), else ``table`` and, when ``-o`` wrote a file, what it holds (``saved``)."""
    if args.json:
        print(json.dumps(summary, allow_nan=False))
    else:
        print(table)
        if args.output:
            print(f"{args.output}: {saved}")
