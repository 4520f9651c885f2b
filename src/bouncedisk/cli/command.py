"""The ``bouncedisk`` command (docs/formats.md "Package and commands").

Errors a user can cause print one line ``bouncedisk: error: FILE: FIELD: what is wrong`` and
exit with status 2; nothing is written then. An interrupted run (Ctrl-C) leaves no output and
exits 130.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import io
import os
import re
import signal
import sys

from .. import __version__
from ..model.errors import InputError, error_line
from .basins import _add_basins
from .check import _add_check
from .common import EXIT_FAIL, EXIT_INTERRUPT, EXIT_USER, flush_stdout
from .fit import _add_fit
from .info import _add_info
from .runs import _add_runs
from .simulate import _add_simulate
from .stats import _add_stats
from .torque_speed import _add_torque_speed


class OneLineParser(argparse.ArgumentParser):
    """Argument errors as one line ``bouncedisk: error: ...`` and exit status 2 (no usage block).

    Subparsers inherit the class (``add_subparsers`` uses the parent's type).
    """

    def error(self, message: str):
        """Print one line naming the command and the problem, then exit 2."""
        message = " ".join(message.split())
        self.exit(EXIT_USER, error_line(f"{self.prog}: {message} (see {self.prog} --help)") + "\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``bouncedisk`` command and its subcommands."""
    parser = OneLineParser(
        prog="bouncedisk",
        description="Exact event-driven simulation of a rotor bouncing on a vibrating, "
        "twisting stator.",
    )
    parser.add_argument("--version", action="version", version=f"bouncedisk {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    adders = (
        _add_simulate,
        _add_stats,
        _add_info,
        _add_runs,
        _add_check,
        _add_fit,
        _add_torque_speed,
        _add_basins,
    )
    for add in adders:
        add(sub)
    return parser


#: A token that starts like a negative number, a list or a range of them: ``-50``, ``-50,0``,
#: ``-.5:1:3``.
_NEGATIVE = re.compile(r"-\.?\d")


def attach_negative_values(parser: argparse.ArgumentParser, argv: list[str]) -> list[str]:
    """``argv`` with every long option that takes a value and is followed by a negative value, list
    or range (``--speeds -50,0``) written as one token (``--speeds=-50,0``): argparse reads a
    token that starts with ``-`` and is not a plain number as an option, and would refuse it."""
    takes_value = {
        opt
        for sub in _subparsers(parser)
        for action in sub._actions
        if action.option_strings and action.nargs != 0
        for opt in action.option_strings
        if opt.startswith("--")
    }
    out: list[str] = []
    i = 0
    while i < len(argv):
        tok = argv[i]
        if tok in takes_value and i + 1 < len(argv) and _NEGATIVE.match(argv[i + 1]):
            out.append(f"{tok}={argv[i + 1]}")
            i += 2
            continue
        out.append(tok)
        i += 1
    return out


def _subparsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    """``parser`` and its subcommands' parsers."""
    subs = [
        choice
        for action in parser._actions
        if isinstance(action, argparse._SubParsersAction)
        for choice in action.choices.values()
    ]
    return [parser, *subs]


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def _stop_once(signum, frame):
    """The console script's first SIGINT or SIGTERM stops the command (``KeyboardInterrupt``);
    a second one while it stops (an impatient Ctrl-C, or ``timeout``, which signals the command
    and then its process group) is ignored: the stop's one line is never followed by a
    traceback."""
    _ignore_stop_signals()
    raise KeyboardInterrupt


def _install_signal_handlers(console: bool) -> None:
    """Ctrl-C (SIGINT) and SIGTERM stop a run cleanly: temporaries removed, no output written;
    in the console script, whose process ends with the command, only the first of them.

    SIGINT is set explicitly because a process started in the background by a non-interactive
    shell inherits it ignored, and Python then installs no handler of its own.
    """
    try:
        signal.signal(signal.SIGINT, _stop_once if console else signal.default_int_handler)
        signal.signal(signal.SIGTERM, _stop_once if console else _interrupt)
    except ValueError:  # not the main thread (embedded use): leave the host's handlers alone
        pass


def _ignore_stop_signals() -> None:
    """Ignore SIGINT and SIGTERM from now on (in the main thread; elsewhere the host's stay)."""
    with contextlib.suppress(ValueError):
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, signal.SIG_IGN)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script."""
    console = argv is None  # the console script: this process ends with the command
    _install_signal_handlers(console)
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    args, extra = parser.parse_known_args(attach_negative_values(parser, argv))
    args.argv = argv
    if extra and args.command == "runs":  # run ids after options: `runs diff A --json B`
        args.words += [x for x in extra if not x.startswith("-")]
        extra = [x for x in extra if x.startswith("-")]
    if extra:
        hint = ""
        if args.command == "fit" and any(x.lower().endswith(".csv") for x in extra):
            hint = (
                "; the run-ups go before the options, and each load curve after a --load of its own"
            )
        sub = next(
            (q for q in _subparsers(parser) if q.prog == f"{parser.prog} {args.command}"), parser
        )
        sub.error(f"unrecognized arguments: {' '.join(extra)}{hint}")  # its --help named
    from ..io import atomic

    stdout, sys.stdout = sys.stdout, _NamedStdout(sys.stdout)
    try:
        with atomic.recording_outputs():
            code, kept = _run_command(args)
    finally:
        sys.stdout = stdout
    if kept:  # interrupted or failed while recording the run: the outputs stay
        names = ", ".join(str(p) for p in kept)
        print(f"bouncedisk: the outputs were written and kept: {names}", file=sys.stderr)
    if console and code == 0:  # done: a signal while the interpreter shuts down (about half
        _ignore_stop_signals()  # a second) cannot turn a finished command's status into 130
    return code


def _discard_stdout() -> None:
    """Point standard output at /dev/null: what could not be written raises no second error
    when Python flushes it at exit."""
    if sys.__stdout__ is None or getattr(sys.stdout, "_stream", sys.stdout) is not sys.__stdout__:
        return  # closed (nothing to point), or a caller's stream (tests, embedding): theirs
    with contextlib.suppress(OSError, ValueError, io.UnsupportedOperation):
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.__stdout__.fileno())


class _NamedStdout:
    """Standard output whose write errors name it: ``OSError`` with filename ``<stdout>``."""

    def __init__(self, stream):
        self._stream = stream

    def __getattr__(self, name: str):
        return getattr(self._stream, name)

    def _call(self, name: str, *a):
        if self._stream is None:  # the shell closed it (`>&-`): Python left sys.stdout None
            raise OSError(errno.EBADF, "standard output is closed", "<stdout>")
        try:
            return getattr(self._stream, name)(*a)
        except BrokenPipeError:
            raise
        except OSError as ex:
            raise OSError(ex.errno, ex.strerror or str(ex), "<stdout>") from None

    def write(self, text: str) -> int:
        return self._call("write", text)

    def flush(self) -> None:
        if self._stream is not None:  # closed: nothing was written (a write raises)
            self._call("flush")


def _run_command(args: argparse.Namespace) -> tuple[int, list]:
    """Run a subcommand; on any failure remove the outputs it wrote (``atomic``).

    Standard output is flushed before the command counts as done, so that a full disk or a
    closed pipe there is an error too. Returns the exit status and the outputs that were
    declared final (by tracking) before a failure, to be named to the user.
    """
    from ..io import atomic

    try:
        code = args.func(args)
        flush_stdout()
        return code, []
    except BaseException as ex:
        if not isinstance(ex, BrokenPipeError | SystemExit):  # a reader that stopped early: done
            atomic.remove_outputs()
        code = _report(ex)
        kept = getattr(ex, "kept_outputs", [])
        return code, kept


def _report(exc: BaseException) -> int:
    """Print one line for a failed command; return its exit status (or re-raise)."""
    try:
        raise exc
    except InputError as ex:
        print(error_line(ex.line()), file=sys.stderr)
        return EXIT_USER
    except KeyboardInterrupt as ex:
        if getattr(ex, "kept_outputs", None):
            print("bouncedisk: interrupted while recording the run", file=sys.stderr)
        else:
            print("bouncedisk: interrupted; no output written", file=sys.stderr)
        return EXIT_INTERRUPT
    except BrokenPipeError:
        _discard_stdout()
        return 0
    except MemoryError:
        print(
            error_line(
                "out of memory: the request needs more memory than this machine has; ask for "
                "less (fewer impacts, a larger outputs.trajectory.dt)"
            ),
            file=sys.stderr,
        )
        return EXIT_USER
    except OSError as ex:  # a file the user named cannot be read or written
        if ex.filename == "<stdout>":
            _discard_stdout()
        where = f"{ex.filename}: " if ex.filename else ""
        reason = ex.strerror or " ".join(str(ex).split()) or type(ex).__name__
        print(error_line(f"{where}{reason}"), file=sys.stderr)
        return EXIT_USER
    except Exception as ex:  # engine failures: one line, no traceback
        from ..engine import EngineError

        if isinstance(ex, EngineError):
            print(error_line(str(ex)), file=sys.stderr)
            return EXIT_FAIL
        raise
