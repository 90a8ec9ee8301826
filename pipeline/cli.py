"""The ``pipeline`` command: parses arguments and calls the library, nothing else.

Each subcommand lives in its own module exposing ``add_parser(subparsers)`` and ``run(args)``.
Exit codes: 0 success; 1 ``pipeline check`` found a mechanism; 2 a project error (one line
``error: ...`` naming file, card or key and the fix) or a bad argument; 130 Ctrl-C (one line naming
the stage that was running). Anything else is a bug and shows its traceback.
"""
from __future__ import annotations

import argparse
import importlib
import os
import sys
import warnings

from pipeline.stage import Interrupted, running
from structures.common.errors import PipelineError
from structures.common.process import settle_process

#: Subcommand modules, in the order ``pipeline --help`` lists them.
COMMANDS = ("pipeline.cmd_run", "pipeline.cmd_select", "pipeline.cmd_modes",
            "pipeline.cmd_correlate", "pipeline.cmd_flutter", "pipeline.cmd_tune",
            "pipeline.cmd_check", "pipeline.cmd_diagnose")


def positive_int(text: str) -> int:
    """argparse type of counts such as ``--nmodes``: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer; give a count >= 1") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} must be >= 1 (a count of modes); leave the "
                                         "option out for the default")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pipeline",
        description="GVT-validated FE model tuning, doublet-lattice aerodynamics and p-k flutter.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(name).add_parser(sub)
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings on the command line: one line with the message, no source excerpt."""
    print(f"warning: {message}", file=sys.stderr if file is None else file)


def main(argv=None) -> int:
    parser = build_parser()
    program = argv is None
    if program:                      # not when called in-process with ``argv`` (tests)
        settle_process()
    args = parser.parse_args(argv)
    if args.command is None:
        args = parser.parse_args(["run", *(argv or [])])
    shown = warnings.showwarning
    warnings.showwarning = _show_warning
    try:
        with running(args.command):
            return int(args.func(args) or 0)
    except PipelineError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except Interrupted as exc:
        print(f"interrupted in {exc.stage}; run the same command again to resume", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # The reader of stdout went away (``pipeline modes deck.bdf | head``): stop quietly,
        # with stdout pointed at devnull so that the interpreter's final flush cannot raise
        # again (Python's signal module documentation, "Note on SIGPIPE").
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    finally:
        warnings.showwarning = shown
        if program:
            settle_process()


if __name__ == "__main__":
    sys.exit(main())
