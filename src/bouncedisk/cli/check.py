"""``bouncedisk check``: the paper's claims, pass or fail."""

from __future__ import annotations

import argparse

from .common import EXIT_FAIL


def _cmd_check(args: argparse.Namespace) -> int:
    from ..studies import reproduction as checks

    if args.output:
        from ..io.output_checks import check_output_path

        check_output_path(args.output, "-o")
    results_dir = checks.check_results_folder(args.results) if args.results is not None else None
    results = checks.run_checks(results_dir)
    text = checks.to_markdown(results)
    if args.output:
        from ..io.atomic import write_text_atomic

        write_text_atomic(args.output, text)
    print(checks.to_text(results))
    return 0 if all(r.passed for r in results) else EXIT_FAIL


def _add_check(sub) -> None:
    """``bouncedisk check [--results DIR]``: the paper's claims."""
    p = sub.add_parser("check", help="verify the paper's claims (exit 0 only if all pass)")
    p.add_argument("--results", help="folder of built results to check (default: simulate)")
    p.add_argument("-o", "--output", help="also write the report as Markdown")
    p.set_defaults(func=_cmd_check)
